"""The deprecated aliases of the names that said "cube" for any part: each works, warns once, names its successor."""

from __future__ import annotations

import importlib
import types
import warnings

import pytest

from bt_arrange import deprecation
from bt_arrange.deprecation import renamed_attributes, renamed_keywords

#: Every alias kept for one release: (module, old name, new name). CHANGELOG.md lists the same.
ALIASES = [
    ("bt_arrange.perception", "CubeDetector", "PartDetector"),
    ("bt_arrange.perception.detection", "CubeDetector", "PartDetector"),
    ("bt_arrange.perception.pose", "cube_centre_in_world", "part_centre_in_world"),
    ("bt_arrange.perception.synthetic", "SIM_CUBE_COLOURS_RGB", "SIM_PART_COLOURS_RGB"),
    ("bt_arrange.behaviours.stages", "MOVE_ABOVE_CUBE", "MOVE_ABOVE_PART"),
    ("bt_arrange.behaviours.stages", "DESCEND_TO_CUBE", "DESCEND_TO_PART"),
    ("bt_arrange.behaviours.stages", "CLOSE_ON_CUBE", "CLOSE_ON_PART"),
    ("bt_arrange.behaviours.stages", "CLOSE_SLOWLY_ON_CUBE", "CLOSE_SLOWLY_ON_PART"),
    ("bt_arrange.behaviours.stages", "OPEN_SQUARED_CUBE", "OPEN_SQUARED_PART"),
    ("bt_arrange.behaviours.stages", "RECENTRE_ON_CUBE", "RECENTRE_ON_PART"),
    ("bt_arrange.behaviours.stages", "CLOSE_ON_TURNED_CUBE", "CLOSE_ON_TURNED_PART"),
    ("bt_arrange.behaviours.stages", "CLOSE_ON_SQUARED_CUBE", "CLOSE_ON_SQUARED_PART"),
    ("bt_arrange.behaviours.stages", "LIFT_CUBE", "LIFT_PART"),
    ("bt_arrange.behaviours.stages", "LOWER_CUBE", "LOWER_PART"),
    ("bt_arrange.behaviours.stages", "RELEASE_CUBE", "RELEASE_PART"),
    ("bt_arrange.behaviours.stages", "MOVE_BEHIND_CUBE", "MOVE_BEHIND_PART"),
]


@pytest.fixture(autouse=True)
def fresh_process(monkeypatch):
    """Each test sees the aliases as a new process does: none has warned yet."""
    monkeypatch.setattr(deprecation, "_warned", set())


@pytest.mark.parametrize(("module_name", "old", "new"), ALIASES, ids=[f"{m}.{o}" for m, o, _ in ALIASES])
def test_the_alias_gives_the_new_name_and_warns_once_naming_it(module_name, old, new):
    module = importlib.import_module(module_name)
    with pytest.warns(DeprecationWarning, match=rf"{module_name}\.{old} is deprecated.*use {module_name}\.{new}$"):
        value = getattr(module, old)
    assert value is getattr(module, new)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert getattr(module, old) is value
        assert getattr(module, new) is value


def test_from_import_of_an_old_name_warns_at_the_importing_line():
    with pytest.warns(DeprecationWarning) as caught:
        from bt_arrange.perception import CubeDetector  # noqa: F401
    assert caught[0].filename == __file__


@pytest.mark.parametrize("module_name", sorted({m for m, _, _ in ALIASES}))
def test_new_names_and_other_attributes_do_not_warn(module_name):
    module = importlib.import_module(module_name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for new in [n for m, _, n in ALIASES if m == module_name]:
            getattr(module, new)
        with pytest.raises(AttributeError, match="has no attribute 'NoSuchName'"):
            module.NoSuchName  # noqa: B018


def test_the_old_stage_names_hold_the_new_words():
    from bt_arrange.behaviours import stages

    with pytest.warns(DeprecationWarning):
        assert stages.CLOSE_ON_CUBE == stages.CLOSE_ON_PART == "close on the part"


def test_renamed_attributes_follows_the_new_name_at_each_access():
    module = types.ModuleType("fake_module")
    module.__getattr__ = renamed_attributes("fake_module", {"old": "new"})  # type: ignore[method-assign]
    import sys

    sys.modules["fake_module"] = module
    try:
        module.new = 1  # type: ignore[attr-defined]
        with pytest.warns(DeprecationWarning, match="fake_module.old is deprecated"):
            assert module.old == 1  # type: ignore[attr-defined]
        module.new = 2  # type: ignore[attr-defined]
        assert module.old == 2  # type: ignore[attr-defined]
    finally:
        del sys.modules["fake_module"]


def test_a_name_cannot_be_both_old_and_new():
    with pytest.raises(ValueError, match="both old and new"):
        renamed_attributes("m", {"a": "b", "b": "c"})


@renamed_keywords(cubes="parts")
def count(parts, *, scale=1):
    return len(parts) * scale


def test_a_renamed_keyword_works_and_warns_once_naming_the_new_one():
    with pytest.warns(DeprecationWarning, match=r"count\(cubes=\.\.\.\) is deprecated.*use .*count\(parts=\.\.\.\)$"):
        assert count(cubes=[1, 2]) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert count(cubes=[1, 2, 3], scale=2) == 6
        assert count(parts=[1]) == 1
        assert count([1, 2]) == 2


def test_the_old_and_the_new_keyword_together_are_refused():
    with pytest.raises(TypeError, match="both cubes= .* and parts="):
        count(cubes=[1], parts=[2])


def test_render_frame_takes_its_old_keyword():
    from bt_arrange.perception.synthetic import SyntheticCube, render_frame, sim_intrinsics

    small = sim_intrinsics(192, 108)
    with pytest.warns(DeprecationWarning, match=r"render_frame\(cubes=\.\.\.\).*render_frame\(parts=\.\.\.\)"):
        frame = render_frame(cubes=[SyntheticCube("red", 0.5, 0.0, 0.0)], intrinsics=small, supersample=1)
    assert frame.rgb.shape[:2] == (small.height_px, small.width_px)


def test_the_changelog_lists_every_alias():
    from pathlib import Path

    changelog = (Path(__file__).parent.parent / "CHANGELOG.md").read_text()
    deprecated = changelog.split("words for any part)", 1)[1].split("\n### ", 1)[0]
    # Each old name is followed, on its line, by "-> `new`".
    after = {old: deprecated.split(f"{old}`", 1)[1][:40] if f"{old}`" in deprecated else "" for _, old, _ in ALIASES}
    assert [f"{old} -> {new}" for _, old, new in ALIASES if f"-> `{new}`" not in after[old]] == []
