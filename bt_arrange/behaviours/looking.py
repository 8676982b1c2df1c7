"""Behaviours that look: Detect and Inspect (camera frame through perception, poses to the blackboard)."""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.context import Context
from bt_arrange.geometry import PlanarPose, Pose, rotation_z
from bt_arrange.perception import Detection, WorldRegion
from bt_arrange.robot import PixelWindow

#: The arm counts as parked (out of the camera's view) within this joint distance of home.
PARKED_TOLERANCE_RAD = 0.01
#: Room around a cube located in the binned search view (accurate to 2 mm) for the window that
#: measures it: the sub-pixel edge fit reads 5 px (2.4 mm) beyond each edge. Measured: windows
#: from 4 mm up give the full frame's detection exactly (clean images, 24 random poses).
LOCATED_MARGIN_M = 0.006
#: Room around where a cube should be (its target) for the window Inspect looks through first:
#: a placed or pushed cube lies within a millimetre or two of its target. One farther away (say,
#: placed after a 2 cm pick error, about 14 mm off) is found by the search view instead: two
#: small renders then, instead of one window large enough for every case every time.
EXPECTED_MARGIN_M = 0.008


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


def _measure_in_window(context: Context, colour: str, x_m: float, y_m: float, margin_m: float) -> Detection | None:
    """Render only the window around ``(x, y)`` at full resolution and measure the cube there."""
    camera, detector = context.robot.camera, context.detector
    half_m = detector.config.cube_edge_m / math.sqrt(2.0) + margin_m
    window = detector.window_around(camera.intrinsics, camera.pose_world, x_m, y_m, half_m)
    if window is None:
        return None
    frame = camera.capture(window=window)
    return detector.detect(frame, colour, roi=WorldRegion.around(x_m, y_m, half_m))


def look(context: Context, colour: str, expected_xy_m: tuple[float, float] | None = None) -> Detection:
    """Find the cube of ``colour``, rendering (or reading out) only the pixels a detection needs.

    1. With ``expected_xy_m`` (where the cube should be), a full-resolution window around it.
    2. Otherwise, or when that window does not show one whole face: a binned view of the whole
       image finds the blobs of the colour; none, or several, is the outcome (as the full frame
       would say); one is measured in a full-resolution window around it.
    3. A face the window does not show whole (cut by the window, covered) is looked at in the
       full frame, whose outcome and reason stand.

    A window shows the pixels the full frame has there, so a window's detection is the full
    frame's (docs/perception.md).
    """
    camera, detector = context.robot.camera, context.detector
    if expected_xy_m is not None:
        detection = _measure_in_window(context, colour, *expected_xy_m, EXPECTED_MARGIN_M)
        if detection is not None and detection.found:
            return detection
    binning = detector.search_binning(camera.intrinsics, camera.pose_world)
    if binning > 1:
        search = camera.capture(window=PixelWindow.full(camera.intrinsics, binning))
        located = detector.locate(search, colour)
        if len(located) != 1:
            return detector.detect(search, colour)
        detection = _measure_in_window(context, colour, *located[0], LOCATED_MARGIN_M)
        if detection is not None and detection.found:
            return detection
    return detector.detect(camera.capture(), colour)


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
    cannot see (not found, ambiguous, partial) is a FAILURE whose feedback says why. The camera
    renders only what the detection needs (``look``): a binned full view to find the cube, a
    full-resolution window around it to measure it.
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

    def expected_xy_m(self) -> tuple[float, float] | None:
        """Where the cube should be, to look there first; None: search the whole view."""
        return None

    def _look(self, context: Context) -> str | None:
        detection = look(context, self.colour, self.expected_xy_m())
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

    Looks through a window around the target first, and searches the whole view only when the
    cube is not there.

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

    def expected_xy_m(self) -> tuple[float, float] | None:
        """The target: a placed or pushed cube lies near it."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        return target.x_m, target.y_m

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


class Recheck(Inspect):
    """Look again at a part placed earlier, after a neighbour's release and pushes: did they move it.

    An Inspect (the offset to its target is written afresh, so a correction loop after it pushes
    the part back when it moved beyond the threshold) that also writes how far the part moved
    since it was last looked at, ``/<obj>/moved_mm`` (camera), and the most any later step moved
    it, ``/<obj>/max_moved_mm``. ``after`` names the step whose effect is checked.
    """

    def __init__(self, name: str, obj: str, colour: str | None = None, after: str = "") -> None:
        super().__init__(name, obj, colour)
        self.after = after
        self.reads(keys.key(obj, keys.POSE), keys.key(obj, keys.MAX_MOVED_MM))
        self.writes(keys.key(obj, keys.MOVED_MM), keys.key(obj, keys.MAX_MOVED_MM))
        self.moved_mm: float | None = None
        self._before: Pose | None = None

    def on_found(self, pose: Pose) -> None:
        """Compare with the pose it had when last looked at, then as Inspect."""
        # Detect wrote the new pose already; the one before it was kept by _look.
        before = self._before
        self.moved_mm = None
        if before is not None:
            self.moved_mm = float(np.hypot(pose.x_m - before.x_m, pose.y_m - before.y_m) * 1000)
            self.write(keys.key(self.obj, keys.MOVED_MM), self.moved_mm)
            max_key = keys.key(self.obj, keys.MAX_MOVED_MM)
            previous = self.blackboard.get(max_key) if self.blackboard.exists(max_key) else 0.0
            self.write(max_key, max(float(previous), self.moved_mm))
        super().on_found(pose)

    def _look(self, context: Context) -> str | None:
        pose_key = keys.key(self.obj, keys.POSE)
        self._before = self.blackboard.get(pose_key) if self.blackboard.exists(pose_key) else None
        return super()._look(context)

    def success_message(self) -> str:
        """Feedback with the offset and the motion since last looked at."""
        moved = "" if self.moved_mm is None else f"; moved {self.moved_mm:.2f} mm since last looked at"
        return f"{super().success_message()}{moved}"
