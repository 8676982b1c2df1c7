"""Place: lower the cube onto its target and release it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import CUBE_EDGE_M, CUBE_GRASP_HEIGHT_M, SETTINGS, assert_never_blocks, command_at, set_up, write
from fakes import fake_arm, fake_gripper, make_context, tick_until_done
from py_trees.common import Status

from bt_arrange.behaviours import Place, stages
from bt_arrange.geometry import PlanarPose, fold_yaw

# -- Place ---------------------------------------------------------------------------------------


def test_place_lowers_the_cube_onto_its_target_and_releases_it(clock) -> None:
    context = make_context(clock, gripper_width_m=CUBE_EDGE_M, object_width_m=CUBE_EDGE_M)
    target = PlanarPose(0.45, -0.1, math.radians(30.0))
    write({"/red/target": target})
    run = tick_until_done(set_up(Place("place red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "red released at its target"
    assert_never_blocks(run)
    assert list(dict.fromkeys(t.feedback for t in run.running)) == [
        stages.CARRY_ABOVE_TARGET,
        stages.LOWER_CUBE,
        stages.RELEASE_CUBE,
        stages.RETREAT,
    ]
    arm, gripper = fake_arm(context), fake_gripper(context)
    # The pads open only the release clearance beyond the cube on each side (8 mm: 66 mm for a 5 cm cube).
    opening_m = CUBE_EDGE_M + 2 * SETTINGS.release_clearance_per_side_m
    assert [(c.kind, c.value) for c in gripper.commands] == [("open", pytest.approx(opening_m))]
    release = arm.tcp_pose_at(command_at(arm.commands, gripper.commands[0].time_s).positions_rad)
    expected_z_m = CUBE_GRASP_HEIGHT_M + SETTINGS.release_clearance_m
    np.testing.assert_allclose(release.position_m, [0.45, -0.1, expected_z_m], atol=1e-6)
    assert fold_yaw(release.yaw_rad - target.yaw_rad) == pytest.approx(0.0, abs=1e-4)
    np.testing.assert_allclose(arm.tcp_pose().position_m, [0.45, -0.1, SETTINGS.approach_height_m], atol=1e-6)
