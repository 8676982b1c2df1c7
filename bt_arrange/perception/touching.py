"""Parts of one colour that touch: a neighbour beside a found part, and clusters of touching faces.

Two helpers of the look before a pick and of ``Separate``:

- ``touching_pixels``: how many pixels of the colour's other faces lie within 4 mm of a found
  part's own face (``TOUCH_RING_M``). A neighbour of the colour that touches the part, or nearly,
  fills that ring even where the image shows the seam between them and the mask cuts the faces
  apart; a part scattered alone (12 cm from any other) leaves it empty.
- ``touching_clusters``: the colour's faces joined across seams narrower than ``JOIN_M``, each
  cluster's outline on the plane of the top faces: one outline for parts in contact, whether the
  mask merged their faces or the image showed the seam.

Both read one camera frame and know nothing of the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.perception.colours import ColourRange
from bt_arrange.perception.outline_fit import pixels_on_plane
from bt_arrange.perception.pose import project_world
from bt_arrange.perception.segmentation import colour_mask
from bt_arrange.robot import CameraFrame

#: The ring about a found part's face that a touching neighbour fills (m from the face). 4 mm is past
#: any seam the mask closes and still well inside the window a part is measured in (6 mm beyond its face).
TOUCH_RING_M = 0.004
#: Pixels of the colour in that ring that make a touching neighbour: a contact of 3 mm along the
#: ring's 2.5 mm width at the top camera's 0.5 mm a pixel is 30; a clean ring has none.
MIN_TOUCHING_PX = 30
#: Seams narrower than this (m) join two faces into one cluster: a touching pair's seam is under a
#: pixel; parts the scene scatters lie centimetres apart.
JOIN_M = 0.003


def _px_per_m(frame: CameraFrame, x_m: float, y_m: float, plane_z_m: float) -> float:
    """Pixels a metre on the plane near ``(x, y)`` (the projection of a centimetre there)."""
    points = np.array([[x_m, y_m, plane_z_m], [x_m + 0.01, y_m, plane_z_m]])
    pixels = project_world(frame.intrinsics, frame.camera_pose_world, points)
    return float(np.hypot(*(pixels[1] - pixels[0]))) / 0.01


def touching_pixels(
    frame: CameraFrame,
    colour: ColourRange,
    outline_m: FloatArray,
    pose_xy_yaw: tuple[float, float, float],
    plane_z_m: float,
    kernel_px: int,
) -> int | None:
    """Pixels of other faces of ``colour`` within ``TOUCH_RING_M`` of the part's own face; None off the frame.

    ``outline_m`` is the top face in the part's frame, ``pose_xy_yaw`` where it was found. The part's
    own face is the blob of the colour mask that covers most of its outline projected into the frame
    (a projection that ignores the lens' distortion and the calibration's error lands within pixels
    of it, which choosing the blob forgives); the ring is that blob grown by ``TOUCH_RING_M``, and
    only the colour's other blobs are counted in it. A neighbour merged with the face is no other blob:
    the detector already reports that (AMBIGUOUS, or a fit on free edges).
    """
    x_m, y_m, yaw = pose_xy_yaw
    c, s = math.cos(yaw), math.sin(yaw)
    outline = np.asarray(outline_m, dtype=float) @ np.array([[c, s], [-s, c]]) + np.array([x_m, y_m])
    points = np.column_stack([outline, np.full(len(outline), plane_z_m)])
    pixels = project_world(frame.intrinsics, frame.camera_pose_world, points)
    px_per_m = _px_per_m(frame, x_m, y_m, plane_z_m)
    outer_px = max(1, round(TOUCH_RING_M * px_per_m))
    slack_px = outer_px + 8  # room for the projection's few pixels of error and the ring beyond the face
    height, width = frame.rgb.shape[:2]
    low = np.floor(pixels.min(axis=0)).astype(int) - slack_px
    high = np.ceil(pixels.max(axis=0)).astype(int) + slack_px + 1
    if low[0] < 0 or low[1] < 0 or high[0] > width or high[1] > height:
        return None
    crop = np.ascontiguousarray(frame.rgb[low[1] : high[1], low[0] : high[0]])
    mask = colour_mask(crop, colour, kernel_px)
    count, labels = cv2.connectedComponents((mask > 0).astype(np.uint8))
    if count <= 2:
        return 0  # the face alone (or nothing) in the colour: no neighbour
    outline_mask = np.zeros(mask.shape, np.uint8)
    cv2.fillPoly(outline_mask, [np.round(pixels - low).astype(np.int32)], 1)
    overlap = np.bincount(labels[outline_mask > 0], minlength=count)
    overlap[0] = 0
    own = int(np.argmax(overlap))
    if overlap[own] == 0:
        return None  # no face of the colour where the part was found
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * outer_px + 1, 2 * outer_px + 1))
    ring = cv2.dilate((labels == own).astype(np.uint8), kernel) > 0
    return int(np.count_nonzero(ring & (labels != own) & (labels != 0)))


@dataclass(frozen=True)
class Cluster:
    """Faces of one colour joined across seams narrower than ``JOIN_M``: outline and area on the plane."""

    contour_m: FloatArray
    area_m2: float

    def holds(self, x_m: float, y_m: float, margin_m: float = 0.0) -> bool:
        """True when ``(x, y)`` lies inside the outline or within ``margin_m`` of it."""
        scale = 1e4  # a tenth of a millimetre a unit: pointPolygonTest wants float32 coordinates of some size
        polygon = (self.contour_m * scale).astype(np.float32).reshape(-1, 1, 2)
        distance = cv2.pointPolygonTest(polygon, (float(x_m * scale), float(y_m * scale)), True) / scale
        return bool(distance >= -margin_m)


def touching_clusters(frame: CameraFrame, colour: ColourRange, plane_z_m: float, kernel_px: int) -> list[Cluster]:
    """The clusters of the colour's faces in ``frame`` (see the module), largest first."""
    mask = colour_mask(frame.rgb, colour, kernel_px)
    height, width = frame.rgb.shape[:2]
    centre = pixels_on_plane(frame.intrinsics, frame.camera_pose_world, np.array([[width / 2, height / 2]]), plane_z_m)[
        0
    ]
    join_px = max(1, round(JOIN_M * _px_per_m(frame, float(centre[0]), float(centre[1]), plane_z_m)))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * join_px + 1, 2 * join_px + 1))
    joined = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel)
    contours, _ = cv2.findContours(joined, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    clusters = []
    for contour in contours:
        if len(contour) < 8:
            continue
        on_plane = pixels_on_plane(
            frame.intrinsics, frame.camera_pose_world, contour.reshape(-1, 2).astype(float), plane_z_m
        )
        if not np.all(np.isfinite(on_plane)):
            continue
        area_m2 = abs(float(cv2.contourArea((on_plane * 1e4).astype(np.float32)))) / 1e8
        clusters.append(Cluster(on_plane, area_m2))
    clusters.sort(key=lambda c: -c.area_m2)
    return clusters
