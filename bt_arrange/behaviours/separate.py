"""Separate: push one of several touching parts of a colour aside, so that each can be found and picked alone.

Parts that touch where they start (a real table's parts) are one blob in the colour mask. The
detector tells such parts apart where their outlines allow (a fresco piece found on its free edges,
``bt_arrange.perception.outline_merged``), but two identical cubes side by side are a 2:1 rectangle
that no face of theirs explains, and a part found beside a touching neighbour may have the
neighbour where the pads go down. ``Detect(alone=True)`` (the look before a pick) fails on both,
and the transfer step runs ``Separate`` and looks again (``bt_arrange.trees.steps``).

The push is planned from the cluster alone, without knowing where each part is in it:

1. **The cluster**: the full frame's faces of the colour joined across seams under 3 mm
   (``bt_arrange.perception.touching.touching_clusters``), on the plane of the part's top face. A
   cluster holds several parts when its area is more than a whole face's (the upper end of
   ``face_area_fraction_range``, in this part's faces); the one that holds the pose the Detect
   before wrote (the part found beside a neighbour) comes first, then the largest. A cluster at a
   target the tree has set (placed parts) is never pushed.
2. **The push**: the cluster's principal axes (its second moments) put the parts in a row along the
   major axis. The pads, nearly closed, stand a quarter of the cluster's length in from one end (the
   end part's middle for two parts) on one side of the minor axis, and push across the major axis
   by the cluster's width there plus ``SEPARATION_MARGIN_M``: the end part slides along its
   neighbour's side until a gap opens between them. Of the four (end, side) choices the one whose
   pushed part ends nearest the point under the camera is taken (in view, within reach).

Objects move only through the pads' contact; the motion is planned when its stage starts and
advanced one control period a tick, as every push's is (``Push._motion``).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import py_trees

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import COLOUR, OBJ, OBJECT_TYPE_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.looking import is_parked, park_stage
from bt_arrange.behaviours.moves import heights_m, wrist_yaw_rad
from bt_arrange.behaviours.push import Push
from bt_arrange.geometry import FloatArray, PlanarPose, Pose
from bt_arrange.motion import GRIPPER_SYMMETRY_RAD, nearest_symmetric_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.pose import pixel_on_plane
from bt_arrange.perception.touching import Cluster, touching_clusters
from bt_arrange.ports import Port

#: How far beyond its neighbour's far side (m, across the push) the pushed part ends: a gap the
#: mask never closes (its 7x7 morphology closes about a millimetre) and the open pads fit beside.
SEPARATION_MARGIN_M = 0.015
#: The fingers' opening while they push a touching part aside (m): nearly closed, so both pads meet
#: the end part only, not its neighbour along the blob.
SEPARATION_OPENING_M = 0.010
#: How far in from the blob's end along its major axis the pads push (share of the blob's length):
#: a quarter is the end part's middle for two parts in a row, and inside the end part for three.
PUSH_POINT_FROM_END = 0.25
#: A blob at least this far (m) from every target of the colour is no placed part.
TARGET_CLEARANCE_M = 0.005


class Separate(StagedBehaviour):
    """Push one part of a blob of several touching parts of the colour aside (see the module).

    Fails at once, without moving, when no blob of the colour holds several parts (nothing to
    separate: the Detect before failed for another reason), saying so.
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "push a touching part of the colour aside"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object, its colour and type (BehaviorTree.CPP's ``providedPorts``)."""
        return (OBJ, COLOUR, OBJECT_TYPE_PORT, *entries((keys.POSE,), ()))

    def __init__(
        self,
        name: str,
        obj: str,
        colour: str | None = None,
        object_type: ObjectType | None = None,
    ) -> None:
        super().__init__(name)
        self.obj = obj
        self.colour = colour or obj
        self.object_type = object_type or CUBE
        # Where the Detect before found the part (merged with a neighbour), when it did: optional.
        self.reads(keys.key(obj, keys.POSE))
        #: What the last run did, for the feedback: the push (mm) and the blob's area in faces.
        self.pushed_mm: float | None = None
        self.blob_faces: float | None = None

    def stages(self, context: Context) -> list[Stage]:
        """Park if needed, then look; the look appends the push's stages when it finds a blob to separate."""
        context.detector.colours[self.colour]  # raises PerceptionError for an unknown colour
        looking = InstantStage(stage.LOOK_FOR_TOUCHING, self._look)
        return [looking] if is_parked(context) else [park_stage(), looking]

    def _look(self, context: Context) -> str | None:
        """Find the cluster of several parts and plan the push aside (appended to this run's stages)."""
        detector = context.detector
        frame = context.robot.camera.capture()
        colour = detector.colours[self.colour]
        plane_z_m = detector.config.table_z_m + self.object_type.shape.height_m
        face_m2 = abs(float(cv2.contourArea(np.asarray(self.object_type.shape.outline_m, dtype=np.float32))))
        pose_key = keys.key(self.obj, keys.POSE)
        seen: Pose | None = self.blackboard.get(pose_key) if self.blackboard.exists(pose_key) else None
        several_area = detector.config.face_area_fraction_range[1]
        targets = set_targets()
        best: tuple[float, Cluster] | None = None
        for cluster in touching_clusters(frame, colour, plane_z_m, detector.config.kernel_px):
            if any(cluster.holds(t.x_m, t.y_m, TARGET_CLEARANCE_M) for t in targets):
                continue  # a placed part (or parts): never pushed
            faces = cluster.area_m2 / face_m2
            if faces <= several_area:
                continue  # one part alone
            holds_seen = seen is not None and cluster.holds(seen.x_m, seen.y_m)
            # The cluster that holds the part the Detect saw comes first, then the largest.
            rank = faces + (1000.0 if holds_seen else 0.0)
            if best is None or rank > best[0]:
                best = (rank, cluster)
        if best is None:
            return f"no {self.colour} parts touch each other: nothing to separate"
        cluster = best[1]
        self.blob_faces = cluster.area_m2 / face_m2
        camera_xy = _under_camera(context, plane_z_m)
        plan = plan_separation(cluster.contour_m, context.settings.gripper.pad_thickness_m, camera_xy)
        point, direction, distance_m, face_offset_m = plan
        s = context.settings
        pad_half_depth_m = s.gripper.pad_width_m / 2
        # The pads' centre starts a clearance outside the face and ends the push's distance in.
        contact = point - direction * (face_offset_m + pad_half_depth_m)
        begin = contact - direction * s.push_clearance_m
        end = contact + direction * distance_m
        back = end - direction * s.push_clearance_m
        heading = math.atan2(direction[1], direction[0])
        yaw = nearest_symmetric_yaw(heading + math.pi / 2, wrist_yaw_rad(context), GRIPPER_SYMMETRY_RAD)
        _, approach_m, push_m = heights_m(s, self.object_type)
        self.pushed_mm = distance_m * 1000
        self._stages.extend(
            Push._motion(SEPARATION_OPENING_M, begin, end, back, (approach_m, push_m), yaw, stage.PUSH_ASIDE)
        )
        return None

    def success_message(self) -> str:
        """What was separated and how far it was pushed."""
        return (
            f"pushed one of the touching {self.colour} parts aside by {self.pushed_mm:.0f} mm (their blob as large as "
            f"{self.blob_faces:.1f} {self.object_type.name} faces): touching parts of one colour, separated to be "
            "picked one by one"
        )


def set_targets() -> list[PlanarPose]:
    """Every part's target the tree has set so far (``/<obj>/target``): where placed parts lie.

    Read from the whole blackboard rather than through declared keys: which parts share a colour with
    this one, and are placed by now, is the run's business, not the part's subtree's (its XML
    definition is shared by every part). A part waiting to be picked starts clear of every target
    (the plan check's start clearance), so a cluster holding one is a placed part.
    """
    suffix = "/" + keys.TARGET
    return [
        value
        for name, value in py_trees.blackboard.Blackboard.storage.items()
        if name.endswith(suffix) and isinstance(value, PlanarPose)
    ]


def _under_camera(context: Context, plane_z_m: float) -> FloatArray:
    """The point of the plane at the image's centre: a part pushed towards it stays in view and in reach."""
    camera = context.robot.camera
    intrinsics = camera.intrinsics
    centre = np.array([intrinsics.cx_px, intrinsics.cy_px])
    point = pixel_on_plane(intrinsics, camera.pose_world, centre, plane_z_m)
    return np.zeros(2) if point is None else np.asarray(point[:2], dtype=float)


def plan_separation(
    contour_m: FloatArray, pad_thickness_m: float, towards_xy_m: FloatArray
) -> tuple[FloatArray, FloatArray, float, float]:
    """Where and which way to push a blob of touching parts aside (see the module).

    Returns the point on the blob's major axis level with the pads (m, world), the push's unit
    direction, its distance (m: the blob's width there and ``SEPARATION_MARGIN_M``) and how far
    the face the pads meet lies from that point against the push (m). Of both ends and both sides,
    the push whose part ends nearest ``towards_xy_m``.
    """
    contour = np.asarray(contour_m, dtype=float)
    scale = 1e4
    moments = cv2.moments((contour * scale).astype(np.float32).reshape(-1, 1, 2))
    area = moments["m00"]
    centre = np.array([moments["m10"] / area, moments["m01"] / area]) / scale
    # The second central moments' principal direction: the parts lie in a row along it.
    angle = 0.5 * math.atan2(2 * moments["mu11"], moments["mu20"] - moments["mu02"])
    major = np.array([math.cos(angle), math.sin(angle)])
    minor = np.array([-major[1], major[0]])
    along = (contour - centre) @ major
    across = (contour - centre) @ minor
    length_m = float(along.max() - along.min())
    half_span_m = SEPARATION_OPENING_M / 2 + pad_thickness_m
    best: tuple[float, tuple[FloatArray, FloatArray, float, float]] | None = None
    for end in (along.max(), along.min()):
        at_m = float(end - math.copysign(PUSH_POINT_FROM_END * length_m, end))
        level = np.abs(along - at_m) <= half_span_m
        if not level.any():
            continue
        high_m, low_m = float(across[level].max()), float(across[level].min())
        width_m = high_m - low_m
        point = centre + at_m * major
        for side, face_offset_m in ((1.0, high_m), (-1.0, -low_m)):
            # Pads on ``side`` push towards the other: the face they meet lies ``face_offset_m`` out.
            direction = -side * minor
            distance_m = width_m + SEPARATION_MARGIN_M
            part_end = point + direction * distance_m
            score = float(np.hypot(*(part_end - towards_xy_m)))
            if best is None or score < best[0]:
                best = (score, (point, direction, distance_m, face_offset_m))
    if best is None:
        raise ValueError("the blob has no contour level with its major axis' quarter points")
    return best[1]
