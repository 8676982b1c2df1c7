"""A painted slab: the picture's contract, and its colours telling the whole's turns apart."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from bt_arrange import plans
from bt_arrange.behaviours.puzzle import SurveyedPiece
from bt_arrange.errors import PlanError
from bt_arrange.plan.puzzle_targets import _sample_points, picture_turn
from bt_arrange.puzzle import Placement, PuzzleSpec
from bt_arrange.puzzle.picture import builtin_picture, check_picture, picture_rgb_at, read_picture
from bt_arrange.shapes.fracture import fracture

PLAN = """
[puzzle.slab]
size_mm = [160, 120, 20]
pieces = 6
picture = "{picture}"
x_mm = 500
y_mm = 0
"""


def test_the_built_in_picture_is_saturated_everywhere_and_drawn_the_same_each_time() -> None:
    first = builtin_picture("fresco")
    check_picture(first)
    assert builtin_picture("fresco") == first
    assert read_picture(first).shape == (480, 640, 3)


def test_a_painted_puzzle_s_pieces_take_the_painted_colour(tmp_path: Path) -> None:
    path = tmp_path / "plan.toml"
    path.write_text(PLAN.format(picture="fresco"))
    plan = plans.load(path)
    assert plan.puzzles[0].picture == "fresco" and plan.puzzles[0].colour == "painted"
    assert "painted" in plan.colours.names
    assert plan.puzzles[0].symmetry_turns_rad == (0.0,)


@pytest.mark.parametrize(
    ("picture", "extra", "message"),
    [
        ("missing.png", "", r"picture .*missing\.png: cannot be read"),
        ("grey.png", "", r"greyish or dark"),
        ("notimage.png", "", r"not an image OpenCV reads"),
        ("fresco", 'colour = "red"\n', r"give colour or picture, not both"),
        ("fresco", '[[targets]]\ncolour = "red"\nx_mm = 400\ny_mm = 250\n', r"holds no other target or puzzle"),
    ],
)
def test_a_bad_picture_is_one_line(tmp_path: Path, picture: str, extra: str, message: str) -> None:
    cv2.imwrite(str(tmp_path / "grey.png"), np.full((40, 40, 3), 120, np.uint8))
    (tmp_path / "notimage.png").write_text("no")
    path = tmp_path / "plan.toml"
    text = PLAN.format(picture=picture)
    path.write_text(text.replace("x_mm = 500", extra + "x_mm = 500") if extra.startswith("colour") else text + extra)
    with pytest.raises(PlanError, match=message) as caught:
        plans.load(path)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("turned", [False, True])
def test_the_picture_chooses_between_the_whole_s_two_turns(turned: bool) -> None:
    spec = PuzzleSpec("slab", (0.16, 0.12, 0.02), 6, 0.002, "painted", 0.5, 0.0, 0.0, picture="fresco")
    picture = read_picture(builtin_picture("fresco"))
    turn = math.pi if turned else 0.0
    c, s = math.cos(turn), math.sin(turn)
    surveyed, placements = [], {}
    for piece in fracture(spec.size_m, spec.pieces, spec.gap_m, 2):
        outline = piece.slab_outline_m
        counts = [12] * len(outline)
        # What the camera saw on the piece: the picture where the piece truly was, turned by ``turn``.
        truly = _sample_points(outline, counts) @ np.array([[c, s], [-s, c]])
        colours = picture_rgb_at(picture, truly, spec.size_m) * 0.8  # the light dims, it does not change hues
        edges = tuple(np.split(colours, np.cumsum(counts)[:-1]))
        name = f"slab {piece.index}"
        surveyed.append(SurveyedPiece(name, outline, (0.0, 0.0), edges))
        placements[name] = Placement(name, 0.0, (0.0, 0.0), (0.0, 0.0))
    assert picture_turn(spec, surveyed, placements) == pytest.approx(turn)


def test_a_painted_face_s_share_of_pixels_is_read_by_the_painted_range() -> None:
    """Beyond a painted face's edge: a saturated pixel is a face's, the table's grey is not; no pixels, no shares."""
    from bt_arrange.perception.outline_face import Face, face_share
    from bt_arrange.puzzle.spec import painted_range

    colour = painted_range()
    assert colour.many_hues
    face = Face(np.zeros((3, 2), np.int32), 1.0, np.zeros((3, 2)), 1.0, np.zeros(2), np.ones(2), False, colour)
    shares = face_share(face, np.array([[200, 30, 30], [30, 60, 200], [140, 140, 136]], dtype=np.uint8))
    assert shares.tolist() == [1.0, 1.0, 0.0]
    assert face_share(face, np.empty((0, 3), dtype=np.uint8)).shape == (0,)  # cvtColor refuses an empty image
