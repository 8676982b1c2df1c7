"""SurveyPieces, SolvePuzzle and ArrangeSolved with a fake camera and a hand-filled blackboard.

The survey and the solve see the pieces through a synthetic camera only: the context has no world,
so these tests are also the honesty check of item 5 (the solve's only input is camera frames).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours.puzzle import SolvePuzzle, SurveyPieces
from bt_arrange.objects import ObjectType
from bt_arrange.perception.synthetic import SyntheticPrism
from bt_arrange.puzzle import PuzzleSpec
from bt_arrange.shapes.fracture import fracture
from bt_arrange.testing import fake_camera, make_context, tick_until_done
from bt_arrange.trees import Arrangement, Target
from bt_arrange.trees.puzzle import ArrangeSolved

SPEC = PuzzleSpec("slab", (0.16, 0.12, 0.02), 6, 0.002, "red", 0.5, 0.0, 0.0)
#: Where the scattered pieces lie in the fake camera's view (clear of the whole's place at x 0.5).
SPOTS = [(0.36, -0.17), (0.50, -0.17), (0.64, -0.17), (0.36, 0.17), (0.50, 0.17), (0.64, 0.17)]


def scattered(seed: int) -> list[tuple[SyntheticPrism, tuple[float, float, float]]]:
    """The slab broken from ``seed``: each piece in the fake camera's view, turned at random, and its home."""
    rng = np.random.default_rng(seed)
    out = []
    for piece, (x, y) in zip(fracture(SPEC.size_m, SPEC.pieces, SPEC.gap_m, seed), SPOTS, strict=True):
        prism = SyntheticPrism("red", x, y, float(rng.uniform(-math.pi, math.pi)), piece.prism)
        out.append((prism, (piece.x_m + SPEC.x_m, piece.y_m + SPEC.y_m, piece.yaw_rad)))
    return out


def solve_in_fake_camera(clock, seed: int):
    context = make_context(clock=clock)
    camera = fake_camera(context)
    pieces = scattered(seed)
    camera.parts.extend(prism for prism, _ in pieces)
    survey = tick_until_done(set_up(SurveyPieces("survey slab", SPEC), context), context)
    assert survey.status == Status.SUCCESS, survey.feedback
    solve = tick_until_done(set_up(SolvePuzzle("solve slab", SPEC), context), context)
    return survey, solve, pieces


@pytest.mark.parametrize(
    "seed",
    [
        0,
        # Seed 1's measured piece 6 has two sides a hair from parallel: turned to one's closing axis, the
        # other came first (fracture.in_grasp_frame settles the turn on it now).
        1,
        # Known miss (docs/puzzle.md), not strict: it may pass once fixed. Seed 2: two sides of 11 and 12 mm
        # (11 and 12 px in the fake camera's frame, 8 px of contour after the 7 px opening) are taken for
        # the opening's chamfers.
        pytest.param(2, marks=pytest.mark.xfail(reason="known miss of the survey: two short sides lost")),
    ],
)
def test_survey_and_solve_from_the_camera_alone_find_every_piece_s_home(clock, seed: int) -> None:
    survey, solve, pieces = solve_in_fake_camera(clock, seed)
    assert solve.status == Status.SUCCESS, solve.feedback
    surveyed = read("/slab/pieces")
    assert [p.name for p in surveyed] == SPEC.piece_names
    solved = read("/slab/solved")
    assert [t.obj for t in solved] == SPEC.piece_names
    assert read("/slab/solve_s") > 0
    # Each named piece is the scattered one nearest where the survey saw it; its target is its home,
    # for one of the whole's two symmetric turns (the pieces alone cannot tell them apart).
    homes = {}
    for piece in surveyed:
        prism, home = min(
            pieces, key=lambda item: math.hypot(item[0].x_m - piece.centre_m[0], item[0].y_m - piece.centre_m[1])
        )
        homes[piece.name] = home
    errors = []
    for turn in SPEC.symmetry_turns_rad:
        c, s = math.cos(turn), math.sin(turn)
        worst = 0.0
        for target in solved:
            hx, hy, _ = homes[target.obj]
            dx, dy = hx - SPEC.x_m, hy - SPEC.y_m
            x, y = SPEC.x_m + c * dx - s * dy, SPEC.y_m + s * dx + c * dy
            worst = max(worst, math.hypot(target.x_m - x, target.y_m - y))
        errors.append(worst)
    assert min(errors) * 1000 < 0.3, errors


def test_a_hidden_piece_is_a_failure_naming_the_count(clock) -> None:
    context = make_context(clock=clock)
    camera = fake_camera(context)
    camera.parts.extend(prism for prism, _ in scattered(0)[:5])
    run = tick_until_done(set_up(SurveyPieces("survey slab", SPEC), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback == "slab: the camera sees 5 pieces of red, the puzzle has 6"


def test_arrange_solved_builds_a_fresco_s_steps_from_the_solve_and_joins_the_root_s_plan(clock) -> None:
    pieces = fracture(SPEC.size_m, SPEC.pieces, SPEC.gap_m, 3, (SPEC.x_m, SPEC.y_m, 0.0))
    solved = [
        Target(
            "red",
            p.x_m,
            p.y_m,
            p.yaw_rad,
            name=f"slab {p.index}",
            object_type=ObjectType(f"slab {p.index}", shape=p.prism),
        )
        for p in pieces
    ]
    node = ArrangeSolved("arrange slab", SPEC, {"threshold_mm": 0.8, "yaw_threshold_deg": 0.8})
    root = Arrangement("arrangement", [node], [], 0.8)
    write({"/slab/solved": tuple(solved)})
    context = make_context(clock=clock)
    set_up(root, context)
    next(iter(node.tick()))
    assert [c.name for c in node.children] == [f"then the next (slab {k})" for k in range(1, 7)]
    assert [t.obj for t in root.targets] == [t.obj for t in solved]
    assert all(n._require_context() is context for n in node.iterate() if hasattr(n, "_require_context"))


def test_arrange_solved_fails_saying_why_when_the_solved_places_cannot_be_arranged(clock) -> None:
    kind = ObjectType("slab 1", (0.05, 0.05, 0.02))
    overlapping = (
        Target("red", 0.5, 0.0, name="slab 1", object_type=kind),
        Target("red", 0.51, 0.0, name="slab 2", object_type=kind),
    )
    write({"/slab/solved": overlapping})
    node = ArrangeSolved("arrange slab", SPEC, {})
    set_up(node, make_context(clock=clock))
    for _ in node.tick():
        pass
    assert node.status == Status.FAILURE
    assert node.feedback_message.startswith("slab: the solved places cannot be arranged: ")
    assert "\n" not in node.feedback_message


def test_arrange_solved_without_a_solve_fails_naming_the_key(clock) -> None:
    node = ArrangeSolved("arrange slab", SPEC, {})
    set_up(node, make_context(clock=clock))
    for _ in node.tick():
        pass
    assert node.status == Status.FAILURE and node.feedback_message == "slab: not solved (no /slab/solved)"
