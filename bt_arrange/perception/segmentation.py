"""Segmentation: colour masks, blobs, contours and the top face's four corners.

The paper's steps: an HSV threshold per colour, a 7x7 closing and opening, contours by
Suzuki-Abe (``cv2.findContours``), the polygon by Douglas-Peucker (``cv2.approxPolyDP``), and
the corners in a sorted order. For speed the search for blobs runs on a downscaled image, and
the paper's steps then run at full resolution on a crop around each blob.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.geometry import FloatArray
from bt_arrange.perception.colours import ColourRange, Mask

#: The paper's structuring element for the closing and the opening, at full resolution.
PAPER_KERNEL_PX = 7


def to_hsv(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """8-bit HSV (hue 0..179) of an RGB image."""
    return np.asarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV), dtype=np.uint8)


def clean_mask(mask: Mask, kernel_px: int = PAPER_KERNEL_PX) -> Mask:
    """Close small holes, then open away specks, with a ``kernel_px`` x ``kernel_px`` disc.

    A disc, not a square: the opening with a 7x7 square cuts 3.5 px off each corner of a face
    turned by 45 degrees and none off an upright one, a disc rounds every yaw alike (by 1.2 px).
    """
    if kernel_px <= 1:
        return mask
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kernel_px, kernel_px))
    closed = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel)
    cleaned = np.asarray(cv2.morphologyEx(closed, cv2.MORPH_OPEN, kernel), dtype=np.uint8)
    return _keep_gaps(mask, cleaned, np.asarray(kernel, dtype=np.uint8))


def _keep_gaps(mask: Mask, cleaned: Mask, kernel: NDArray[np.uint8]) -> Mask:
    """Undo the closing's bridges between faces.

    Where two separate regions of the eroded mask come within a kernel of each other, take the
    opened mask instead of the closed one, and cut it along the gap's middle where the gap shows.

    A closing fills any gap narrower than its kernel, so two faces of one colour 2 mm (4 px)
    apart would become one blob. Each pixel belongs to the nearest region of the eroded mask
    (``cv2.distanceTransformWithLabels``, one label per region); where the labels of adjacent
    pixels differ lies the middle of a gap, and a kernel around it keeps the real gap. A gap
    under a millimetre (a pixel or two) survives the opening only as a line a diagonal step
    crosses, so two regions whose gap's middle mostly holds no pixel of the colour are cut apart
    along all of it by three pixels: a line no 8-connected region crosses (``_gap_cut``). A neck
    of one face that the erosion parted is of the colour along its middle, and is not cut.
    """
    eroded = cv2.erode(mask, kernel)
    count, _ = cv2.connectedComponents(eroded, connectivity=8)
    if count <= 2:  # background and at most one region: nothing to keep apart
        return cleaned
    opened = np.asarray(cv2.dilate(eroded, kernel), dtype=np.uint8)
    background = np.where(eroded > 0, 0, 1).astype(np.uint8)
    _, nearest = cv2.distanceTransformWithLabels(background, cv2.DIST_L2, 3, labelType=cv2.DIST_LABEL_CCOMP)
    boundary = np.zeros(mask.shape, dtype=np.uint8)
    across = nearest[:, 1:] != nearest[:, :-1]
    down = nearest[1:, :] != nearest[:-1, :]
    boundary[:, 1:] |= across.astype(np.uint8)
    boundary[1:, :] |= down.astype(np.uint8)
    near_gap = cv2.dilate(boundary, kernel) > 0
    kept = np.where(near_gap, opened, cleaned).astype(np.uint8)
    cut = _gap_cut(mask, np.asarray(nearest, dtype=np.int32), across, down)
    if cut is not None:
        kept[cv2.dilate(cut, np.ones((3, 3), np.uint8)) > 0] = 0
    return kept


#: Two regions are cut apart along the middle of their gap when this share of it holds no pixel of the
#: colour: a gap the image shows, not a neck of one face (all colour) nor a seam it blurs (a few pixels).
GAP_CUT_SHARE = 0.6


def _gap_cut(mask: Mask, nearest: NDArray[np.int32], across: NDArray[np.bool_], down: NDArray[np.bool_]) -> Mask | None:
    """The middles of the gaps between regions (label pairs) that the image shows as a gap, or None."""
    rows_a, cols_a = np.nonzero(across)
    rows_d, cols_d = np.nonzero(down)
    rows = np.concatenate([rows_a, rows_d])
    cols = np.concatenate([cols_a + 1, cols_d])
    first = np.concatenate([nearest[rows_a, cols_a], nearest[rows_d, cols_d]])
    second = np.concatenate([nearest[rows_a, cols_a + 1], nearest[rows_d + 1, cols_d]])
    pair = np.minimum(first, second).astype(np.int64) * (int(nearest.max()) + 1) + np.maximum(first, second)
    # A pixel off the colour within a pixel of the middle: an aliased gap's line is a pixel wide, and
    # the middle of the regions' gap may lie beside it.
    empty = cv2.erode(mask, np.ones((3, 3), np.uint8))[rows, cols] == 0
    pairs, index = np.unique(pair, return_inverse=True)
    share = np.bincount(index, weights=empty.astype(float), minlength=len(pairs)) / np.bincount(
        index, minlength=len(pairs)
    )
    cutting = share[index] >= GAP_CUT_SHARE
    if not cutting.any():
        return None
    cut = np.zeros(mask.shape, dtype=np.uint8)
    cut[rows[cutting], cols[cutting]] = 1
    return cut


def colour_mask(rgb: NDArray[np.uint8], colour: ColourRange, kernel_px: int = PAPER_KERNEL_PX) -> Mask:
    """The paper's segmentation of one colour: HSV threshold, then closing and opening."""
    return clean_mask(colour.mask(to_hsv(rgb)), kernel_px)


@dataclass(frozen=True)
class Blob:
    """A connected region of one colour, in full-resolution pixel coordinates.

    ``bbox_px`` is ``(x, y, width, height)``; ``area_px`` is the pixel count scaled back from
    the downscaled search image, so it is approximate.
    """

    area_px: float
    centroid_px: tuple[float, float]
    bbox_px: tuple[int, int, int, int]


def find_blobs(mask: Mask, scale: int, min_area_px: float) -> list[Blob]:
    """Connected regions of a (downscaled) mask at least ``min_area_px`` large at full resolution.

    ``scale`` is the downscaling factor of ``mask``: coordinates and areas are mapped back to
    the full-resolution image. Blobs are returned largest first.
    """
    count, _, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    blobs = []
    for label in range(1, count):
        x, y, w, h, area = (int(v) for v in stats[label])
        area_px = float(area) * scale * scale
        if area_px < min_area_px:
            continue
        cu, cv = centroids[label]
        # A downscaled pixel (i, j) covers full-resolution pixels scale*i .. scale*i + scale - 1.
        centroid = ((cu + 0.5) * scale - 0.5, (cv + 0.5) * scale - 0.5)
        blobs.append(Blob(area_px, centroid, (x * scale, y * scale, w * scale, h * scale)))
    blobs.sort(key=lambda b: -b.area_px)
    return blobs


def largest_contour(mask: Mask) -> NDArray[np.int32] | None:
    """The outer contour (Suzuki-Abe) with the largest area, as an Nx2 array, or None."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return None
    contour = max(contours, key=cv2.contourArea)
    return np.asarray(contour, dtype=np.int32).reshape(-1, 2)


def approximate_quadrilateral(
    contour: NDArray[np.int32], epsilon_fractions: tuple[float, ...] = (0.02, 0.03, 0.04, 0.05)
) -> NDArray[np.int32]:
    """Douglas-Peucker polygon of a contour with the fewest vertices down to four.

    Tries growing tolerances (fractions of the perimeter) and stops at the first polygon with
    at most four vertices; a square face gives four, a covered or cut face may give more or
    fewer, which the caller reports.
    """
    perimeter_px = cv2.arcLength(contour.reshape(-1, 1, 2), True)
    polygon = contour
    for fraction in epsilon_fractions:
        approximation = cv2.approxPolyDP(contour.reshape(-1, 1, 2), fraction * perimeter_px, True)
        polygon = np.asarray(approximation, dtype=np.int32).reshape(-1, 2)
        if len(polygon) <= 4:
            break
    return np.asarray(polygon, dtype=np.int32)


def order_corners(corners_px: NDArray[np.floating] | NDArray[np.integer]) -> FloatArray:
    """Four corners in a fixed order: clockwise on screen, starting nearest the image's top left.

    Clockwise on screen (x right, y down) is the order of the object points of
    ``cv2.SOLVEPNP_IPPE_SQUARE`` for a square seen from the front; which corner comes first only
    turns the face frame by a multiple of 90 degrees, which the cube's symmetry makes irrelevant.
    """
    points = np.asarray(corners_px, dtype=float).reshape(4, 2)
    centre = points.mean(axis=0)
    # Angles measured in image coordinates grow clockwise on screen.
    angles = np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0])
    points = points[np.argsort(angles)]
    start = int(np.argmin(points[:, 0] + points[:, 1]))
    return np.roll(points, -start, axis=0)


def outline_deviation_px(contour_px: NDArray[np.integer], polygon_px: FloatArray) -> float:
    """Largest distance, in pixels, from a contour's points to the sides of a closed polygon."""
    points = np.asarray(contour_px, dtype=float).reshape(-1, 2)
    polygon = np.asarray(polygon_px, dtype=float).reshape(-1, 2)
    distance = np.full(len(points), np.inf)
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        ab = b - a
        t = np.clip((points - a) @ ab / float(ab @ ab), 0.0, 1.0)
        distance = np.minimum(distance, np.linalg.norm(points - (a + t[:, None] * ab), axis=1))
    return float(distance.max()) if len(points) else 0.0
