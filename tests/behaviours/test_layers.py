"""Layers: Pick, Place and Push at a support's height; CheckStanding from depth."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from behaviour_helpers import CUBE_EDGE_M, CUBE_GRASP_HEIGHT_M, SETTINGS, assert_never_blocks, command_at, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import CheckStanding, Pick, Place, keys
from bt_arrange.geometry import PlanarPose, Pose
from bt_arrange.robot import CameraFrame, PixelWindow
from bt_arrange.testing import fake_arm, fake_gripper, make_context, tick_until_done

Z_M = 0.05  # one 5 cm cube below


def test_place_on_a_support_releases_at_its_height_and_retreats_above_the_raised_part(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    write({"/red/target": PlanarPose(0.5, 0.0, 0.0)})
    run = tick_until_done(set_up(Place("place red", "red", z_m=Z_M), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert_never_blocks(run)
    arm, gripper = fake_arm(context), fake_gripper(context)
    release = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[0].time_s).positions_rad)
    # Let go higher above a support than above the table, and slowly (docs/stacking.md, "Releasing on parts").
    assert SETTINGS.raised_release_clearance_m > SETTINGS.release_clearance_m
    assert release.position_m[2] == pytest.approx(
        Z_M + CUBE_GRASP_HEIGHT_M + SETTINGS.raised_release_clearance_m, abs=1e-6
    )
    (opening,) = gripper.commands
    assert opening.kind == "open" and opening.speed_m_s == SETTINGS.raised_release_finger_speed_m_s
    assert SETTINGS.raised_release_finger_speed_m_s < SETTINGS.finger_speed_m_s
    # The pads' bottoms stay the gripper's table clearance above the support's top face.
    assert release.position_m[2] - SETTINGS.gripper.pad_half_height_m > Z_M + SETTINGS.gripper.table_clearance_m
    assert arm.tcp_pose().position_m[2] == pytest.approx(Z_M + CUBE_EDGE_M + SETTINGS.approach_clearance_m, abs=1e-6)


def test_pick_off_a_support_closes_at_the_raised_part_s_grasp_height(clock) -> None:
    context = make_context(clock=clock, gripper_width_m=0.085, object_width_m=CUBE_EDGE_M)
    write({"/red/pose": Pose.from_planar(0.5, 0.0, 0.0, Z_M + CUBE_EDGE_M)})
    run = tick_until_done(set_up(Pick("pick red", "red", z_m=Z_M), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    arm, gripper = fake_arm(context), fake_gripper(context)
    close = next(c for c in gripper.commands if c.kind == "close")
    grasp = arm.tcp_pose_at(command_at(arm.commands, close.time_s).positions_rad)
    assert grasp.position_m[2] == pytest.approx(Z_M + CUBE_GRASP_HEIGHT_M, abs=1e-6)


class PlaneCamera:
    """A depth camera over one plane: ``z = top_m + tan(tilt) * (x - x0)`` everywhere (no colour)."""

    def __init__(self, camera, x0_m: float, top_m: float, tilt_deg: float = 0.0) -> None:
        self.inner, self.x0_m, self.top_m, self.slope = camera, x0_m, top_m, math.tan(math.radians(tilt_deg))

    @property
    def intrinsics(self):
        return self.inner.intrinsics

    @property
    def pose_world(self) -> Pose:
        return self.inner.pose_world

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        intrinsics = self.intrinsics if window is None else self.intrinsics.windowed(window)
        T = self.pose_world
        v, u = np.mgrid[0 : intrinsics.height_px, 0 : intrinsics.width_px].astype(float)
        rays = np.stack(
            [(u - intrinsics.cx_px) / intrinsics.fx_px, (v - intrinsics.cy_px) / intrinsics.fy_px, np.ones_like(u)], -1
        )
        world = rays @ T.rotation.T  # direction per unit of depth
        origin = T.position_m
        # origin_z + d * w_z = top + slope * (origin_x + d * w_x - x0)
        depth = (self.top_m + self.slope * (origin[0] - self.x0_m) - origin[2]) / (
            world[..., 2] - self.slope * world[..., 0]
        )
        rgb = np.zeros((intrinsics.height_px, intrinsics.width_px, 3), dtype=np.uint8)
        return CameraFrame(rgb, depth.astype(np.float32), intrinsics, T, 0.0)


def standing_run(clock, top_m: float, tilt_deg: float = 0.0):
    context = make_context(clock=clock)
    context.robot = dataclasses.replace(context.robot, camera=PlaneCamera(context.robot.camera, 0.5, top_m, tilt_deg))
    write({"/red/pose": Pose.from_planar(0.5, 0.0, 0.2, Z_M + CUBE_EDGE_M)})
    return tick_until_done(set_up(CheckStanding("red stands", "red", z_m=Z_M), context), context)


def test_check_standing_passes_a_level_top_face_at_its_height_and_writes_what_depth_measured(clock) -> None:
    run = standing_run(clock, Z_M + CUBE_EDGE_M + 0.0005)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback.startswith("red stands on its support: top face +0.50 mm from 100 mm, tilted 0.00 deg")
    import py_trees

    assert py_trees.blackboard.Blackboard.get(keys.key("red", keys.TOP_HEIGHT_ERROR_MM)) == pytest.approx(0.5, abs=1e-3)


def test_check_standing_fails_a_part_that_fell_naming_by_how_much(clock) -> None:
    run = standing_run(clock, CUBE_EDGE_M)
    assert run.status == Status.FAILURE
    assert run.feedback == (
        "red does not stand on its support: its top face lies at 50.0 mm, 50.0 mm below the 100.0 mm it should "
        "(fallen; tilted 0.0 deg)"
    )


def test_check_standing_fails_a_tipped_part(clock) -> None:
    run = standing_run(clock, Z_M + CUBE_EDGE_M, tilt_deg=6.0)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith("red is tipped: its top face tilts 6.0 deg, more than 2 deg")


def test_a_raised_part_is_pushed_at_its_own_height_along_the_gentler_line(clock) -> None:
    from bt_arrange.behaviours import Push
    from bt_arrange.motion import LinearMotion

    context = make_context(clock=clock)
    write(
        {
            "/red/pose": Pose.from_planar(0.5, 0.0, 0.0, Z_M + CUBE_EDGE_M),
            "/red/target": PlanarPose(0.506, 0.0, 0.0),
            "/red/offset_xy_mm": (6.0, 0.0),
        }
    )
    push = set_up(Push("push red", "red", z_m=Z_M), context)
    run = tick_until_done(push, context)
    assert run.status == Status.SUCCESS, run.feedback
    lines = {s.name: s.motion for s in push._stages if isinstance(getattr(s, "motion", None), LinearMotion)}
    pushing = lines["push 6.00 mm along x"]
    assert pushing.cartesian_limits == SETTINGS.raised_push_limits
    assert SETTINGS.raised_push_limits.velocity_m_s < SETTINGS.push_limits.velocity_m_s
    # At the part's own height: the pads' middle at its grasp height above the support, start to end.
    for pose in (pushing.start_pose, pushing.end_pose):
        assert pose.position_m[2] == pytest.approx(Z_M + CUBE_GRASP_HEIGHT_M, abs=1e-6)
