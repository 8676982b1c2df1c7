"""Behaviours that look: Detect and Inspect (camera frame through perception, poses to the blackboard)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import (
    COLOUR,
    DETECT_ENTRIES,
    INSPECT_ENTRIES,
    KIND_TARGETS,
    OBJ,
    OBJECT_TYPE_PORT,
    Z_PORT,
    entries,
)
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import JointMovePlan
from bt_arrange.geometry import PlanarPose, Pose, rotation_z
from bt_arrange.numbers import fixed
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception import Detection, DetectionStatus, PartDetector, WorldRegion
from bt_arrange.perception.touching import MIN_TOUCHING_PX, TOUCH_RING_M, touching_pixels
from bt_arrange.ports import BOOL, STRING, Port
from bt_arrange.robot import CameraFrame, PixelWindow
from bt_arrange.shapes import yaw_error_rad

#: A part counts as "at a target" (placed already) when its centre lies within this fraction of
#: its shorter top edge from a target of its kind: a placed part lies within millimetres of its
#: target, a part waiting to be picked starts at least 12 cm from every target (scenes, plan check).
AT_TARGET_FRACTION = 0.5

#: Chooses one of several blobs (world x, y) of a colour; None: none will do (with the reason).
Chooser = Callable[[tuple[tuple[float, float], ...]], "tuple[tuple[float, float] | None, str]"]

#: The arm counts as parked (out of the camera's view) within this joint distance of home.
PARKED_TOLERANCE_RAD = 0.01
#: Room around a part located in the binned search view (accurate to 2 mm) for the window that
#: measures it: the sub-pixel edge fit reads 5 px (2.4 mm) beyond each edge. Measured: windows
#: from 4 mm up give the full frame's detection exactly (clean images, 24 random poses).
LOCATED_MARGIN_M = 0.006
#: Room around where a part should be (its target) for the window Inspect looks through first:
#: a placed or pushed part lies within a millimetre or two of its target. One farther away (say,
#: placed after a 2 cm pick error, about 14 mm off) is found by the search view instead: two
#: small renders then, instead of one window large enough for every case every time.
EXPECTED_MARGIN_M = 0.008


def park_stage(name: str = stage.PARK) -> MoveStage:
    """A joint motion home at the free-space limits (it may take over a motion handed on at speed)."""
    return MoveStage(name, JointMovePlan(lambda context: context.home_q, free=True))


def is_parked(context: Context) -> bool:
    """True when the arm rests at its home pose, out of the camera's view."""
    q = context.robot.arm.joint_positions()
    return float(np.max(np.abs(q - context.home_q))) < PARKED_TOLERANCE_RAD


def offset_in_target_frame_mm(target: PlanarPose, pose: Pose) -> tuple[float, float]:
    """Target minus measured position, in the target's frame (x along its yaw), in millimetres."""
    world = np.array([target.x_m - pose.x_m, target.y_m - pose.y_m, 0.0])
    local = rotation_z(target.yaw_rad).T @ world
    return float(local[0] * 1000), float(local[1] * 1000)


def _measure_in_window(
    context: Context,
    detector: PartDetector,
    colour: str,
    x_m: float,
    y_m: float,
    margin_m: float,
    roi_half_m: float | None = None,
    frames: list[CameraFrame] | None = None,
) -> Detection | None:
    """Render only the window around ``(x, y)`` at full resolution and measure the part there.

    ``roi_half_m`` (default the window's half size) bounds where a face's centre may lie; the frame
    rendered is appended to ``frames`` when given.
    """
    camera = context.robot.camera
    x_size, y_size, _ = detector.config.size_m
    half_m = 0.5 * math.hypot(x_size, y_size) + margin_m
    window = detector.window_around(camera.intrinsics, camera.pose_world, x_m, y_m, half_m)
    if window is None:
        return None
    frame = camera.capture(window=window)
    if frames is not None:
        frames.append(frame)
    return detector.detect(frame, colour, roi=WorldRegion.around(x_m, y_m, roi_half_m or half_m))


def identical_roi_half_m(object_type: ObjectType) -> float:
    """Where the centre of the part looked for may lie, among identical parts: half its shorter top edge.

    An identical neighbour 2 mm away (or the piece of it a window cuts) has its centre farther
    than that, so it is not taken for the part; the part itself lies within millimetres of where
    it is looked for (its target, or where the search view located it).
    """
    return 0.5 * min(object_type.shape.extent_m)


def look(
    context: Context,
    colour: str,
    expected_xy_m: tuple[float, float] | None = None,
    object_type: ObjectType | None = None,
    choose: Chooser | None = None,
    z_m: float = 0.0,
    frames: list[CameraFrame] | None = None,
    near_m: float | None = None,
) -> Detection:
    """Find the part of ``colour``, rendering (or reading out) only the pixels a detection needs.

    1. With ``expected_xy_m`` (where the part should be), a full-resolution window around it.
    2. Otherwise, or when that window does not show one whole face: a binned view of the whole
       image finds the blobs of the colour; none, or several, is the outcome (as the full frame
       would say) unless ``choose`` picks one of several (identical parts); one is measured in a
       full-resolution window around it.
    3. A face the window does not show whole (cut by the window, covered) is looked at in the
       full frame, whose outcome and reason stand.

    ``object_type`` (default the cube) sets the size the detector expects; ``z_m`` (a raised part's
    bottom face above the table) the plane its top face is measured on. ``near_m``: the search of
    step 2 counts only the blobs within that distance of ``expected_xy_m`` (a part looked at again
    where it was placed is not one of its colour found elsewhere). A window shows the
    pixels the full frame has there, so a window's detection is the full frame's (docs/perception.md).
    """
    camera = context.robot.camera

    def capture(window: PixelWindow | None = None) -> CameraFrame:
        # Every frame looked at is kept in ``frames`` (the last is the one the outcome was measured in).
        frame = camera.capture(window=window) if window is not None else camera.capture()
        if frames is not None:
            frames.append(frame)
        return frame

    kind = object_type or CUBE
    detector = context.detector.for_object(kind)
    if z_m:
        detector = raised_detector(detector, z_m)
    # Among identical parts a window also shows the neighbours: only a face centred near the spot counts.
    roi_half_m = identical_roi_half_m(kind) if choose is not None else None
    if expected_xy_m is not None:
        detection = _measure_in_window(context, detector, colour, *expected_xy_m, EXPECTED_MARGIN_M, roi_half_m, frames)
        if detection is not None and detection.found:
            return detection
    binning = detector.search_binning(camera.intrinsics, camera.pose_world)
    if binning > 1 or choose is not None:
        # Identical parts 2 mm apart merge into one blob in the binned view (its centre between two
        # placed parts, at neither's target): among identical parts the search reads the full frame,
        # whose large blobs the detector splits at full resolution.
        binned = binning > 1 and choose is None
        window = PixelWindow.full(camera.intrinsics, binning) if binned else None
        search = capture(window)
        located = detector.locate(search, colour)
        if near_m is not None and expected_xy_m is not None:
            near = tuple(xy for xy in located if math.dist(xy, expected_xy_m) <= near_m)
            if located and not near:
                count = len(located)
                return Detection(
                    colour,
                    DetectionStatus.NOT_FOUND,
                    f"none within {near_m * 1000:.0f} mm of ({expected_xy_m[0]:.3f}, {expected_xy_m[1]:.3f}) m, "
                    f"{count} {colour} {'blob' if count == 1 else 'blobs'} farther off",
                    candidates_xy_m=located,
                )
            located = near
        if len(located) > 1 and choose is not None:
            chosen, reason = choose(located)
            if chosen is None:
                return Detection(colour, DetectionStatus.NOT_FOUND, reason, candidates_xy_m=located)
        elif len(located) > 1 and not kind.shape.rectangular:
            # Parts of one colour told apart by outline: each blob measured at full resolution, where
            # only this part's outline registers (another outline is WRONG_OUTLINE there).
            spot_m = identical_roi_half_m(kind)
            measured = [
                _measure_in_window(context, detector, colour, *xy, LOCATED_MARGIN_M, spot_m, frames) for xy in located
            ]
            found = [d for d in measured if d is not None and d.found]
            if len(found) == 1:
                return found[0]
            return detector.detect(search, colour)
        elif len(located) != 1:
            return detector.detect(search, colour)
        else:
            chosen = located[0]
        detection = _measure_in_window(context, detector, colour, *chosen, LOCATED_MARGIN_M, roi_half_m, frames)
        if detection is not None and detection.found:
            return detection
        if len(located) > 1:
            # The chosen part is not whole in its window: the full frame, around it only.
            half_m = roi_half_m or 0.5 * math.hypot(*detector.config.size_m[:2]) + LOCATED_MARGIN_M
            return detector.detect(capture(), colour, roi=WorldRegion.around(*chosen, half_m))
    return detector.detect(capture(), colour)


def raised_detector(detector: PartDetector, z_m: float) -> PartDetector:
    """The detector for a part whose bottom face stands ``z_m`` above the table: its top face's plane moves up."""
    return PartDetector(detector.colours, replace(detector.config, table_z_m=detector.config.table_z_m + z_m))


def at_a_target(xy_m: tuple[float, float], kind_targets: Sequence[PlanarPose], object_type: ObjectType) -> bool:
    """True when a part at ``xy_m`` lies at one of ``kind_targets`` (see ``AT_TARGET_FRACTION``)."""
    radius_m = AT_TARGET_FRACTION * min(object_type.shape.extent_m)
    return any(math.hypot(xy_m[0] - t.x_m, xy_m[1] - t.y_m) < radius_m for t in kind_targets)


class MoveHome(StagedBehaviour):
    """Move the arm home, out of the top camera's view."""

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "park the arm"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """None: it only parks the arm (BehaviorTree.CPP's ``providedPorts``)."""
        return ()

    def stages(self, context: Context) -> list[Stage]:
        """One joint motion, or none when parked."""
        return [] if is_parked(context) else [park_stage(stage.MOVE_HOME)]

    def success_message(self) -> str:
        """Feedback once home."""
        return "at home, out of the camera's view"


class Detect(StagedBehaviour):
    """Find an object with the top camera and write its measured pose to ``/<obj>/pose``.

    The arm first moves out of the camera's view when it is not parked. A part the camera
    cannot see (not found, ambiguous, partial) is a FAILURE whose feedback says why. The camera
    renders only what the detection needs (``look``): a binned full view to find the part, a
    full-resolution window around it to measure it.

    ``object_type`` is the part's size (default the cube). ``kind_targets`` are the targets of
    every part of this type and colour (identical parts, the object's own among them): with
    several blobs of the colour, Detect picks one that is not at any of them (a part is "at a
    target" within half its shorter top edge, ``AT_TARGET_FRACTION``), the one nearest the
    object's own target (``/<obj>/target``, when set), so parts already placed stay put.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "camera -> /<obj>/pose"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object, its colour and type, the targets of its kind (BehaviorTree.CPP's ``providedPorts``)."""
        alone = Port(
            "alone",
            BOOL,
            False,
            "the look before a pick: fails on touching parts of its colour and says so in /<obj>/touching",
            optional=True,
        )
        return (OBJ, COLOUR, OBJECT_TYPE_PORT, KIND_TARGETS, Z_PORT, alone, *DETECT_ENTRIES)

    def __init__(
        self,
        name: str,
        obj: str,
        colour: str | None = None,
        object_type: ObjectType | None = None,
        kind_targets: Sequence[PlanarPose] = (),
        z_m: float = 0.0,
        alone: bool = False,
    ) -> None:
        super().__init__(name)
        #: The look before a pick (``before_pick``): a part found only on its free edges, in a blob it
        #: shares with touching parts, is a FAILURE (its pose is written, for ``Separate``): a neighbour
        #: may stand where the pads go down (a fresco piece's pads closed on its touching neighbour and stalled).
        self.alone = False
        self.obj = obj
        #: Layers: the height of the part's bottom face (0: the table), its top face's plane above it.
        self.z_m = float(z_m)
        self.colour = colour or obj
        self.object_type = object_type or CUBE
        self.kind_targets: tuple[PlanarPose, ...] = tuple(kind_targets)
        self.writes(keys.key(obj, keys.POSE))
        if self.kind_targets:
            self.reads(keys.key(obj, keys.TARGET))
        self.found: Pose | None = None
        #: The last look measured the part on its free edges only (``Detection.merged``).
        self.merged = False
        if alone:
            self.before_pick()

    def before_pick(self) -> None:
        """Make this the look before a pick (``alone``): it also writes ``/<obj>/touching`` at each look.

        A part found in a blob it shares with touching parts of its colour, or beside a neighbour of
        its colour (``touching_pixels``), fails; so does a blob no face explains (AMBIGUOUS): each
        writes ``"touching parts"``, and the tree pushes one aside (``Separate``) before it looks again.
        """
        self.alone = True
        self.writes(keys.key(self.obj, keys.TOUCHING))

    def among(self, kind_targets: Sequence[PlanarPose]) -> None:
        """Make this the Detect of one of several identical parts: the targets of its kind."""
        self.kind_targets = tuple(kind_targets)
        if self.kind_targets:
            self.reads(keys.key(self.obj, keys.TARGET))

    def stages(self, context: Context) -> list[Stage]:
        """Park if needed, then look."""
        context.detector.colours[self.colour]  # raises PerceptionError for an unknown colour
        looking = InstantStage(stage.look_for(self.colour), self._look)
        return [looking] if is_parked(context) else [park_stage(), looking]

    def expected_xy_m(self) -> tuple[float, float] | None:
        """Where the part should be, to look there first; None: search the whole view."""
        return None

    def search_near_m(self) -> float | None:
        """How far from ``expected_xy_m`` the whole view's search may find the part (m); None: anywhere."""
        return None

    def own_target(self) -> PlanarPose | None:
        """The object's target, when the tree has set it."""
        target_key = keys.key(self.obj, keys.TARGET)
        if not self.kind_targets or not self.blackboard.exists(target_key):
            return None
        value = self.blackboard.get(target_key)
        return value if isinstance(value, PlanarPose) else None

    def choose(self, located: tuple[tuple[float, float], ...]) -> tuple[tuple[float, float] | None, str]:
        """Of several parts of the kind: one not at a target of the kind, nearest the own target."""
        free = [xy for xy in located if not at_a_target(xy, self.kind_targets, self.object_type)]
        if not free:
            return None, (
                f"all {len(located)} {self.colour} {self.object_type.name}s lie at targets of their kind: "
                "none left to pick"
            )
        target = self.own_target()
        if target is None:
            return free[0], ""
        return min(free, key=lambda xy: math.hypot(xy[0] - target.x_m, xy[1] - target.y_m)), ""

    def _look(self, context: Context) -> str | None:
        chooser = self.choose if self.kind_targets else None
        frames: list[CameraFrame] | None = [] if self.alone else None
        detection = look(
            context,
            self.colour,
            self.expected_xy_m(),
            self.object_type,
            chooser,
            self.z_m,
            frames=frames,
            near_m=self.search_near_m(),
        )
        if self.alone:
            # Only a blob of several parts of the colour (AMBIGUOUS) may be touching parts; a part not
            # found, or partly covered, is no business of ``Separate``.
            touching = detection.status is DetectionStatus.AMBIGUOUS
            self.write(keys.key(self.obj, keys.TOUCHING), keys.TOUCHING_PARTS if touching else "no")
        if not detection.found or detection.pose_world is None:
            return f"{self.colour} {detection.status.value}: {detection.reason}"
        self.found = detection.pose_world
        self.merged = detection.merged
        self.write(keys.key(self.obj, keys.POSE), detection.pose_world)
        if self.alone and detection.merged:
            self.write(keys.key(self.obj, keys.TOUCHING), keys.TOUCHING_PARTS)
            return (
                f"{self.colour} found in a blob it shares with touching parts of its colour ({detection.reason}): "
                "to be separated before it is picked"
            )
        if frames:
            touching_px = self._touching_px(context, frames, detection.pose_world)
            if touching_px >= MIN_TOUCHING_PX:
                self.write(keys.key(self.obj, keys.TOUCHING), keys.TOUCHING_PARTS)
                return (
                    f"{self.colour} found alone in its blob but touching a part of its colour ({touching_px} px of it "
                    f"within {TOUCH_RING_M * 1000:.0f} mm of its outline, where the pads go down): to be separated "
                    "before it is picked"
                )
        self.on_found(detection.pose_world)
        return None

    def _touching_px(self, context: Context, frames: list[CameraFrame], pose: Pose) -> int:
        """Pixels of the colour just outside the found outline, in the last frame that holds its ring (0: none)."""
        colour = context.detector.colours[self.colour]
        config = context.detector.config
        plane_z_m = config.table_z_m + self.z_m + self.object_type.shape.height_m
        planar = pose.planar()
        for frame in reversed(frames):
            count = touching_pixels(
                frame,
                colour,
                self.object_type.shape.outline_m,
                (planar.x_m, planar.y_m, planar.yaw_rad),
                plane_z_m,
                config.kernel_px,
            )
            if count is not None:
                return count
        return 0

    def on_found(self, pose: Pose) -> None:
        """Hook for subclasses: called with the measured pose."""

    def success_message(self) -> str:
        """Feedback with the measured pose."""
        assert self.found is not None
        planar = self.found.planar()
        return (
            f"{self.colour} at x={fixed(planar.x_m, 4)} m, y={fixed(planar.y_m, 4)} m, "
            f"yaw={fixed(math.degrees(planar.yaw_rad))} deg"
        )


class Inspect(Detect):
    """Detect again and write the offset and the yaw error to the target.

    The keys: ``/<obj>/offset_mm``, ``/<obj>/offset_xy_mm`` and ``/<obj>/yaw_error_deg`` (measured
    minus target yaw, folded to the shape's symmetry).

    Looks through a window around the target first, and searches the whole view only when the
    part is not there. With identical parts (``kind_targets``), Inspect follows the part nearest
    its target: the one this subtree placed.

    ``after_placing=True`` also records the offset as ``/<obj>/placed_offset_mm`` and the yaw error
    as ``/<obj>/placed_yaw_error_deg`` (the paper's "after placing" figures).
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "camera -> /<obj>/pose, /<obj>/offset_mm, /<obj>/yaw_error_deg"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """Detect's ports and ``after_placing`` (BehaviorTree.CPP's ``providedPorts``)."""
        after_placing = Port("after_placing", BOOL, False, "also write /<obj>/placed_offset_mm")
        return (OBJ, COLOUR, after_placing, OBJECT_TYPE_PORT, KIND_TARGETS, Z_PORT, *INSPECT_ENTRIES)

    def __init__(
        self,
        name: str,
        obj: str,
        colour: str | None = None,
        after_placing: bool = False,
        object_type: ObjectType | None = None,
        kind_targets: Sequence[PlanarPose] = (),
        z_m: float = 0.0,
    ) -> None:
        super().__init__(name, obj, colour, object_type, kind_targets, z_m)
        self.after_placing = after_placing
        self.reads(keys.key(obj, keys.TARGET), written_by=keys.TARGET_SETTER)
        self.writes(
            keys.key(obj, keys.OFFSET_MM),
            keys.key(obj, keys.OFFSET_XY_MM),
            keys.key(obj, keys.YAW_ERROR_DEG),
            keys.key(obj, keys.MEASURED_ON),
        )
        if after_placing:
            self.writes(keys.key(obj, keys.PLACED_OFFSET_MM), keys.key(obj, keys.PLACED_YAW_ERROR_DEG))
        self.offset_mm: float | None = None
        self.yaw_error_deg: float | None = None

    def expected_xy_m(self) -> tuple[float, float] | None:
        """The target: a placed or pushed part lies near it."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        return target.x_m, target.y_m

    def choose(self, located: tuple[tuple[float, float], ...]) -> tuple[tuple[float, float] | None, str]:
        """Of several parts of the kind: the one nearest the target (the part this subtree placed)."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        return min(located, key=lambda xy: math.hypot(xy[0] - target.x_m, xy[1] - target.y_m)), ""

    def on_found(self, pose: Pose) -> None:
        """Compare with the target and write the offsets."""
        target: PlanarPose = self.read(keys.key(self.obj, keys.TARGET), "the tree's target setter")
        dx_mm, dy_mm = offset_in_target_frame_mm(target, pose)
        self.offset_mm = math.hypot(dx_mm, dy_mm)
        self.yaw_error_deg = math.degrees(yaw_error_rad(self.object_type.shape, pose.yaw_rad, target.yaw_rad))
        self.write(keys.key(self.obj, keys.OFFSET_MM), self.offset_mm)
        self.write(keys.key(self.obj, keys.OFFSET_XY_MM), (dx_mm, dy_mm))
        self.write(keys.key(self.obj, keys.YAW_ERROR_DEG), self.yaw_error_deg)
        self.write(keys.key(self.obj, keys.MEASURED_ON), keys.FREE_EDGES if self.merged else keys.WHOLE_FACE)
        if self.after_placing:
            self.write(keys.key(self.obj, keys.PLACED_OFFSET_MM), self.offset_mm)
            self.write(keys.key(self.obj, keys.PLACED_YAW_ERROR_DEG), self.yaw_error_deg)

    def _look(self, context: Context) -> str | None:
        failure = super()._look(context)
        if failure is not None:
            # The part's last offset is from before whatever made it unmeasurable now: it no longer
            # confirms the part within (the report says unconfirmed).
            self.write(keys.key(self.obj, keys.MEASURED_ON), keys.NOT_MEASURED)
        return failure

    def success_message(self) -> str:
        """Feedback with the offset."""
        yaw = "unknown" if self.yaw_error_deg is None else fixed(self.yaw_error_deg, sign=True)
        yaw_text = f"yaw error {yaw} deg"
        return f"{super().success_message()}; {yaw_text}; {self.offset_mm:.2f} mm from the target"


class Recheck(Inspect):
    """Look again at a part placed earlier, after a neighbour's release and pushes: did they move it.

    An Inspect (the offset to its target is written afresh, so a correction loop after it pushes
    the part back when it moved beyond the threshold) that also writes how far the part moved
    since it was last looked at, ``/<obj>/moved_mm`` (camera), and the most any later step moved
    it, ``/<obj>/max_moved_mm``. ``after`` names the step whose effect is checked.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "camera -> /<obj>/pose, /<obj>/offset_mm, /<obj>/moved_mm: did a neighbour's step move it"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """Detect's ports and ``after``, the step checked (BehaviorTree.CPP's ``providedPorts``)."""
        after = Port("after", STRING, "", "the step whose effect is checked")
        return (
            OBJ,
            COLOUR,
            after,
            OBJECT_TYPE_PORT,
            KIND_TARGETS,
            Z_PORT,
            *INSPECT_ENTRIES,
            *entries(outputs=(keys.MOVED_MM,), inouts=(keys.MAX_MOVED_MM,)),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        colour: str | None = None,
        after: str = "",
        object_type: ObjectType | None = None,
        kind_targets: Sequence[PlanarPose] = (),
        z_m: float = 0.0,
    ) -> None:
        super().__init__(name, obj, colour, object_type=object_type, kind_targets=kind_targets, z_m=z_m)
        self.after = after
        self.reads(keys.key(obj, keys.POSE), keys.key(obj, keys.MAX_MOVED_MM))
        self.writes(keys.key(obj, keys.MOVED_MM), keys.key(obj, keys.MAX_MOVED_MM))
        self.moved_mm: float | None = None
        self._before: Pose | None = None

    def search_near_m(self) -> float | None:
        """The part's own size: a neighbour's step may shove it, not carry it off.

        Not in the window at its target (its face merged with the new neighbour's), a placed part is
        not another blob of its colour farther off whose outline fits: a 6-piece puzzle (seed 8) so
        "found" a piece 163 mm away, still where it was scattered, and pushed it 123 mm through the others.
        """
        return max(self.object_type.shape.extent_m)

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
