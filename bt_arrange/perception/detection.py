"""The part detector: a camera frame and a colour in, a :class:`Detection` out.

Outcomes are values, never exceptions: a behaviour reads ``status`` and puts ``reason`` into
its feedback message. Only configuration mistakes raise
:class:`~bt_arrange.errors.PerceptionError` (a colour not in the table, an image that does not
match its intrinsics).

The detector is a pure function of the frame: it keeps no state between calls and knows
nothing of the simulator.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import replace
from typing import TYPE_CHECKING

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.deprecation import renamed_attributes
from bt_arrange.errors import PerceptionError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.numbers import fixed
from bt_arrange.objects import ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.perception.corners import (
    CornerRefinement,
    refine_contour_lines,
    refine_corner_subpix,
    refine_edge_lines,
)
from bt_arrange.perception.pose import (
    PoseModel,
    fit_square_on_plane,
    part_centre_in_world,
    pixel_on_plane,
    project_world,
    solve_face_pose,
    tilt_deg,
    undistorted,
)
from bt_arrange.perception.segmentation import (
    Blob,
    approximate_quadrilateral,
    clean_mask,
    colour_mask,
    find_blobs,
    order_corners,
    outline_deviation_px,
    to_hsv,
)
from bt_arrange.perception.values import Detection, DetectionStatus, DetectorConfig, PreparedView, WorldRegion
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow

#: A box's outcomes that a twin touching it may cause (merged blob, a side not measurable): the
#: outline registration is tried there (``PartDetector._on_free_edges``).
_TWIN_STATUSES = (DetectionStatus.PARTIAL, DetectionStatus.AMBIGUOUS)


def _format_xy(points: Iterable[tuple[float, float]]) -> str:
    return ", ".join(f"({x:.3f}, {y:.3f})" for x, y in points)


class _Rejected(Exception):
    """A check of ``PartDetector._measure`` the blob failed: the outcome's status and reason."""

    def __init__(self, reason: str, status: DetectionStatus = DetectionStatus.PARTIAL) -> None:
        super().__init__(reason)
        self.reason = reason
        self.status = status


class PartDetector:
    """Finds coloured parts' top faces in a camera frame and estimates their poses.

    ``detect(frame, "red")`` looks for one colour, ``detect_all(frame)`` for every colour of the
    table; both accept a :class:`WorldRegion` to look only at blobs whose centre lies inside.
    """

    def __init__(self, colours: ColourTable = DEFAULT_COLOUR_TABLE, config: DetectorConfig | None = None) -> None:
        self.colours = colours
        self.config = config or DetectorConfig()

    def for_object(self, object_type: object | None) -> PartDetector:
        """A detector like this one for parts of ``object_type`` (an ``ObjectType``; None or the same shape: itself)."""
        if not isinstance(object_type, ObjectType) or object_type.shape == self.config.part.shape:
            return self
        return PartDetector(self.colours, replace(self.config, part=object_type))

    def detect(self, frame: CameraFrame, colour: str, roi: WorldRegion | None = None) -> Detection:
        """Look for the part of ``colour``; raises PerceptionError for a colour not in the table."""
        colour_range = self.colours[colour]
        return self._detect(self._prepare(frame), colour_range, roi)

    def detect_all(self, frame: CameraFrame, roi: WorldRegion | None = None) -> dict[str, Detection]:
        """Look for the part of every colour in the table, in table order."""
        view = self._prepare(frame)
        return {name: self._detect(view, colour_range, roi) for name, colour_range in self.colours.items()}

    def locate(
        self, frame: CameraFrame, colour: str, roi: WorldRegion | None = None
    ) -> tuple[tuple[float, float], ...]:
        """Where on the table (world x, y in metres) the blobs of ``colour`` large enough to be faces are.

        The blob search of :meth:`detect` alone, without the full-resolution measurement: cheap on
        a low-resolution frame (``PixelWindow.full(intrinsics, binning=8)``), to choose a window to
        measure in. Centres are accurate to about a pixel of ``frame``.
        """
        found, _ = self.candidates(self._prepare(frame), self.colours[colour], roi)
        return tuple((float(p[0]), float(p[1])) for _, p, _ in found)

    def search_binning(self, intrinsics: CameraIntrinsics, T_W_C: Pose, face_edge_px: float = 12.0) -> int:
        """Binning of a full view in which a face at the image centre is about ``face_edge_px`` wide.

        Such a view is enough for :meth:`locate`, at a fraction of the pixels: 8 for the
        simulated 1920 x 1080 camera 70 cm above the table (faces about 105 px wide).
        """
        centre = pixel_on_plane(intrinsics, T_W_C, np.array([intrinsics.cx_px, intrinsics.cy_px]), self.config.top_z_m)
        if centre is None:
            raise PerceptionError(f"the camera at {T_W_C} does not look down at the table plane")
        x_m, y_m, _ = self.config.size_m
        edge_px = math.sqrt(self.config.face_area_px(intrinsics, T_W_C, centre) * min(x_m, y_m) / max(x_m, y_m))
        return max(1, int(edge_px // face_edge_px))

    def window_around(
        self, intrinsics: CameraIntrinsics, T_W_C: Pose, x_m: float, y_m: float, half_size_m: float
    ) -> PixelWindow | None:
        """The full-resolution window that sees the square of ``2 * half_size_m`` around ``(x, y)``.

        The square lies on the plane of the top faces; the window is cut to the image, and None
        when the square is outside it. Half a face's diagonal plus the uncertainty of ``(x, y)``
        holds the whole face and the pixels beyond its edges that the sub-pixel fit reads.
        """
        h = half_size_m
        z = self.config.top_z_m
        square = np.array([[x_m - h, y_m - h, z], [x_m + h, y_m - h, z], [x_m + h, y_m + h, z], [x_m - h, y_m + h, z]])
        in_camera = (square - T_W_C.position_m) @ T_W_C.rotation
        if np.any(in_camera[:, 2] <= 0):
            return None
        pixels = project_world(intrinsics, T_W_C, square)
        return PixelWindow.covering(
            intrinsics, pixels[:, 0].min(), pixels[:, 1].min(), pixels[:, 0].max(), pixels[:, 1].max()
        )

    # -- stages ----------------------------------------------------------------------------

    def _prepare(self, frame: CameraFrame) -> PreparedView:
        rgb, intrinsics = frame.rgb, frame.intrinsics
        if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
            raise PerceptionError(f"expected an RGB uint8 image (H x W x 3), got {rgb.dtype} {rgb.shape}")
        if rgb.shape[:2] != (intrinsics.height_px, intrinsics.width_px):
            raise PerceptionError(
                f"image is {rgb.shape[1]}x{rgb.shape[0]} px but the intrinsics say "
                f"{intrinsics.width_px}x{intrinsics.height_px} px"
            )
        T_W_C = frame.camera_pose_world
        config = self.config
        centre_px = np.array([intrinsics.cx_px, intrinsics.cy_px])
        on_table = pixel_on_plane(intrinsics, T_W_C, centre_px, config.top_z_m)
        if on_table is None:
            raise PerceptionError(f"the camera at {T_W_C} does not look down at the table plane z = {config.top_z_m} m")
        # The smallest face anywhere in the image sets the speck threshold; the image corners
        # see the table farthest away.
        height, width = rgb.shape[:2]
        areas = []
        for pixel in ([0, 0], [width - 1, 0], [0, height - 1], [width - 1, height - 1], centre_px):
            point = pixel_on_plane(intrinsics, T_W_C, np.asarray(pixel, dtype=float), config.top_z_m)
            if point is not None:
                areas.append(config.face_area_px(intrinsics, T_W_C, point))
        # The face's shorter side sets the downscaling, so a narrow face keeps enough pixels across.
        x_m, y_m, _ = config.size_m
        centre_edge_px = math.sqrt(config.face_area_px(intrinsics, T_W_C, on_table) * min(x_m, y_m) / max(x_m, y_m))
        scale = int(np.clip(centre_edge_px // config.coarse_face_edge_px, 1, 8))
        # Downscale by an exact integer factor, so that small and full-resolution pixels align.
        small = rgb[: height // scale * scale, : width // scale * scale]
        if scale > 1:
            small = np.asarray(
                cv2.resize(small, (width // scale, height // scale), interpolation=cv2.INTER_AREA),
                dtype=np.uint8,
            )
        undistort = None
        if any(abs(k) > 0 for k in intrinsics.distortion):

            def undistort(points: FloatArray) -> FloatArray:
                return undistorted(intrinsics, np.asarray(points, dtype=np.float64).reshape(-1, 2))

        return PreparedView(
            rgb, intrinsics, T_W_C, scale, to_hsv(small), config.min_area_fraction * min(areas), undistort
        )

    def candidates(
        self, view: PreparedView, colour: ColourRange, roi: WorldRegion | None
    ) -> tuple[list[tuple[Blob, FloatArray, float]], int]:
        """Blobs of the colour that may be faces, and how many lay outside ``roi``.

        Each candidate is (blob, its centre on the plane of the top faces, a face's expected area there).
        """
        config = self.config
        # The paper's 7x7 kernel is meant for full resolution: scale it with the image.
        coarse_kernel_px = max(3, round(config.kernel_px / view.scale) | 1)
        mask = clean_mask(colour.mask(view.hsv_small), coarse_kernel_px)
        candidates: list[tuple[Blob, FloatArray, float]] = []
        outside_roi = 0
        for blob in self._split_merged(view, colour, find_blobs(mask, view.scale, view.min_blob_area_px)):
            on_plane = pixel_on_plane(view.intrinsics, view.T_W_C, np.asarray(blob.centroid_px), config.top_z_m)
            if on_plane is None:
                continue
            expected_px = config.face_area_px(view.intrinsics, view.T_W_C, on_plane)
            if blob.area_px < config.min_area_fraction * expected_px:
                continue
            if roi is not None and not roi.contains(on_plane[0], on_plane[1]):
                outside_roi += 1
                continue
            candidates.append((blob, on_plane, expected_px))
        return self._join_fragments(candidates), outside_roi

    def _join_fragments(self, candidates: list[tuple[Blob, FloatArray, float]]) -> list[tuple[Blob, FloatArray, float]]:
        """Pieces of one face the coarse cleaning cut apart, joined into one blob.

        In a binned search view the opening erases a strip narrower than its kernel: an L's 20 mm
        arms are 6.7 px wide at a 6x binning, and its face fell apart in two blobs, which read as
        two parts of the colour (``irregular_parts`` at seed 5 lost its ``ell``). Two blobs each
        less than a whole face (``face_area_fraction_range``), together no more than one, whose
        centres lie within the part's sweep diameter, are one: the window at full resolution
        measures it. A whole face is never joined.
        """
        low, high = self.config.face_area_fraction_range
        diameter_m = 2.0 * self.config.part.shape.sweep_radius_m
        joined = list(candidates)
        i = 0
        while i < len(joined):
            first, first_xy, first_px = joined[i]
            for j in range(i + 1, len(joined)):
                second, second_xy, second_px = joined[j]
                if max(first.area_px / first_px, second.area_px / second_px) >= low:
                    continue
                if (first.area_px + second.area_px) / max(first_px, second_px) > high:
                    continue
                if float(np.hypot(*(first_xy[:2] - second_xy[:2]))) > diameter_m:
                    continue
                area = first.area_px + second.area_px
                w1, w2 = first.area_px / area, second.area_px / area
                x0 = min(first.bbox_px[0], second.bbox_px[0])
                y0 = min(first.bbox_px[1], second.bbox_px[1])
                x1 = max(first.bbox_px[0] + first.bbox_px[2], second.bbox_px[0] + second.bbox_px[2])
                y1 = max(first.bbox_px[1] + first.bbox_px[3], second.bbox_px[1] + second.bbox_px[3])
                blob = Blob(
                    area,
                    (
                        w1 * first.centroid_px[0] + w2 * second.centroid_px[0],
                        w1 * first.centroid_px[1] + w2 * second.centroid_px[1],
                    ),
                    (x0, y0, x1 - x0, y1 - y0),
                )
                joined[i] = (blob, w1 * first_xy + w2 * second_xy, max(first_px, second_px))
                del joined[j]
                break
            else:
                i += 1
        return joined

    def _split_merged(self, view: PreparedView, colour: ColourRange, blobs: list[Blob]) -> list[Blob]:
        """Blobs of the downscaled search, a blob larger than a face looked at again at full resolution.

        Two faces of one colour a few pixels apart (identical parts 2 mm apart) merge in the
        downscaled image; the full-resolution mask of that blob's box, whose cleaning keeps gaps
        (``clean_mask``), tells them apart. A blob that stays whole is kept as it was.
        """
        if view.scale == 1:
            return blobs
        height, width = view.rgb.shape[:2]
        split: list[Blob] = []
        for blob in blobs:
            if (
                blob.area_px
                <= self.config.face_area_fraction_range[1] * view.min_blob_area_px / self.config.min_area_fraction
            ):
                split.append(blob)
                continue
            x, y, w, h = blob.bbox_px
            x0, y0 = max(0, x - view.scale), max(0, y - view.scale)
            x1, y1 = min(width, x + w + view.scale), min(height, y + h + view.scale)
            mask = colour_mask(view.rgb[y0:y1, x0:x1], colour, self.config.kernel_px)
            parts = find_blobs(mask, 1, view.min_blob_area_px)
            if len(parts) <= 1:
                split.append(blob)
                continue
            for part in parts:
                px, py, pw, ph = part.bbox_px
                centre = (part.centroid_px[0] + x0, part.centroid_px[1] + y0)
                split.append(Blob(part.area_px, centre, (px + x0, py + y0, pw, ph)))
        split.sort(key=lambda b: -b.area_px)
        return split

    def _detect(self, view: PreparedView, colour: ColourRange, roi: WorldRegion | None) -> Detection:
        if not self.config.part.shape.rectangular:
            # An outline that is no box is registered (bt_arrange.perception.outline), not cornered.
            from bt_arrange.perception.outline import detect_outline

            return detect_outline(self, view, colour, roi)
        config = self.config
        candidates, outside_roi = self.candidates(view, colour, roi)
        xy = tuple((float(p[0]), float(p[1])) for _, p, _ in candidates)
        name = colour.name

        if not candidates:
            where = "in the image" if roi is None else f"inside the region of interest ({outside_roi} outside)"
            return Detection(
                name,
                DetectionStatus.NOT_FOUND,
                f"no {name} blob of at least {config.min_area_fraction:.0%} of a face {where}",
            )
        if len(candidates) > 1:
            return Detection(
                name,
                DetectionStatus.AMBIGUOUS,
                f"{len(candidates)} {name} blobs, at {_format_xy(xy)} m; expected one",
                candidates_xy_m=xy,
            )
        blob, _, expected_px = candidates[0]
        try:
            detection = self._measure(view, colour, blob, expected_px, xy)
            if detection.found or roi is None or detection.status not in _TWIN_STATUSES:
                return detection
            return self._on_free_edges(view, colour, roi) or detection
        except (cv2.error, ValueError, np.linalg.LinAlgError) as error:
            # Degenerate geometry (say, corners that coincide) must not end a run: report it.
            return Detection(
                name,
                DetectionStatus.PARTIAL,
                f"{name} face could not be measured: {type(error).__name__}: {error}",
                expected_area_px=expected_px,
                candidates_xy_m=xy,
            )

    def _on_free_edges(self, view: PreparedView, colour: ColourRange, roi: WorldRegion) -> Detection | None:
        """A box's face beside a twin, found by the outline registration where its corners could not be.

        A box face closer than a pixel or two to another of its colour (a raised cube bumped towards
        its twin in a pyramid's layer) is one blob with it, or its edge facing the twin cannot be
        measured: its corners are not the face's. Where the part is expected (the region's centre),
        its outline is registered on its free edges instead (``outline_merged``, as for a prism);
        None when that finds it neither.
        """
        from bt_arrange.perception.outline import detect_outline

        outlined = detect_outline(self, view, colour, roi)
        return outlined if outlined.found else None

    def _measure(
        self,
        view: PreparedView,
        colour: ColourRange,
        blob: Blob,
        expected_px: float,
        xy: tuple[tuple[float, float], ...],
    ) -> Detection:
        """The paper's pipeline at full resolution on a crop around the one blob, as named checks.

        Each check either passes on what it measured or rejects the blob with a status and a
        reason (``_Rejected``): the face's contour, a whole single face, a square outline,
        sub-pixel corners; then the pose from the corners and its reprojection check.
        """
        name = colour.name
        area_px: float | None = None
        try:
            contour, area_px = self._face_contour(view, colour, blob, expected_px)
            self._check_whole_face(view, name, contour, area_px, expected_px)
            polygon, outline = self._check_square_outline(contour, expected_px)
            corners = self._refine(view, polygon, outline)
            if corners is None:
                raise _Rejected("edges could not be measured below a pixel")
        except _Rejected as rejected:
            reason = rejected.reason if rejected.status is DetectionStatus.AMBIGUOUS else f"{name} {rejected.reason}"
            return Detection(
                name, rejected.status, reason, area_px=area_px, expected_area_px=expected_px, candidates_xy_m=xy
            )
        return self._pose_from_corners(view, name, corners, area_px, expected_px, xy)

    def _face_contour(
        self, view: PreparedView, colour: ColourRange, blob: Blob, expected_px: float
    ) -> tuple[NDArray[np.int32], float]:
        """The blob's outline at full resolution (image pixels) and its area; rejected if it vanished."""
        x_m, y_m, _ = self.config.size_m
        edge_px = math.sqrt(expected_px * min(x_m, y_m) / max(x_m, y_m))
        height, width = view.rgb.shape[:2]
        # The downscaled blob's box is accurate to a few pixels: add room for the sides.
        margin = int(max(12, 0.25 * edge_px)) + view.scale
        x, y, w, h = blob.bbox_px
        x0, y0 = max(0, x - margin), max(0, y - margin)
        x1, y1 = min(width, x + w + margin), min(height, y + h + margin)
        mask = colour_mask(view.rgb[y0:y1, x0:x1], colour, self.config.kernel_px)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        if not contours:
            raise _Rejected("blob vanished at full resolution after the closing and opening")
        # The crop may also catch a piece of another blob: keep the one at this blob's centre.
        centre = (blob.centroid_px[0] - x0, blob.centroid_px[1] - y0)
        contour = max(contours, key=lambda c: (cv2.pointPolygonTest(c, centre, False) >= 0, cv2.contourArea(c)))
        return contour.reshape(-1, 2) + np.array([x0, y0]), float(cv2.contourArea(contour))

    def _check_whole_face(
        self, view: PreparedView, name: str, contour: NDArray[np.int32], area_px: float, expected_px: float
    ) -> None:
        """One whole top face: not cut by the image border, not two faces, not a covered piece of one."""
        height, width = view.rgb.shape[:2]
        touches_border = (
            contour[:, 0].min() <= 0
            or contour[:, 1].min() <= 0
            or contour[:, 0].max() >= width - 1
            or contour[:, 1].max() >= height - 1
        )
        if touches_border:
            raise _Rejected("face is cut by the image border")
        ratio = area_px / expected_px
        if ratio > self.config.ambiguous_area_fraction:
            raise _Rejected(
                f"one {name} blob as large as {ratio:.1f} faces: touching parts of one colour?",
                DetectionStatus.AMBIGUOUS,
            )
        low, high = self.config.face_area_fraction_range
        if not low <= ratio <= high:
            raise _Rejected(f"blob is {ratio:.0%} of a face: covered, or not a whole top face")

    def _check_square_outline(self, contour: NDArray[np.int32], expected_px: float) -> tuple[FloatArray, FloatArray]:
        """Four convex corners, sides of a face's length, a contour that keeps to them: (polygon, outline).

        A rectangle's opposite sides pair up: one pair must match its x edge, the other its y edge.
        """
        config = self.config
        vertices = approximate_quadrilateral(contour)
        if len(vertices) != 4:
            raise _Rejected(f"outline has {len(vertices)} corners, not 4: covered?")
        if not cv2.isContourConvex(vertices.reshape(-1, 1, 2)):
            raise _Rejected("outline is not convex: covered?")
        polygon = order_corners(vertices)
        # Lines through each side's contour pixels: corners within about half a pixel (the
        # polygon's vertices sit up to 3 px inside, on the mask's rounded corners).
        outline = refine_contour_lines(contour, polygon)
        sides_px = np.linalg.norm(outline - np.roll(outline, -1, axis=0), axis=1)
        low, high = config.side_length_fraction_range
        x_m, y_m, _ = config.size_m
        px_per_m = math.sqrt(expected_px / (x_m * y_m))
        expected_x_px, expected_y_px = x_m * px_per_m, y_m * px_per_m
        # Either pair of opposite sides may be the x edges: the assignment that fits better.
        ratios = []
        for first, second in ((expected_x_px, expected_y_px), (expected_y_px, expected_x_px)):
            expected = np.array([first, second, first, second])
            ratios.append(sides_px / expected)
        ratio = min(ratios, key=lambda r: float(np.max(np.abs(r - 1.0))))
        if not (low <= ratio.min() and ratio.max() <= high):
            expected_text = (
                f"{expected_x_px:.0f}" if config.square_top else f"{expected_x_px:.0f} and {expected_y_px:.0f}"
            )
            raise _Rejected(
                f"outline sides {sides_px.min():.0f}..{sides_px.max():.0f} px, "
                f"expected {expected_text}: not a {'square' if config.square_top else config.face_text} face?"
            )
        # Where the contour leaves the quadrilateral, something covers the face (or
        # Douglas-Peucker forced four corners on a shape that has more).
        deviation_px = outline_deviation_px(contour, outline)
        if deviation_px > config.max_outline_deviation_px:
            raise _Rejected(f"outline strays {deviation_px:.1f} px from a quadrilateral: covered?")
        return polygon, outline

    def _pose_from_corners(
        self,
        view: PreparedView,
        name: str,
        corners: FloatArray,
        area_px: float,
        expected_px: float,
        xy: tuple[tuple[float, float], ...],
    ) -> Detection:
        """The part's pose from its four corners (on the table plane, or by PnP), checked by reprojection."""
        config = self.config
        x_m, y_m, z_m = config.size_m
        other = None if config.square_top else y_m
        face = solve_face_pose(corners, view.intrinsics.matrix, x_m, other_edge_m=other)
        pnp_pose = None if face is None else part_centre_in_world(view.T_W_C, face.T_C_F, z_m, config.symmetry_rad)
        plane = fit_square_on_plane(corners, view.intrinsics, view.T_W_C, config.top_z_m, x_m, other)
        # Everything measured so far, as a PARTIAL outcome that the checks below complete.
        measured = Detection(
            name,
            DetectionStatus.PARTIAL,
            "",
            corners_px=corners,
            area_px=area_px,
            expected_area_px=expected_px,
            tilt_deg=None if pnp_pose is None else tilt_deg(pnp_pose),
            edge_m=None if plane is None else plane.edge_m,
            pnp_pose_world=pnp_pose,
            candidates_xy_m=xy,
        )
        if config.pose_model is PoseModel.RESTING:
            if plane is None:
                return replace(measured, reason=f"{name} corners do not meet the table plane")
            if abs(plane.edge_m / x_m - 1.0) > config.max_edge_error_fraction:
                return replace(
                    measured,
                    reason=f"{name} face measures {plane.edge_m * 100:.1f} cm on the table plane, not "
                    f"{x_m * 100:.1f} cm: not resting on the table?",
                )
            pose = Pose.from_planar(plane.centre_m[0], plane.centre_m[1], plane.yaw_rad, config.top_z_m)
            pose = pose @ Pose(np.array([0.0, 0.0, -z_m / 2.0]))
            error_px = plane.reprojection_error_px
        else:
            if face is None or pnp_pose is None:
                return replace(measured, reason=f"{name} corners give no pose (PnP failed)")
            pose, error_px = pnp_pose, face.reprojection_error_px
        if error_px > config.max_reprojection_error_px:
            return replace(
                measured,
                reason=f"{name} corners are not a {config.face_text} (reprojection error {error_px:.2f} px)",
                reprojection_error_px=error_px,
            )
        return replace(
            measured,
            status=DetectionStatus.FOUND,
            reason=f"{name} part at x={fixed(pose.x_m, 4)} m, y={fixed(pose.y_m, 4)} m, "
            f"yaw={fixed(math.degrees(pose.yaw_rad))} deg",
            pose_world=pose,
            reprojection_error_px=error_px,
        )

    def _refine(self, view: PreparedView, polygon: FloatArray, outline: FloatArray) -> FloatArray | None:
        """Corners in undistorted pixel coordinates, by the configured method, or None.

        ``polygon`` holds the Douglas-Peucker vertices and ``outline`` the pixel-level corners
        where the contour's side lines meet; the sub-pixel methods start from the latter.
        """
        method = self.config.corner_refinement
        if method is CornerRefinement.EDGE_LINES:
            refined = refine_edge_lines(view.rgb, outline, view.undistort)
            if refined is None:
                return None
            # The refined corners must stay near the pixel-level ones; far away, a band fitted
            # a neighbour's edge instead.
            reference = outline if view.undistort is None else view.undistort(outline)
            return refined if np.abs(refined - reference).max() <= 3.0 else None
        if method is CornerRefinement.CORNER_SUBPIX:
            corners = refine_corner_subpix(view.rgb, outline)
        elif method is CornerRefinement.CONTOUR_LINES:
            corners = outline
        else:
            corners = polygon
        return corners if view.undistort is None else view.undistort(corners)


# Deprecated: the names that said "cube" for any part, kept one release (CHANGELOG.md).
if TYPE_CHECKING:
    CubeDetector = PartDetector
else:
    __getattr__ = renamed_attributes(__name__, {"CubeDetector": "PartDetector"})
