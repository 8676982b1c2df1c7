"""Behaviours that look: Detect and Inspect (camera frame through perception, poses to the blackboard)."""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.context import Context
from bt_arrange.geometry import PlanarPose, Pose, rotation_z

#: The arm counts as parked (out of the camera's view) within this joint distance of home.
PARKED_TOLERANCE_RAD = 0.01


def park_stage(name: str = stage.PARK) -> MoveStage:
    """A joint motion home, or nothing when the arm is already there."""

    def plan(context: Context, q: np.ndarray):  # noqa: ANN202 - a Motion
        return context.planner.move_joints(q, context.home_q)

    return MoveStage(name, plan)


def is_parked(context: Context) -> bool:
    """True when the arm rests at its home pose, out of the camera's view."""
    q = context.robot.arm.joint_positions()
    return float(np.max(np.abs(q - context.home_q))) < PARKED_TOLERANCE_RAD


def offset_in_target_frame_mm(target: PlanarPose, pose: Pose) -> tuple[float, float]:
    """Target minus measured position, in the target's frame (x along its yaw), in millimetres."""
    world = np.array([target.x_m - pose.x_m, target.y_m - pose.y_m, 0.0])
    local = rotation_z(target.yaw_rad).T @ world
    return float(local[0] * 1000), float(local[1] * 1000)


class MoveHome(StagedBehaviour):
    """Move the arm home, out of the top camera's view."""

    def stages(self, context: Context) -> list[Stage]:
        """One joint motion, or none when parked."""
        return [] if is_parked(context) else [park_stage(stage.MOVE_HOME)]

    def success_message(self) -> str:
        """Feedback once home."""
        return "at home, out of the camera's view"


class Detect(StagedBehaviour):
    """Find an object with the top camera and write its measured pose to ``/<obj>/pose``.

    The arm first moves out of the camera's view when it is not parked. A cube the camera
    cannot see (not found, ambiguous, partial) is a FAILURE whose feedback says why.
    """

    def __init__(self, name: str, obj: str, colour: str | None = None) -> None:
        super().__init__(name)
        self.obj = obj
        self.colour = colour or obj
        self.writes(keys.key(obj, keys.POSE))
        self.found: Pose | None = None

    def stages(self, context: Context) -> list[Stage]:
        """Park if needed, then look."""
        context.detector.colours[self.colour]  # raises PerceptionError for an unknown colour
        looking = InstantStage(stage.look_for(self.colour), self._look)
        return [looking] if is_parked(context) else [park_stage(), looking]

    def _look(self, context: Context) -> str | None:
        frame = context.robot.camera.capture()
        detection = context.detector.detect(frame, self.colour)
        if not detection.found or detection.pose_world is None:
            return f"{self.colour} {detection.status.value}: {detection.reason}"
        self.found = detection.pose_world
        self.write(keys.key(self.obj, keys.POSE), detection.pose_world)
        self.on_found(detection.pose_world)
        return None

    def on_found(self, pose: Pose) -> None:
        """Hook for subclasses: called with the measured pose."""

    def success_message(self) -> str:
        """Feedback with the measured pose."""
        assert self.found is not None
        planar = self.found.planar()
        return (
            f"{self.colour} at x={planar.x_m:.4f} m, y={planar.y_m:.4f} m, yaw={math.degrees(planar.yaw_rad):.2f} deg"
        )


class Inspect(Detect):
    """Detect again and write the offset to the target: ``/<obj>/offset_mm`` and ``/<obj>/offset_xy_mm``.

    ``after_placing=True`` also records the offset as ``/<obj>/placed_offset_mm`` (the paper's
    "after placing" figure).
    """

    def __init__(self, name: str, obj: str, colour: str | None = None, after_placing: bool = False) -> None:
        super().__init__(name, obj, colour)
        self.after_placing = after_placing
        self.reads(keys.key(obj, keys.TARGET))
        self.writes(keys.key(obj, keys.OFFSET_MM), keys.key(obj, keys.OFFSET_XY_MM))
        if after_placing:
            self.writes(keys.key(obj, keys.PLACED_OFFSET_MM))
        self.offset_mm: float | None = None

    def on_found(self, pose: Pose) -> None:
        """Compare with the target and write the offsets."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        dx_mm, dy_mm = offset_in_target_frame_mm(target, pose)
        self.offset_mm = math.hypot(dx_mm, dy_mm)
        self.write(keys.key(self.obj, keys.OFFSET_MM), self.offset_mm)
        self.write(keys.key(self.obj, keys.OFFSET_XY_MM), (dx_mm, dy_mm))
        if self.after_placing:
            self.write(keys.key(self.obj, keys.PLACED_OFFSET_MM), self.offset_mm)

    def success_message(self) -> str:
        """Feedback with the offset."""
        return f"{super().success_message()}; {self.offset_mm:.2f} mm from the target"
