"""A plan's ``[puzzle.NAME]``: the contract's keys, one line per mistake, the scene the simulator breaks."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bt_arrange import plans
from bt_arrange.errors import PlanError
from bt_arrange.puzzle import PuzzleSpec
from bt_arrange.trees import Arrangement
from bt_arrange_sim.puzzles import PieceStart

PUZZLE = """
[colours.ochre]
rgb = [0.8, 0.55, 0.2]
[puzzle.slab]
size_mm = [160, 120, 20]
pieces = 6
gap_mm = 2
colour = "ochre"
x_mm = 500
y_mm = 0
yaw_deg = 10
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "plan.toml"
    path.write_text(text)
    return path


def test_a_puzzle_has_no_seed_and_no_outline_only_its_whole(tmp_path: Path) -> None:
    plan = plans.load(write(tmp_path, PUZZLE))
    (spec,) = plan.puzzles
    assert spec == PuzzleSpec("slab", (0.16, 0.12, 0.02), 6, 0.002, "ochre", 0.5, 0.0, math.radians(10))
    assert spec.piece_names == [f"slab {k}" for k in range(1, 7)]
    assert plan.targets == []
    root = plan.create_root()
    assert isinstance(root, Arrangement) and root.puzzles == [spec] and root.targets == []
    assert [c.name for c in root.children] == ["then the next (slab)", "park the arm"]


def test_a_puzzle_beside_ordinary_targets(tmp_path: Path) -> None:
    plan = plans.load(write(tmp_path, PUZZLE + '[[targets]]\ncolour = "red"\nx_mm = 400\ny_mm = 250\n'))
    root = plan.create_root()
    assert [t.obj for t in root.targets] == ["red"]
    assert [c.name for c in root.children][-2:] == ["then the next (slab)", "park the arm"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("pieces = 6", "pieces = 1"), r"\[puzzle\.slab\]: pieces = 1: a puzzle has 2 to 16 pieces$"),
        (("pieces = 6", "pieces = 17"), r"pieces = 17: a puzzle has 2 to 16 pieces$"),
        (("pieces = 6", "pieces = 6.5"), r"pieces = 6\.5: a puzzle has 2 to 16 pieces$"),
        (("gap_mm = 2", "gap_mm = 0.2"), r"gap_mm = 0\.2: two pieces need at least 0\.5 mm$"),
        (("gap_mm = 2", "gap = 2"), r"unknown key 'gap' \(did you mean 'gap_mm'\?\)"),
        (("gap_mm = 2", "seed = 3"), r"unknown key 'seed'"),
        (('colour = "ochre"', 'colour = "ocre"'), r"unknown colour 'ocre' \(did you mean 'ochre'\?\)"),
        (("x_mm = 500", "x_mm = 0.5"), r"look like metres"),
        (("size_mm = [160, 120, 20]", "size_mm = [0.16, 0.12, 0.02]"), r"looks like metres"),
        (("size_mm = [160, 120, 20]", "size_mm = [160, 120]"), r"size_mm = \[160, 120\] is not three numbers"),
        (("y_mm = 0\n", ""), r"\[puzzle\.slab\]: missing y_mm$"),
    ],
)
def test_every_mistake_is_one_line_naming_the_file_and_the_entry(
    tmp_path: Path, change: tuple[str, str], message: str
) -> None:
    path = write(tmp_path, PUZZLE.replace(*change))
    with pytest.raises(PlanError, match=message) as caught:
        plans.load(path)
    assert "\n" not in str(caught.value)
    assert str(caught.value).startswith(f"{path}: [puzzle.slab]: ")


def test_a_piece_may_not_take_a_target_s_name(tmp_path: Path) -> None:
    path = write(tmp_path, PUZZLE + '[[targets]]\ncolour = "red"\nname = "slab 2"\nx_mm = 400\ny_mm = 250\n')
    with pytest.raises(PlanError, match=r"\[puzzle\.slab\]: its piece 'slab 2' has the name of another"):
        plans.load(path)


def test_the_simulator_breaks_the_slab_from_the_run_s_seed_and_scatters_its_pieces(tmp_path: Path) -> None:
    plan = plans.load(write(tmp_path, PUZZLE))
    scene = plan.create_scene(4)
    assert [s.name for s in scene] == [f"slab fragment {k}" for k in range(1, 7)]
    assert all(isinstance(s, PieceStart) and s.puzzle == "slab" for s in scene)
    # Off the whole's place: every piece starts farther from its centre than the slab's half diagonal.
    assert min(math.hypot(s.x_m - 0.5, s.y_m) for s in scene) > 0.1
    # Its homes fill the whole: their centroids lie on the slab, turned 10 degrees about (500, 0) mm.
    c, s_ = math.cos(math.radians(-10)), math.sin(math.radians(-10))
    for start in scene:
        dx, dy = start.home[0] - 0.5, start.home[1]
        assert abs(c * dx - s_ * dy) < 0.08 and abs(s_ * dx + c * dy) < 0.06
    assert [s.home for s in plan.create_scene(4)] == [s.home for s in scene]
    assert [s.home for s in plan.create_scene(5)] != [s.home for s in scene]


def test_the_tree_never_receives_the_break(tmp_path: Path) -> None:
    """Honesty (item 5): the tree holds the puzzle's whole only; outlines and homes stay in the scene."""
    plan = plans.load(write(tmp_path, PUZZLE))
    root = plan.create_root()
    for node in root.iterate():
        for value in vars(node).values():
            assert not isinstance(value, PieceStart)
    assert not hasattr(root.puzzles[0], "seed")


def test_the_xml_twin_is_the_plan_s_tree_and_scene() -> None:
    """trees/puzzle.xml (``bt-arrange show puzzle --format xml``) keeps the puzzle's ports and its scene."""
    from bt_arrange import treefile, xmltree

    trees = Path(__file__).resolve().parents[1] / "trees"
    plan, xml = treefile.load(trees / "puzzle.toml"), treefile.load(trees / "puzzle.xml")
    plan_root, xml_root = treefile.build_root(plan), treefile.build_root(xml)
    assert xml_root.puzzles == plan_root.puzzles
    assert xmltree.to_xml(xml_root, tree_id="puzzle") == xmltree.to_xml(plan_root, tree_id="puzzle")
    assert treefile.scene(xml, 2) == treefile.scene(plan, 2)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            "threshold_mm = 1.5\n",
            r"\[puzzle\.slab\]: gap_mm = 2 is under twice the threshold \(3 mm at threshold_mm = 1\.5\).*"
            r"make gap_mm at least 3 or threshold_mm at most 1$",
        ),
        (
            '[[targets]]\ncolour = "red"\nx_mm = 520\ny_mm = 40\n',
            r"target 1 \(red\) lies where \[puzzle\.slab\] is put back together: move the target or the slab$",
        ),
        (
            '[[targets]]\ncolour = "ochre"\nx_mm = 400\ny_mm = 250\n',
            r"target 1 \(ochre\) is ochre, the colour of \[puzzle\.slab\]'s pieces",
        ),
        (
            '[puzzle.other]\nsize_mm = [100, 80, 20]\npieces = 4\ngap_mm = 2\ncolour = "blue"\nx_mm = 560\ny_mm = 30\n',
            r"\[puzzle\.slab\] and \[puzzle\.other\]: the two slabs overlap where they are put back together",
        ),
    ],
    ids=["gap under twice the threshold", "a target under the slab", "a target of its colour", "slabs overlap"],
)
def test_a_puzzle_the_run_would_fail_on_is_refused_before_anything_moves(tmp_path: Path, extra, message) -> None:
    text = (extra + PUZZLE) if extra.startswith("threshold") else PUZZLE + extra
    with pytest.raises(PlanError, match=message) as caught:
        plans.load(write(tmp_path, text)).create_root()
    assert "fragment" not in str(caught.value), "the message names only what the plan names"
