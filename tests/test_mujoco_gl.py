"""MuJoCo without its OpenGL (no ``libosmesa6``): one line saying what to install, exit 2, from every command.

The missing library is simulated, not uninstalled: ``import mujoco`` is made to fail as it does
without libOSMesa (deep inside PyOpenGL, an ``AttributeError``, not an ``ImportError``).
"""

from __future__ import annotations

import importlib.abc
import sys
from pathlib import Path

import pytest

from bt_arrange import cli
from bt_arrange.errors import BackendError

#: What ``import mujoco`` raises under ``MUJOCO_GL=osmesa`` when libOSMesa is not installed.
NO_OSMESA = "'NoneType' object has no attribute 'glGetError'"


class _NoOSMesa(importlib.abc.MetaPathFinder):
    """Makes ``import mujoco`` fail as it does without libOSMesa."""

    def find_spec(self, name: str, path: object = None, target: object = None) -> None:
        if name == "mujoco" or name.startswith(("mujoco.", "OpenGL")):
            raise AttributeError(NO_OSMESA)


@pytest.fixture
def no_osmesa(monkeypatch: pytest.MonkeyPatch) -> None:
    """From now on, in this process, mujoco's OpenGL does not load (the modules come back afterwards)."""
    for name in list(sys.modules):
        if name == "mujoco" or name.startswith(("mujoco.", "OpenGL")):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    monkeypatch.setattr(sys, "meta_path", [_NoOSMesa(), *sys.meta_path])


def _assert_one_line_naming_what_to_install(err: str) -> None:
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("bt-arrange: error: the MuJoCo backend cannot render"), err
    assert "apt-get install libosmesa6" in err and "MUJOCO_GL=egl" in err, err
    assert NO_OSMESA in err, "the library's own words, for whoever debugs it"


def test_the_check_names_what_to_install(no_osmesa: None) -> None:
    from bt_arrange_sim.mujoco.gl import check_gl

    with pytest.raises(BackendError, match=r"libosmesa6.*MUJOCO_GL=egl"):
        check_gl()


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "four_cubes", "--backend", "mujoco"],
        ["experiment", "--backend", "mujoco", "--rows", "system", "--trials", "1"],
        ["info", "--backend", "mujoco"],
    ],
    ids=["run", "experiment", "info"],
)
def test_every_command_says_in_one_line_what_to_install_and_exits_2(
    no_osmesa: None, argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    from bt_arrange_sim.experiment import campaign

    def moved(*args: object, **kwargs: object) -> None:
        raise AssertionError("a trial ran before the renderer was checked")

    monkeypatch.setattr(campaign, "run_trial", moved)
    if argv[0] == "experiment":
        argv = [*argv, "--out", str(tmp_path / "out")]
    code = cli.main(argv)
    captured = capsys.readouterr()
    assert code == 2
    _assert_one_line_naming_what_to_install(captured.err)
    if argv[0] == "experiment":
        assert not (tmp_path / "out" / "specification.json").exists(), "refused before the campaign began"
