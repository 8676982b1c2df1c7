"""A scripted pick and place steered by ground truth: a yardstick for the cell, not the task.

The benchmark of the work cell and its integration tests use it to measure what the arm, the
gripper and the physics can do before perception enters. The behaviours of
``bt_arrange.behaviours`` do the same steps tick by tick from camera poses instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_arrange.motion import (
    ArmKinematics,
    CartesianLimits,
    JointLimits,
    Motion,
    MotionPlanner,
    gripper_down_pose,
    nearest_symmetric_yaw,
)
from bt_arrange.settings import CUBE_EDGE_M, ManipulationSettings
from bt_arrange_sim.cell import WorkCell


@dataclass
class PickPlaceResult:
    """What one scripted pick and place measured (ground truth; the robot saw none of it)."""

    grasped: bool
    grip_width_m: float
    sim_seconds: float


class ScriptedPickPlace:
    """Drives the cell through approach, descend, close, lift, carry, lower, open, retreat."""

    def __init__(
        self,
        cell: WorkCell,
        settings: ManipulationSettings | None = None,
        joint_limits: JointLimits | None = None,
        cartesian_limits: CartesianLimits | None = None,
    ) -> None:
        self.cell = cell
        self.settings = settings or ManipulationSettings()
        self.kinematics = ArmKinematics()
        self.planner = MotionPlanner(
            self.kinematics,
            joint_limits or JointLimits(),
            cartesian_limits or CartesianLimits(),
            cell.config.physics.control_period_s,
        )

    def run(self, motion: Motion) -> None:
        """Step the world until the motion is done and the arm has settled."""
        arm = self.cell.arm
        while not motion.done:
            setpoint = motion.step()
            arm.command(setpoint.positions_rad, setpoint.velocities_rad_s)
            self.cell.step()
        self.wait(self.settings.settle_s)

    def wait(self, seconds: float) -> None:
        """Let the world run with the current commands."""
        self.cell.settle(seconds)

    def wait_for_gripper(self) -> None:
        """Step until the fingers stop (or the timeout passes)."""
        period = self.cell.config.physics.control_period_s
        self.cell.step(3)
        waited = 0.0
        while self.cell.gripper.is_moving() and waited < self.settings.gripper_timeout_s:
            self.cell.step()
            waited += period

    def pick(self, x_m: float, y_m: float, yaw_rad: float) -> PickPlaceResult:
        """Grasp a cube resting at (x, y, yaw) and lift it to the approach height."""
        s = self.settings
        start = self.cell.clock.now()
        arm, gripper = self.cell.arm, self.cell.gripper
        yaw = nearest_symmetric_yaw(yaw_rad, self.kinematics.wrist_yaw_rad(arm.joint_positions()))
        gripper.open(s.open_width_m)
        above = gripper_down_pose(x_m, y_m, s.approach_height_m, yaw)
        self.run(self.planner.move_to_pose(arm.joint_positions(), above))
        self.wait_for_gripper()
        self.run(self.planner.move_line(arm.joint_positions(), gripper_down_pose(x_m, y_m, s.grasp_height_m, yaw)))
        gripper.close(s.grip_force_n)
        self.wait_for_gripper()
        width = gripper.width()
        grasped = width > CUBE_EDGE_M - s.grasp_width_tolerance_m
        self.run(self.planner.move_line(arm.joint_positions(), above))
        return PickPlaceResult(grasped, width, self.cell.clock.now() - start)

    def place(self, x_m: float, y_m: float, yaw_rad: float) -> float:
        """Carry the held cube above (x, y), lower it to rest, open and retreat; returns sim seconds."""
        s = self.settings
        start = self.cell.clock.now()
        arm, gripper = self.cell.arm, self.cell.gripper
        yaw = nearest_symmetric_yaw(yaw_rad, self.kinematics.wrist_yaw_rad(arm.joint_positions()))
        above = gripper_down_pose(x_m, y_m, s.approach_height_m, yaw)
        self.run(self.planner.move_to_pose(arm.joint_positions(), above))
        release_z = s.grasp_height_m + s.release_clearance_m
        self.run(self.planner.move_line(arm.joint_positions(), gripper_down_pose(x_m, y_m, release_z, yaw)))
        gripper.open(s.open_width_m)
        self.wait_for_gripper()
        self.run(self.planner.move_line(arm.joint_positions(), above))
        return self.cell.clock.now() - start

    def push(self, x_m: float, y_m: float, axis: str, distance_m: float) -> float:
        """Push a cube resting at (x, y) by ``distance_m`` along world ``axis`` ("x" or "y").

        The fingers stand side by side along the face, opened to the cube's width minus a pad's
        thickness, so both pads meet the face near its edges. Returns sim seconds.
        """
        if axis not in ("x", "y"):
            raise ValueError(f"push axis must be 'x' or 'y', got {axis!r}")
        s = self.settings
        start = self.cell.clock.now()
        arm, gripper = self.cell.arm, self.cell.gripper
        direction = np.array([1.0, 0.0] if axis == "x" else [0.0, 1.0]) * np.sign(distance_m)
        # The closing axis lies across the push; the pads' leading faces are half a pad width ahead.
        push_yaw = math.atan2(direction[1], direction[0]) + math.pi / 2
        yaw = nearest_symmetric_yaw(push_yaw, self.kinematics.wrist_yaw_rad(arm.joint_positions()), math.pi)
        reach_m = s.push_reach_m
        centre = np.array([x_m, y_m])
        begin = centre - direction * (reach_m + s.push_clearance_m)
        end = centre - direction * reach_m + direction * abs(distance_m)
        back = end - direction * s.push_clearance_m
        gripper.open(s.push_opening_m)
        self.run(self.planner.move_to_pose(arm.joint_positions(), gripper_down_pose(*begin, s.approach_height_m, yaw)))
        self.wait_for_gripper()
        self.run(self.planner.move_line(arm.joint_positions(), gripper_down_pose(*begin, s.push_height_m, yaw)))
        self.run(self.planner.move_line(arm.joint_positions(), gripper_down_pose(*end, s.push_height_m, yaw)))
        self.run(self.planner.move_line(arm.joint_positions(), gripper_down_pose(*back, s.push_height_m, yaw)))
        self.run(self.planner.move_line(arm.joint_positions(), gripper_down_pose(*back, s.approach_height_m, yaw)))
        return self.cell.clock.now() - start
