"""The learned and diagonal push strategies (ours; the paper's stays the default)."""

from __future__ import annotations

import numpy as np
import pytest
from behaviour_helpers import CUBE_GRASP_HEIGHT_M, CUBE_PUSH_REACH_M, SETTINGS, cube_pose, read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Context, Push
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import PlanarPose
from bt_arrange.testing import fake_arm, make_context, tick_until_done

# -- the learned push strategy (ours; the paper's stays the default) ----------------------------


def test_learned_push_goes_along_the_larger_offset_first() -> None:
    assert Push.plan_learned((0.5, -3.0), (0.0, 0.0), None, 0.2) == ((0.0, 0.0), "y", -3.0)
    assert Push.plan_learned((2.0, 1.0), (0.0, 0.0), None, 0.2) == ((0.0, 0.0), "x", 2.0)


def test_learned_push_learns_where_the_last_push_landed_and_aims_short_by_it() -> None:
    # The last push along x aimed at the target (aim 0) and the cube stopped 0.6 mm past it
    # (offset -0.6 mm): pushes along x land 0.6 mm beyond their aim.
    bias, axis, distance = Push.plan_learned((-0.6, 0.1), (0.0, 0.0), ("x", 0.0), 0.2)
    assert bias == pytest.approx((0.6, 0.0))
    assert axis == "x"
    assert distance == pytest.approx(-1.2), "aim 0.6 mm short of the target, from 0.6 mm past it"
    # Aimed 0.6 mm short and landed on the target: the bias stays 0.6 mm.
    bias, _, _ = Push.plan_learned((0.0, 0.1), bias, ("x", -0.6), 0.2)
    assert bias == pytest.approx((0.6, 0.0))


def test_learned_push_that_fell_short_of_the_cube_reaches_further_next_time() -> None:
    # Aimed at the target, but the cube did not move from 0.3 mm short: push further.
    bias, axis, distance = Push.plan_learned((0.3, 0.0), (0.0, 0.0), ("x", 0.0), 0.2)
    assert bias == pytest.approx((-0.3, 0.0))
    assert (axis, distance) == ("x", pytest.approx(0.6))


def test_learned_push_keeps_its_bias_on_the_blackboard_between_pushes(context: Context) -> None:
    write({"/red/pose": cube_pose(0.5, 0.0), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (3.0, 1.0)})
    run = tick_until_done(set_up(Push("push red", "red", strategy="learned"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x"
    assert read("/red/last_push") == ("x", -0.0)
    # The camera then sees the cube 0.4 mm past the target along x, 1 mm short along y.
    write({"/red/offset_xy_mm": (-0.4, 1.0)})
    run = tick_until_done(set_up(Push("push red", "red", strategy="learned"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert read("/red/push_bias_mm") == pytest.approx((0.4, 0.0))
    assert run.feedback == "pushed +1.00 mm along y"


def test_an_unknown_push_strategy_is_a_clear_error() -> None:
    with pytest.raises(BtArrangeError, match="push strategy 'magic': choose one of paper, learned"):
        Push("push red", "red", strategy="magic")


def test_a_diagonal_push_moves_the_cube_across_its_axis_by_the_other_offset_within_the_friction_limit() -> None:
    assert Push.across_push_mm((3.0, 1.0), "x", 3.0, 0.2) == pytest.approx(1.0)
    assert Push.across_push_mm((-0.5, 2.0), "y", 2.0, 0.2) == pytest.approx(-0.5)
    # At most 0.6 mm across per mm along: the rest is left to a later push.
    assert Push.across_push_mm((1.0, -2.0), "x", 1.0, 0.2) == pytest.approx(-0.6)
    # Nothing across below the shortest push, nor when there is no push.
    assert Push.across_push_mm((3.0, 0.1), "x", 3.0, 0.2) == 0.0
    assert Push.across_push_mm((0.1, 3.0), "x", 0.1, 0.2) == 0.0


def test_a_diagonal_push_goes_sideways_while_the_pads_touch_and_says_so(clock) -> None:
    context = make_context(clock=clock)
    centre = np.array([0.5, 0.05])
    write({"/red/pose": cube_pose(*centre), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (3.0, 1.0)})
    push = set_up(Push("push red", "red", strategy="diagonal"), context)
    arm, s = fake_arm(context), SETTINGS
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x, +1.00 mm along y"
    assert read("/red/last_push") == ("x", -0.0), "the push along x is learned as the learned strategy's"
    tcp = np.array([arm.tcp_pose_at(c.positions_rad).position_m for c in arm.commands]) - [*centre, 0.0]
    low = tcp[np.abs(tcp[:, 2] - CUBE_GRASP_HEIGHT_M) < 1e-6]
    deepest = low[int(np.argmax(low[:, 0]))]
    assert deepest[0] == pytest.approx(-CUBE_PUSH_REACH_M + 0.003, abs=1e-6)
    assert deepest[1] == pytest.approx(0.001, abs=1e-6), "1 mm along y by the end of the push"
    # Where the pads meet the face (reach from the centre), the line has not gone sideways yet.
    pushing = low[: int(np.argmax(low[:, 0])) + 1]  # up to the deepest point: the back-off comes after
    meet = pushing[int(np.argmin(np.abs(pushing[:, 0] + CUBE_PUSH_REACH_M)))]
    assert meet[1] == pytest.approx(0.0, abs=5e-5)
    assert low[0][1] == pytest.approx(-0.001 * s.push_clearance_m / 0.003, abs=1e-6), "started that far the other way"


def test_a_diagonal_push_does_not_go_sideways_towards_a_blocked_side(clock) -> None:
    context = make_context(clock=clock)
    write(
        {"/red/pose": cube_pose(0.5, 0.05), "/red/target": PlanarPose(0.0, 0.0, 0.0), "/red/offset_xy_mm": (3.0, 1.0)}
    )
    # +y is blocked by a neighbour: the push along +x stays straight.
    push = set_up(Push("push red", "red", strategy="diagonal", towards=("+x", "-x", "-y")), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +3.00 mm along x"
    assert push.across_m == 0.0
