"""GraspGuard: runs its child while the cube is held, fails within a tick when it slips."""

from __future__ import annotations

from behaviour_helpers import (
    CUBE_EDGE_M,
    HELD_MIN_WIDTH_M,
    SETTINGS,
    after,
    assert_comes_to_rest,
    assert_never_blocks,
    set_up,
    write,
)
from py_trees.common import Status

from bt_arrange.behaviours import Context, GraspGuard, Place, stages
from bt_arrange.geometry import PlanarPose
from bt_arrange.testing import brake_until_idle, fake_arm, fake_clock, fake_gripper, make_context, tick_until_done

# -- GraspGuard ----------------------------------------------------------------------------------


def guarded_place(context: Context) -> tuple[GraspGuard, Place]:
    """A cube held between closed fingers, a Place under the guard."""
    fake_gripper(context).close(SETTINGS.grip_force_n)
    fake_clock(context).advance(2.0)  # 85 mm closed at 50 mm/s: at rest
    write({"/red/target": PlanarPose(0.45, -0.1, 0.0)})
    place = Place("place red", "red")
    guard = GraspGuard("while holding red", place)
    set_up(guard, context)
    return guard, place


def test_grasp_guard_runs_the_child_while_the_cube_is_held(clock) -> None:
    context = make_context(clock=clock, object_width_m=CUBE_EDGE_M)
    guard, place = guarded_place(context)
    run = tick_until_done(guard, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert place.status == Status.SUCCESS
    assert run.ticks[0].feedback == f"holding; {stages.CARRY_ABOVE_TARGET}"
    assert all(t.feedback.startswith("holding; ") for t in run.ticks)
    assert_never_blocks(run)


def test_grasp_guard_fails_within_a_tick_when_the_cube_slips_out(clock) -> None:
    context = make_context(clock=clock, object_width_m=CUBE_EDGE_M)
    guard, place = guarded_place(context)
    run = tick_until_done(guard, context, until=after(f"holding; {stages.CARRY_ABOVE_TARGET}", 50))
    assert guard.status == Status.RUNNING and place.status == Status.RUNNING
    assert run.feedback == f"holding; {stages.CARRY_ABOVE_TARGET}"

    gripper = fake_gripper(context)
    gripper.slip()
    for _ in range(100):
        width_m = gripper.width()
        guard.tick_once()
        context.brake.step()
        clock.advance(fake_arm(context).control_period_s)
        if width_m >= HELD_MIN_WIDTH_M:
            assert guard.status == Status.RUNNING, f"still held at {width_m * 1000:.1f} mm"
        else:
            assert guard.status == Status.FAILURE, f"the first tick at {width_m * 1000:.1f} mm fails"
            break
    assert guard.status == Status.FAILURE
    assert place.status == Status.INVALID, "the child is interrupted"
    assert place.feedback_message == stages.INTERRUPTED
    assert guard.feedback_message.startswith("the part left the gripper: fingers at ")
    assert guard.feedback_message.endswith("mm, under the 47.0 mm of a held part")
    assert context.brake.active, "the carry motion goes to the brake"
    assert_comes_to_rest(brake_until_idle(context))


def test_grasp_guard_fails_at_once_when_nothing_is_held(clock) -> None:
    context = make_context(clock=clock, object_width_m=None)
    guard, place = guarded_place(context)
    guard.tick_once()
    assert guard.status == Status.FAILURE
    assert guard.feedback_message == "the part left the gripper: fingers at 0.0 mm, under the 47.0 mm of a held part"
    assert place.status == Status.INVALID, "the child never ran"
    assert fake_arm(context).commands == []


def test_grasp_guard_judges_a_sunk_grip_by_the_grip_it_found(clock) -> None:
    """Pads sunk 2 mm into the part hold it: the guard fails only when the fingers close 3 mm past that grip.

    The real-cell model's fresco piece: gripped 2.3 mm under its nominal width, 0.7 mm more on the
    lift, it was judged gone (under the nominal less 3 mm) while held, and carried to the next pick.
    """
    sunk_m = 0.002
    context = make_context(clock=clock, object_width_m=CUBE_EDGE_M - sunk_m)
    guard, place = guarded_place(context)
    tick_until_done(guard, context, until=after(f"holding; {stages.CARRY_ABOVE_TARGET}", 10))
    assert guard.grip_width_m is not None and abs(guard.grip_width_m - (CUBE_EDGE_M - sunk_m)) < 1e-9
    grip_low_m = CUBE_EDGE_M - sunk_m - SETTINGS.grasp_width_tolerance_m
    assert abs(guard.held_width_m() - grip_low_m) < 1e-9 and grip_low_m < HELD_MIN_WIDTH_M

    gripper = fake_gripper(context)
    gripper.object_width_m = HELD_MIN_WIDTH_M - 0.0007  # sinks on: under the nominal bound, over the grip's
    gripper.close(SETTINGS.grip_force_n)
    clock.advance(0.1)
    guard.tick_once()
    assert guard.status == Status.RUNNING, guard.feedback_message
    assert place.status == Status.RUNNING

    gripper.slip()
    for _ in range(100):
        guard.tick_once()
        context.brake.step()
        clock.advance(fake_arm(context).control_period_s)
        if guard.status == Status.FAILURE:
            break
    assert guard.status == Status.FAILURE
    assert guard.feedback_message.endswith(f"under the {grip_low_m * 1000:.1f} mm of a held part")
    assert gripper.commands[-1].kind == "open", "what is left between the pads is let go"
    assert guard.grip_width_m is None, "the next run judges its own grip"


def test_grasp_guard_never_raises_the_bound_above_the_nominal(clock) -> None:
    """A grip wider than the part (held across corners) keeps the nominal bound: it may sink that far."""
    context = make_context(clock=clock, object_width_m=CUBE_EDGE_M + 0.004)
    guard, _ = guarded_place(context)
    guard.tick_once()
    assert guard.status == Status.RUNNING
    assert guard.held_width_m() == HELD_MIN_WIDTH_M
