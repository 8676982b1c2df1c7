"""Push among neighbours: only from free sides, and a squaring push from a free side."""

from __future__ import annotations

import pytest
from behaviour_helpers import cube_pose, read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Context, Push
from bt_arrange.behaviours.push import Blocked
from bt_arrange.geometry import PlanarPose
from bt_arrange.testing import fake_arm, fake_gripper, tick_until_done

# -- pushes only from free sides (neighbours as the layout names them) ---------------------


@pytest.mark.parametrize(
    ("offset_xy_mm", "towards", "expected"),
    [
        ((3.0, 0.0), ("+x", "-x", "+y", "-y"), "x"),
        ((3.0, 2.0), ("-x", "+y", "-y"), "y"),  # +x blocked (a neighbour on the -x side): the other axis
        ((3.0, 0.1), ("-x", "+y", "-y"), ("+x", 3.0)),  # only +x would do: blocked
        ((-3.0, 0.0), ("-x", "+y", "-y"), "x"),
        ((0.1, -2.0), ("+y",), ("-y", -2.0)),
    ],
    ids=["all free", "other axis", "blocked", "free direction", "blocked y"],
)
def test_push_chooses_a_free_side_or_says_which_side_is_blocked(offset_xy_mm, towards, expected) -> None:
    choice = Push.choose_side("x", offset_xy_mm, 0.2, towards)
    if isinstance(expected, tuple):
        assert isinstance(choice, Blocked) and (choice.towards, choice.offset_mm) == expected
    else:
        assert choice == expected


def test_a_push_a_neighbour_blocks_fails_saying_so_and_writes_the_direction(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (1.5, 0.0)})
    push = set_up(Push("push red", "red", towards=("-x", "+y", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.FAILURE
    assert "red needs a push of 1.50 mm towards +x, from its -x side, where a neighbour leaves the pads no room" in (
        run.feedback
    )
    assert read("/red/blocked_towards") == "+x"
    assert read("/red/blocked_by") == "a neighbour"
    assert fake_arm(context).commands == [], "never pushes through the neighbour"


def test_a_blocked_push_names_the_neighbour_the_plan_says_stands_there(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (1.5, 0.0)})
    push = set_up(Push("push red", "red", towards=("-x", "+y", "-y"), blockers={"+x": "blue"}), context)
    run = tick_until_done(push, context)
    assert run.status == Status.FAILURE
    assert "towards +x, from its -x side, where blue leaves the pads no room" in run.feedback
    assert read("/red/blocked_by") == "blue"


def test_a_free_push_says_nothing_blocked_it(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (0.0, 2.0)})
    push = set_up(Push("push red", "red", towards=("-x", "+y", "-y"), blockers={"+x": "blue"}), context)
    tick_until_done(push, context)
    assert read("/red/blocked_towards") == "none"
    assert read("/red/blocked_by") == "none"


def test_a_push_among_neighbours_opens_only_to_keep_the_fingers_within_the_face(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (0.0, 2.0)})
    push = set_up(Push("push red", "red", towards=("+y", "-y"), opening_m=0.024), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +2.00 mm along y"
    assert [(c.kind, c.value) for c in fake_gripper(context).commands] == [("open", 0.024)]


@pytest.mark.parametrize(
    ("offset_y_mm", "towards", "pushed"),
    [
        (-4.0, ("-x", "+x", "-y"), "pushed -3.00 mm along y"),  # home after a release again: stops 1 mm short
        (-4.0, ("-x", "+x", "-y", "+y"), "pushed -4.00 mm along y"),  # an overshoot is free to undo
        (-2.0, ("-x", "+x", "-y"), "pushed -2.00 mm along y"),  # short: all the way
    ],
    ids=["long, overshoot blocked", "long, overshoot free", "short"],
)
def test_a_long_push_among_neighbours_stops_short_where_only_a_blocked_push_could_undo_an_overshoot(
    context: Context, offset_y_mm: float, towards: tuple[str, ...], pushed: str
) -> None:
    write(
        {
            "/red/pose": cube_pose(0.5, 0.0),
            "/red/target": PlanarPose(0.0, 0.0, 0.0),
            "/red/offset_xy_mm": (0.0, offset_y_mm),
            "/red/push_axis": "y",
        }
    )
    push = set_up(Push("push red", "red", towards=towards, opening_m=0.024), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == pushed


# -- a squaring push among neighbours ----------------------------


def test_a_squaring_push_among_neighbours_goes_from_a_free_side(context: Context) -> None:
    # Within reach (0.1 mm along x) but turned 3 degrees: the line contact squares it. A neighbour
    # on the -x side blocks a push towards +x, so the squaring push goes towards -x.
    write(
        {
            "/red/pose": cube_pose(0.5, 0.0),
            "/red/target": PlanarPose(0.5, 0.0, 0.0),
            "/red/offset_xy_mm": (0.1, 0.0),
            "/red/yaw_error_deg": 3.0,
        }
    )
    push = set_up(Push("push red", "red", yaw_threshold_deg=1.0, towards=("-x", "+y", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "squared the part with a push of -0.10 mm along x"
    assert fake_arm(context).commands, "the squaring push is made"


def test_a_squaring_push_with_both_sides_of_its_axis_blocked_is_not_made(context: Context) -> None:
    write(
        {
            "/red/pose": cube_pose(0.5, 0.0),
            "/red/target": PlanarPose(0.5, 0.0, 0.0),
            "/red/offset_xy_mm": (0.1, 0.0),
            "/red/yaw_error_deg": 3.0,
        }
    )
    push = set_up(Push("push red", "red", yaw_threshold_deg=1.0, towards=("+y", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert fake_arm(context).commands == [], "never pushes from a side a neighbour blocks"


def test_a_blocked_learned_push_leaves_nothing_to_learn_from(context: Context) -> None:
    # The part is released past its place before the next push: that move is no push's landing.
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (0.1, 2.0)})
    push = set_up(Push("push red", "red", "diagonal", towards=("-x", "+x", "-y"), blockers={"+y": "blue"}), context)
    run = tick_until_done(push, context)
    assert run.status == Status.FAILURE
    assert "where blue leaves the pads no room" in run.feedback
    assert read("/red/last_push") == ("x", None)
