"""An irregular part's look parks the arm with its last wrist joint where it is (issue 36); a cube's goes home."""

from __future__ import annotations

import math

import numpy as np
from behaviour_helpers import AWAY_Q, set_up
from fakes import fake_arm, fake_camera, make_context, tick_until_done
from py_trees.common import Status

from bt_arrange.behaviours import Context, Detect, MoveHome, stages
from bt_arrange.behaviours.looking import HOLDING_MARGIN_M, keeps_wrist_parked
from bt_arrange.behaviours.moves import grasp_width_m, release_opening_m, wrist_yaw_rad
from bt_arrange.motion import DEFAULT_HOME_Q
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.synthetic import SyntheticCube, SyntheticPrism
from bt_arrange.shapes import Prism

FRAGMENT = ObjectType(
    "fragment",
    shape=Prism.from_outline(np.array([[0, 0], [45, 4], [60, 30], [35, 28], [30, 50], [5, 40]]) / 1000, 0.02),
)
#: Away from home with the last wrist joint turned 2.5 rad from home's.
TURNED_Q = [*AWAY_Q[:5], DEFAULT_HOME_Q[5] + 2.5]


def _detect_fragment(context: Context) -> tuple[Status, str]:
    fake_camera(context).cubes.append(SyntheticPrism("red", 0.55, -0.12, 2.5, FRAGMENT.shape))
    run = tick_until_done(set_up(Detect("detect the fragment", "fragment", "red", FRAGMENT), context), context)
    return run.status, run.feedback


def _released(clock: object, object_type: ObjectType, q: list[float]) -> Context:
    """Fingers at the release's opening: nothing between them."""
    context = make_context(clock, q=q)  # type: ignore[arg-type]
    context.robot.gripper.open(release_opening_m(context.settings, object_type))
    clock.advance(1.0)  # type: ignore[attr-defined]
    return context


def test_an_irregular_parts_look_parks_with_the_last_wrist_joint_where_it_is(clock) -> None:
    context = _released(clock, FRAGMENT, TURNED_Q)
    status, feedback = _detect_fragment(context)
    assert status == Status.SUCCESS, feedback
    q = fake_arm(context).joint_positions()
    np.testing.assert_allclose(q[:5], context.home_q[:5], atol=1e-6)
    assert q[5] == TURNED_Q[5]
    # The camera looked with the arm there, not at the full home pose.
    assert fake_camera(context).captures[-1][1][5] == TURNED_Q[5]


def test_a_cubes_look_parks_fully_home(clock) -> None:
    context = _released(clock, CUBE, TURNED_Q)
    fake_camera(context).cubes.append(SyntheticCube("red", 0.45, 0.1, 0.3))
    run = tick_until_done(set_up(Detect("detect red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    np.testing.assert_allclose(fake_arm(context).joint_positions(), context.home_q, atol=1e-6)


def test_an_irregular_part_at_home_with_its_wrist_turned_is_looked_at_without_moving(clock) -> None:
    turned_home = [*DEFAULT_HOME_Q[:5], DEFAULT_HOME_Q[5] - 1.0]
    context = _released(clock, FRAGMENT, turned_home)
    status, feedback = _detect_fragment(context)
    assert status == Status.SUCCESS, feedback
    assert fake_arm(context).commands == []


def test_fingers_about_the_parts_width_apart_park_fully_home(clock) -> None:
    """A part may be wedged between the pads: the full park of before, whose wrist turn let it fall."""
    context = make_context(clock, q=TURNED_Q)
    held_m = grasp_width_m(context.settings, FRAGMENT) - 0.5 * HOLDING_MARGIN_M
    context.robot.gripper.open(held_m)
    clock.advance(1.0)
    assert not keeps_wrist_parked(context, FRAGMENT)
    status, feedback = _detect_fragment(context)
    assert status == Status.SUCCESS, feedback
    np.testing.assert_allclose(fake_arm(context).joint_positions(), context.home_q, atol=1e-6)


def test_keeps_the_wrist_only_for_irregular_parts_with_the_fingers_clear(clock) -> None:
    context = _released(clock, FRAGMENT, TURNED_Q)
    assert keeps_wrist_parked(context, FRAGMENT)
    assert not keeps_wrist_parked(context, CUBE)


def test_move_home_leaves_an_arm_parked_with_its_wrist_turned(clock) -> None:
    turned_home = [*DEFAULT_HOME_Q[:5], DEFAULT_HOME_Q[5] + math.pi]
    context = make_context(clock, q=turned_home)
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert [t.status for t in run.ticks] == [Status.SUCCESS]
    assert fake_arm(context).commands == []


def test_move_home_from_away_goes_fully_home(clock) -> None:
    context = make_context(clock, q=TURNED_Q)
    run = tick_until_done(set_up(MoveHome("park"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert {t.feedback for t in run.running} == {stages.MOVE_HOME}
    np.testing.assert_allclose(fake_arm(context).joint_positions(), context.home_q, atol=1e-6)


def test_a_parked_arm_with_its_wrist_turned_chooses_grasps_as_from_home(clock) -> None:
    """The pads meet an irregular part's sides as after a full park: the same grasp, a shorter route."""
    home = make_context(clock)
    turned = make_context(clock, q=[*DEFAULT_HOME_Q[:5], DEFAULT_HOME_Q[5] + 2.0])
    away = make_context(clock, q=TURNED_Q)
    assert wrist_yaw_rad(turned) == wrist_yaw_rad(home)
    assert wrist_yaw_rad(away) != wrist_yaw_rad(home)
