"""The detector's value types: what it is told and what it answers.

``DetectorConfig`` and ``WorldRegion`` go in, ``Detection`` and ``DetectionStatus`` come out.

Outcomes are values, never exceptions: a behaviour reads ``status`` and puts ``reason`` into its
feedback message. The pipeline that makes them is ``bt_arrange.perception.detection``.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PerceptionError
from bt_arrange.geometry import FloatArray, PlanarPose, Pose
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.corners import CornerRefinement, Undistort
from bt_arrange.perception.pose import PoseModel, expected_face_area_px, expected_outline_area_px
from bt_arrange.perception.segmentation import PAPER_KERNEL_PX
from bt_arrange.robot import CameraIntrinsics


class DetectionStatus(str, enum.Enum):
    """What a detection of one colour found."""

    #: Exactly one whole face of the colour: ``pose_world`` is set.
    FOUND = "found"
    #: No blob of the colour large enough to be a face (in the region of interest, if one was given).
    NOT_FOUND = "not_found"
    #: More than one blob of the colour, or one blob as large as several faces.
    AMBIGUOUS = "ambiguous"
    #: One blob that is not a whole face: cut by the image border, covered, or not a 5 cm square.
    PARTIAL = "partial"
    #: Prisms only: a whole face of the colour whose outline is not the part's (another part of
    #: that colour, or one whose outline is not known).
    WRONG_OUTLINE = "wrong_outline"


@dataclass(frozen=True)
class WorldRegion:
    """An axis-aligned rectangle on the table, in world metres: a region of interest."""

    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float

    def __post_init__(self) -> None:
        if not (self.x_min_m < self.x_max_m and self.y_min_m < self.y_max_m):
            raise PerceptionError(f"empty region of interest: {self}")

    @classmethod
    def around(cls, x_m: float, y_m: float, half_size_m: float) -> WorldRegion:
        """A square region of ``2 * half_size_m`` centred at ``(x, y)``."""
        return cls(x_m - half_size_m, x_m + half_size_m, y_m - half_size_m, y_m + half_size_m)

    @property
    def centre_m(self) -> tuple[float, float]:
        """The region's centre (x, y): where a part looked for around a place is expected."""
        return (0.5 * (self.x_min_m + self.x_max_m), 0.5 * (self.y_min_m + self.y_max_m))

    def contains(self, x_m: float, y_m: float) -> bool:
        """True when ``(x, y)`` lies inside the region (borders included)."""
        return self.x_min_m <= x_m <= self.x_max_m and self.y_min_m <= y_m <= self.y_max_m


@dataclass(frozen=True)
class DetectorConfig:
    """Everything the detector assumes about the parts and how strict it is.

    Areas are fractions of the expected image area of one top face, derived per blob from the
    intrinsics, the camera pose and the height of the top faces (``table_z_m`` + the part's height).
    """

    #: The part looked for: a cuboid, whose top face (x by y) stands its height above the table,
    #: or a prism, whose top face is its outline (registered by ``bt_arrange.perception.outline``)
    #: (``PartDetector.for_object`` sets it; the paper's cube by default).
    part: ObjectType = CUBE
    #: World z of the table top; the top faces lie the part's height above it.
    table_z_m: float = 0.0
    #: The paper's 7x7 closing and opening, applied at full resolution.
    kernel_px: int = PAPER_KERNEL_PX
    #: Blobs smaller than this are specks, not parts, and are ignored.
    min_area_fraction: float = 0.25
    #: A whole, uncovered face: anything outside is PARTIAL.
    face_area_fraction_range: tuple[float, float] = (0.8, 1.25)
    #: A single blob this large holds several faces of one colour: AMBIGUOUS.
    ambiguous_area_fraction: float = 1.6
    #: Each side of the outline, relative to the expected edge length in pixels.
    side_length_fraction_range: tuple[float, float] = (0.85, 1.15)
    #: The contour may stray this far from the quadrilateral of its side lines: a whole face
    #: strays about 2 px (the rounded corners of the mask), a notch deeper than this (a
    #: covered corner) makes the face PARTIAL. Shallower ones do not touch the measured edges.
    max_outline_deviation_px: float = 4.0
    #: A larger RMS reprojection error means the corners are not those of the part's top face.
    max_reprojection_error_px: float = 1.0
    #: RESTING only: the face's size on the top-face plane may differ this much from the edge;
    #: more means the part is not resting on the table (lifted, stacked, tipped) or not of ``part``'s size.
    max_edge_error_fraction: float = 0.04
    pose_model: PoseModel = PoseModel.RESTING
    corner_refinement: CornerRefinement = CornerRefinement.EDGE_LINES
    #: The blob search runs on the image downscaled so that a face is about this wide.
    coarse_face_edge_px: float = 24.0

    @property
    def size_m(self) -> tuple[float, float, float]:
        """The part's size (x, y, z)."""
        return self.part.size_m

    @property
    def square_top(self) -> bool:
        """True when the top face is a square (within 0.5 mm)."""
        return self.part.shape.square_top

    @property
    def symmetry_rad(self) -> float:
        """The turns that show the same face: 90 degrees for a square, 180 for a rectangle."""
        return self.part.shape.symmetry_rad

    @property
    def face_text(self) -> str:
        """The top face in words: ``5.0 cm square`` or ``8.0 x 4.0 cm rectangle``."""
        if not self.part.shape.rectangular:
            return f"{self.part.name} outline"
        x, y, _ = self.size_m
        return f"{x * 100:.0f} cm square" if self.square_top else f"{x * 100:.1f} x {y * 100:.1f} cm rectangle"

    def face_area_px(self, intrinsics: CameraIntrinsics, T_W_C: Pose, centre_world: FloatArray) -> float:
        """Image area of one top face centred at ``centre_world`` (level, axis-aligned), pixels."""
        shape = self.part.shape
        if not shape.rectangular:
            return expected_outline_area_px(intrinsics, T_W_C, centre_world, shape.outline_m)
        x, y, _ = self.size_m
        return expected_face_area_px(intrinsics, T_W_C, centre_world, x, y)

    @property
    def top_z_m(self) -> float:
        """World z of the parts' top faces."""
        return self.table_z_m + self.size_m[2]


@dataclass(frozen=True)
class Detection:
    """The outcome of looking for one colour in one frame.

    ``pose_world`` is ``T_W_O`` of the part's centre (set only when FOUND) from the configured
    :class:`PoseModel`, its yaw folded into ``[-45, 45)`` degrees (``[-90, 90)`` for a rectangle). Quality figures:
    ``corners_px``, the refined top-face corners (undistorted pixel coordinates);
    ``reprojection_error_px``, the RMS distance between them and the model's projected face;
    ``area_px``, the blob's area, and ``expected_area_px``, a face's expected area there;
    ``edge_m``, the face's edge as measured on the plane of the top faces; ``pnp_pose_world``
    and ``tilt_deg``, the paper's 6-DoF PnP pose and the angle between its up axis and the
    world's. ``candidates_xy_m`` lists where on the table the blobs of this colour were, e.g.
    the two of an AMBIGUOUS outcome.
    """

    colour: str
    status: DetectionStatus
    reason: str
    pose_world: Pose | None = None
    corners_px: FloatArray | None = None
    reprojection_error_px: float | None = None
    area_px: float | None = None
    expected_area_px: float | None = None
    tilt_deg: float | None = None
    edge_m: float | None = None
    pnp_pose_world: Pose | None = None
    candidates_xy_m: tuple[tuple[float, float], ...] = field(default_factory=tuple)
    #: The face merged with another of its colour and was measured on its free edges only: a
    #: measurement the camera's margin does not cover (a neighbour's edge can pass for its own),
    #: so it can steer a push but not confirm "within" (``keys.MEASURED_ON``).
    merged: bool = False

    @property
    def found(self) -> bool:
        """True when the part was found and ``pose_world`` is set."""
        return self.status is DetectionStatus.FOUND

    @property
    def planar(self) -> PlanarPose | None:
        """x, y and folded yaw of the part's centre on the table, when found."""
        return None if self.pose_world is None else self.pose_world.planar()


@dataclass(frozen=True)
class PreparedView:
    """One frame, prepared once for any number of colours: what the detectors' stages share."""

    rgb: NDArray[np.uint8]
    intrinsics: CameraIntrinsics
    T_W_C: Pose
    scale: int
    hsv_small: NDArray[np.uint8]
    min_blob_area_px: float
    undistort: Undistort | None
