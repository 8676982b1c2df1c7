"""Perception of outlines: a flat part's top face registered to its known outline.

A prism part (``bt_arrange.shapes.Prism``) has a top face of any simple polygon, convex or not,
at a known height. Its pose on the table (x, y of the area centroid, yaw) is found by
registering that outline to the face seen by the top camera, in three steps:

1. **The face**: the HSV mask of the colour, cleaned as for boxes, at full resolution on a crop
   around the blob; its Suzuki-Abe contour is taken onto the plane of the top faces (each
   pixel's ray meets ``z = table + height``), so the rest works in metres on the table.
2. **Coarse registration**, over the full circle of yaw (over one symmetry turn for a symmetric
   outline): the centre is the area centroid of the contour on the plane; every yaw on a 2
   degree grid is scored by the contour points' robust distance to the outline turned by it; the
   best, and the best of the yaws that are no symmetry turn of it, are refined by point-to-line
   ICP on the contour. The contour's two-sided deviation from the fitted outline, away from the
   corners the morphology rounds, says whether the face is this outline at all (another part,
   covered) and whether the second yaw fits as well (ambiguous).
3. **Sub-pixel edges**: each model edge of the coarse pose is measured below a pixel by the
   box's method (``bt_arrange.perception.corners``: covered fractions unmixed in the chroma
   plane, summed across columns or rows), skipping where a band would reach another edge; the
   points are taken onto the plane and the 3-DoF pose is solved by trimmed least squares on
   their distances to the model's edge lines (Gauss-Newton on x, y and yaw). Two passes, like
   the box's; the second reads the outside colour just beyond the measured edge spread.

Corners are never used: the mask's corners are rounded by the 7x7 morphology (by several
pixels at an acute corner), whereas every edge point between them is measured exactly.

``PartDetector`` hands a prism part's face to ``detect_outline``, so ``Detect`` and ``Inspect``
need nothing new; ``bt_arrange.perception.outline_detector.OutlineDetector`` tells parts of one
colour apart by their outlines. The registration on the table plane is
``bt_arrange.perception.outline_fit``. Perception stays free of the simulator.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np

from bt_arrange.geometry import Pose, fold_yaw
from bt_arrange.perception.colours import ColourRange
from bt_arrange.perception.corners import SHARP_EDGE_SPREAD, CornerRefinement, _median, chroma
from bt_arrange.perception.outline_face import Face, FaceSearch, edge_points, face_of, project, spans_two_directions
from bt_arrange.perception.outline_fit import (
    COARSE_POINTS,
    DISTINCT_YAW_DEG,
    EDGE_PASSES,
    ICP_POINTS,
    MIN_EDGE_POINTS,
    MISFIT_CAP_PX,
    OutlineFit,
    OutlineModel,
    coarse_yaws,
    edge_residuals_m,
    gauss_newton,
    icp,
    outline_deviation_m,
    pixels_on_plane,
    resample,
)
from bt_arrange.perception.outline_merged import find_in_merged, register_in_merged
from bt_arrange.perception.segmentation import Blob
from bt_arrange.perception.values import Detection, DetectionStatus, DetectorConfig, PreparedView, WorldRegion


def register(
    view: PreparedView,
    face: Face,
    model: OutlineModel,
    plane_z_m: float,
    px_per_m: float,
    kernel_px: int,
    method: CornerRefinement = CornerRefinement.EDGE_LINES,
    rival_deviation_px: float | None = None,
    max_deviation_px: float | None = None,
) -> tuple[OutlineFit | None, list[OutlineFit], list[OutlineFit]]:
    """The fine fit of the face, its coarse registrations (best first), and the fine fits of its rivals.

    The coarse registrations are distinct yaws (no symmetry turn of each other) found on the contour.
    Every one whose contour deviation is within ``rival_deviation_px`` (default: only the best) is
    fitted below a pixel; the fine fit returned is the one whose edge points lie closest to the model's
    edges, the others are its rivals (best first). A near-symmetric outline is told apart here, by the
    sub-pixel edges, where the pixel contour cannot tell its yaws apart.

    The fine fit is None when the edges could not be measured below a pixel, and, without measuring
    them, when the best contour strays more than ``max_deviation_px`` from its fit (the face is no
    such outline whatever its edges say: most faces of another part of the colour). ``method`` chooses it
    (for comparison; docs/perception.md has the figures): ``EDGE_LINES``, sub-pixel edge points and
    least squares on the model's edge lines (the default); ``CORNER_SUBPIX``, ``cv2.cornerSubPix``
    at the outline's vertices on the face-coverage image and a rigid fit of the vertices;
    ``CONTOUR_LINES``, the contour's ICP alone; ``NONE``, the contour's centroid and the coarse grid's yaw.
    """
    metre = 1.0 / px_per_m
    points = resample(face.contour_m, COARSE_POINTS)
    rounding_m = 0.5 * kernel_px * metre
    yaws = coarse_yaws(points, face.centroid_m, model, cap_m=6.0 * metre)
    contour_dense = face.contour_m
    icp_points = resample(contour_dense, ICP_POINTS) if len(contour_dense) > ICP_POINTS else contour_dense
    fits: list[OutlineFit] = []
    for yaw in yaws[:3]:
        pose = icp(icp_points, model, (float(face.centroid_m[0]), float(face.centroid_m[1]), yaw), 0.3 * metre)
        folded = fold_yaw(pose[2], model.symmetry_rad)
        pose = (pose[0], pose[1], folded)
        if any(
            abs(fold_yaw(pose[2] - other.yaw_rad, model.symmetry_rad)) < math.radians(DISTINCT_YAW_DEG)
            for other in fits
        ):
            continue
        deviation = outline_deviation_m(contour_dense, model, pose, rounding_m) * px_per_m
        fits.append(OutlineFit(model, pose[0], pose[1], pose[2], deviation))
    fits.sort(key=lambda f: f.deviation_px)
    if not fits:
        return None, fits, []
    best = fits[0]
    if method is CornerRefinement.NONE:
        grid = yaws[0] if yaws else 0.0
        coarse = (float(face.centroid_m[0]), float(face.centroid_m[1]), fold_yaw(grid, model.symmetry_rad))
        return replace(best, x_m=coarse[0], y_m=coarse[1], yaw_rad=coarse[2], rms_px=0.0), fits, []
    if method is CornerRefinement.CONTOUR_LINES:
        return replace(best, rms_px=0.0), fits, []
    if method is CornerRefinement.CORNER_SUBPIX:
        return _corner_fit(view, face, best, plane_z_m, px_per_m), fits, []
    if max_deviation_px is not None and best.deviation_px > max_deviation_px:
        return None, fits, []
    contenders = [best] + [
        fit for fit in fits[1:] if rival_deviation_px is not None and fit.deviation_px <= rival_deviation_px
    ]
    fine_fits = [_edge_fit(view, face, fit, plane_z_m, px_per_m) for fit in contenders]
    measured = sorted((f for f in fine_fits if f is not None), key=lambda f: f.misfit_px or math.inf)
    if not measured:
        return None, fits, []
    return measured[0], fits, measured[1:]


def _edge_fit(
    view: PreparedView, face: Face, coarse: OutlineFit, plane_z_m: float, px_per_m: float
) -> OutlineFit | None:
    """The sub-pixel edge fit from a coarse registration; None when the edges could not be measured."""
    model = coarse.model
    metre = 1.0 / px_per_m
    pose = (coarse.x_m, coarse.y_m, coarse.yaw_rad)
    near_outside_px: float | None = None
    residual = np.empty(0)
    edges = np.empty(0, dtype=np.intp)
    for half_width_px, margin_px in EDGE_PASSES:
        points_m, edges, spread = edge_points(
            view, face, model, pose, plane_z_m, half_width_px, margin_px, near_outside_px
        )
        if len(points_m) < 3 * MIN_EDGE_POINTS or not spans_two_directions(model, edges):
            return None
        pose, residual = gauss_newton(points_m, edges, model, pose, 0.05 * metre)
        excess = max(0.0, float(_median(spread)) - SHARP_EDGE_SPREAD)
        near_outside_px = 1.0 + 4.0 * excess
    rms_px = float(np.sqrt(np.mean(residual**2))) * px_per_m if len(residual) else math.inf
    every_px = np.minimum(np.abs(edge_residuals_m(points_m, edges, model, pose)) * px_per_m, MISFIT_CAP_PX)
    misfit_px = float(np.sqrt(np.mean(every_px**2)))
    yaw = fold_yaw(pose[2], model.symmetry_rad)
    return replace(
        coarse,
        x_m=pose[0],
        y_m=pose[1],
        yaw_rad=yaw,
        rms_px=rms_px,
        edge_points=len(residual),
        misfit_px=misfit_px,
    )


def _corner_fit(
    view: PreparedView, face: Face, coarse: OutlineFit, plane_z_m: float, px_per_m: float
) -> OutlineFit | None:
    """The outline's vertices by ``cv2.cornerSubPix`` on the face-coverage image, and a rigid fit of the model's."""
    model = coarse.model
    posed = model.posed(coarse.x_m, coarse.y_m, coarse.yaw_rad)
    start = project(view, np.column_stack([posed, np.full(len(posed), plane_z_m)]))
    height, width = view.rgb.shape[:2]
    margin = 16
    x0, y0 = np.maximum(np.floor(start.min(axis=0)).astype(int) - margin, 0)
    x1, y1 = np.minimum(np.ceil(start.max(axis=0)).astype(int) + margin + 1, [width, height])
    face_chroma = face.face_chroma
    coverage = (chroma(view.rgb[y0:y1, x0:x1]) @ face_chroma / float(face_chroma @ face_chroma)).astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    seeds = (start - [x0, y0]).astype(np.float32).reshape(-1, 1, 2)
    corners = cv2.cornerSubPix(coverage, seeds, (5, 5), (-1, -1), criteria).reshape(-1, 2).astype(float) + [x0, y0]
    if view.undistort is not None:
        corners = view.undistort(corners)
    measured = pixels_on_plane(view.intrinsics, view.T_W_C, corners, plane_z_m)
    # Procrustes: the rotation that best turns the model's vertices onto the measured ones.
    centre = measured.mean(axis=0)
    model_centre = model.outline_m.mean(axis=0)
    a, b = model.outline_m - model_centre, measured - centre
    yaw = math.atan2(float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])), float(np.sum(a * b)))
    c, s = math.cos(yaw), math.sin(yaw)
    origin = centre - np.array([[c, -s], [s, c]]) @ model_centre
    fitted = model.posed(float(origin[0]), float(origin[1]), yaw)
    rms_px = float(np.sqrt(np.mean(np.sum((fitted - measured) ** 2, axis=1)))) * px_per_m
    return replace(
        coarse,
        x_m=float(origin[0]),
        y_m=float(origin[1]),
        yaw_rad=fold_yaw(yaw, model.symmetry_rad),
        rms_px=rms_px,
        edge_points=len(measured),
    )


# -- outcomes ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Verdict:
    """What one blob is: the model it fits (with the fit), or why it fits none."""

    blob_xy_m: tuple[float, float]
    fit: OutlineFit | None
    status: DetectionStatus
    reason: str
    area_px: float | None = None
    expected_area_px: float | None = None
    #: Found on its free edges in a blob it shares with other parts: the blob is not this part's alone.
    shared: bool = False
    #: Measured on its free edges only (its face merged with another of its colour).
    merged: bool = False


def _judge(
    detector: FaceSearch,
    view: PreparedView,
    colour: ColourRange,
    blob: Blob,
    blob_xy_m: tuple[float, float],
    models: Sequence[OutlineModel],
    prior_xy_m: tuple[float, float] | None = None,
) -> dict[str, _Verdict]:
    """Register every known outline to one blob: what the blob is, for each model by name.

    With ``prior_xy_m`` (where the one model's part is expected), a blob cut by the frame's border or
    as large as two faces may be that part merged with another of its colour: it is registered on
    its free edges (``outline_merged``) before it is called partial or ambiguous.
    """
    config = detector.config
    name = colour.name
    verdicts: dict[str, _Verdict] = {}
    faces: dict[float, Face | None] = {}
    for model in models:
        plane_z_m = config.table_z_m + model.height_m
        if model.height_m not in faces:
            faces[model.height_m] = face_of(detector, view, colour, blob, plane_z_m)
        face = faces[model.height_m]
        if face is None:
            verdicts[model.name] = _Verdict(
                blob_xy_m, None, DetectionStatus.PARTIAL, f"{name} blob vanished at full resolution"
            )
            continue
        centre = np.array([face.centroid_m[0], face.centroid_m[1], plane_z_m])
        expected_px = replace(config, part=model.part).face_area_px(view.intrinsics, view.T_W_C, centre)
        px_per_m = math.sqrt(expected_px / model.area_m2)
        ratio = face.area_px / expected_px
        low, high = config.face_area_fraction_range
        if prior_xy_m is not None and (face.touches_border or ratio > config.ambiguous_area_fraction):
            fit = register_in_merged(view, face, model, plane_z_m, px_per_m, prior_xy_m)
            if fit is not None and fit.rms_px is not None and fit.rms_px <= config.max_reprojection_error_px:
                verdicts[model.name] = _Verdict(
                    blob_xy_m,
                    fit,
                    DetectionStatus.FOUND,
                    f"{name} {model.name} at x={fit.x_m:.4f} m, y={fit.y_m:.4f} m, yaw={math.degrees(fit.yaw_rad):.2f} "
                    "deg, on its free edges (its face merged with another of its colour)",
                    face.area_px,
                    expected_px,
                    merged=True,
                )
                continue
        if prior_xy_m is None and not face.touches_border and ratio > config.ambiguous_area_fraction:
            # No expected place (Detect before picking): where in the blob the outline's free edges fit.
            fit, places = find_in_merged(view, face, model, plane_z_m, px_per_m, config.max_reprojection_error_px)
            if places > 1:
                verdicts[model.name] = _Verdict(
                    blob_xy_m,
                    None,
                    DetectionStatus.AMBIGUOUS,
                    f"one {name} blob as large as {ratio:.1f} {model.name} faces, where its free edges fit at "
                    f"{places} places: touching parts of one colour?",
                    face.area_px,
                    expected_px,
                )
                continue
            if fit is not None:
                verdicts[model.name] = _Verdict(
                    blob_xy_m,
                    fit,
                    DetectionStatus.FOUND,
                    f"{name} {model.name} at x={fit.x_m:.4f} m, y={fit.y_m:.4f} m, yaw={math.degrees(fit.yaw_rad):.2f} "
                    f"deg, on its free edges (one of a blob as large as {ratio:.1f} faces)",
                    face.area_px,
                    expected_px,
                    shared=True,
                )
                continue
        if face.touches_border:
            verdicts[model.name] = _Verdict(
                blob_xy_m, None, DetectionStatus.PARTIAL, f"{name} face is cut by the image border", face.area_px
            )
        elif ratio > config.ambiguous_area_fraction:
            verdicts[model.name] = _Verdict(
                blob_xy_m,
                None,
                DetectionStatus.AMBIGUOUS,
                f"one {name} blob as large as {ratio:.1f} {model.name} faces: touching parts of one colour?",
                face.area_px,
                expected_px,
            )
        elif not low <= ratio <= high:
            verdicts[model.name] = _Verdict(
                blob_xy_m,
                None,
                DetectionStatus.PARTIAL,
                f"{name} blob is {ratio:.0%} of a {model.name} face: covered, or another part?",
                face.area_px,
                expected_px,
            )
        else:
            fine, fits, rivals = register(
                view,
                face,
                model,
                plane_z_m,
                px_per_m,
                config.kernel_px,
                config.corner_refinement,
                rival_deviation_px=config.max_outline_deviation_px,
                max_deviation_px=config.max_outline_deviation_px,
            )
            verdicts[model.name] = _verdict_of_fit(
                name, blob_xy_m, model, fine, fits, rivals, face.area_px, expected_px, config
            )
    return verdicts


def _verdict_of_fit(
    name: str,
    blob_xy_m: tuple[float, float],
    model: OutlineModel,
    fine: OutlineFit | None,
    fits: list[OutlineFit],
    rivals: list[OutlineFit],
    area_px: float,
    expected_px: float,
    config: DetectorConfig,
) -> _Verdict:
    max_deviation_px = config.max_outline_deviation_px
    max_rms_px = config.max_reprojection_error_px
    if not fits:
        return _Verdict(blob_xy_m, None, DetectionStatus.PARTIAL, f"{name} face could not be registered", area_px)
    best = fits[0]
    if best.deviation_px > max_deviation_px:
        return _Verdict(
            blob_xy_m,
            best,
            DetectionStatus.WRONG_OUTLINE,
            f"{name} face is no {model.name} outline (strays {best.deviation_px:.1f} px from the best fit): "
            "another part, or covered?",
            area_px,
            expected_px,
        )
    if fine is not None and rivals and _excess_px(fine, rivals[0]) < MIN_RIVAL_EXCESS_PX:
        second = rivals[0]
        return _Verdict(
            blob_xy_m,
            fine,
            DetectionStatus.AMBIGUOUS,
            f"{name} {model.name} fits at yaw {math.degrees(fine.yaw_rad):.1f} "
            f"and {math.degrees(second.yaw_rad):.1f} deg, its edges nearly as well at both "
            f"({fine.misfit_px:.2f} and {second.misfit_px:.2f} px): too nearly symmetric to tell apart at this "
            "resolution",
            area_px,
            expected_px,
        )
    if fine is None:
        return _Verdict(
            blob_xy_m,
            fits[0],
            DetectionStatus.PARTIAL,
            f"{name} {model.name} edges could not be measured below a pixel",
            area_px,
            expected_px,
        )
    if fine.rms_px is None or fine.rms_px > max_rms_px:
        return _Verdict(
            blob_xy_m,
            fine,
            DetectionStatus.PARTIAL,
            f"{name} edges are not a {model.name} outline (residual {fine.rms_px:.2f} px)",
            area_px,
            expected_px,
        )
    return _Verdict(
        blob_xy_m,
        fine,
        DetectionStatus.FOUND,
        f"{name} {model.name} at x={fine.x_m:.4f} m, y={fine.y_m:.4f} m, yaw={math.degrees(fine.yaw_rad):.2f} deg",
        area_px,
        expected_px,
    )


#: A rival yaw is told apart when its edges misfit this much (px, beyond the best yaw's own misfit, in
#: quadrature) more than the best's: the sub-pixel edges of a wrong yaw stray, those of the right one do not.
#: docs/irregular.md has the figures (0.24 px and more for a near-symmetric outline the plan check lets by).
MIN_RIVAL_EXCESS_PX = 0.12


def _excess_px(fine: OutlineFit, rival: OutlineFit) -> float:
    """How much more (px, in quadrature) the rival yaw's edges misfit than the best yaw's."""
    best_px, rival_px = fine.misfit_px or 0.0, rival.misfit_px or math.inf
    return math.sqrt(max(rival_px**2 - best_px**2, 0.0))


def _detection(colour: str, verdict: _Verdict, xy: tuple[tuple[float, float], ...], table_z_m: float) -> Detection:
    fit = verdict.fit
    pose = None
    if verdict.status is DetectionStatus.FOUND and fit is not None:
        pose = Pose.from_planar(fit.x_m, fit.y_m, fit.yaw_rad, table_z_m + fit.model.height_m / 2)
    return Detection(
        colour,
        verdict.status,
        verdict.reason,
        pose_world=pose,
        reprojection_error_px=None if fit is None else fit.rms_px,
        area_px=verdict.area_px,
        expected_area_px=verdict.expected_area_px,
        candidates_xy_m=xy,
        merged=verdict.merged or verdict.shared,
    )


def detect_outlines(
    detector: FaceSearch,
    view: PreparedView,
    colour: ColourRange,
    roi: WorldRegion | None,
    models: Sequence[OutlineModel],
) -> dict[str, Detection]:
    """For each model (by name), the detection of the one part of ``colour`` with that outline."""
    name = colour.name
    candidates, outside_roi = detector.candidates(view, colour, roi)
    xy = tuple((float(p[0]), float(p[1])) for _, p, _ in candidates)
    if not candidates:
        where = "in the image" if roi is None else f"inside the region of interest ({outside_roi} outside)"
        reason = f"no {name} blob of at least {detector.config.min_area_fraction:.0%} of a face {where}"
        return {m.name: Detection(name, DetectionStatus.NOT_FOUND, reason) for m in models}
    judged: list[dict[str, _Verdict]] = []
    # Where the one part looked for is expected (the region's centre): a face merged with another of its
    # colour is registered on its free edges there. Several parts have no one expected place.
    prior_xy_m = None if roi is None or len(models) != 1 else roi.centre_m
    for blob, on_plane, _ in candidates:
        blob_xy = (float(on_plane[0]), float(on_plane[1]))
        try:
            judged.append(_judge(detector, view, colour, blob, blob_xy, models, prior_xy_m))
        except (cv2.error, ValueError, np.linalg.LinAlgError) as error:
            failed = _Verdict(
                blob_xy,
                None,
                DetectionStatus.PARTIAL,
                f"{name} face could not be measured: {type(error).__name__}: {error}",
            )
            judged.append({m.name: failed for m in models})
    # Each blob is the part whose outline it fits (the closest fit, if it fits several).
    # A blob several parts share (each found on its free edges in it) is each of theirs.
    owners: list[str | None] = []
    for verdicts in judged:
        fitting = [
            (v.fit.deviation_px, n)
            for n, v in verdicts.items()
            if v.status is DetectionStatus.FOUND and v.fit and not v.shared
        ]
        owners.append(min(fitting)[1] if fitting else None)
    table_z_m = detector.config.table_z_m
    results: dict[str, Detection] = {}
    for model in models:
        mine = [
            verdicts[model.name]
            for verdicts, owner in zip(judged, owners, strict=True)
            if owner == model.name or (owner is None and verdicts[model.name].shared)
        ]
        rest = [verdicts[model.name] for verdicts, owner in zip(judged, owners, strict=True) if owner is None]
        if len(mine) == 1:
            results[model.name] = _detection(name, mine[0], xy, table_z_m)
        elif len(mine) > 1:
            where = ", ".join(f"({v.fit.x_m:.3f}, {v.fit.y_m:.3f})" for v in mine if v.fit is not None)
            results[model.name] = Detection(
                name,
                DetectionStatus.AMBIGUOUS,
                f"{len(mine)} {name} {model.name} faces, at {where} m; expected one",
                candidates_xy_m=xy,
            )
        elif len(rest) == 1:
            # One blob that could be this part (cut, covered, touching, no known outline): its outcome.
            results[model.name] = _detection(name, rest[0], xy, table_z_m)
        elif rest:
            reasons = "; ".join(v.reason for v in rest)
            results[model.name] = Detection(
                name,
                DetectionStatus.AMBIGUOUS,
                f"{len(rest)} {name} blobs, none a whole {model.name}: {reasons}",
                candidates_xy_m=xy,
            )
        else:
            others = ", ".join(
                f"the {owner} at ({v[owner].fit.x_m:.3f}, {v[owner].fit.y_m:.3f}) m"  # type: ignore[union-attr]
                for v, owner in zip(judged, owners, strict=True)
                if owner is not None
            )
            results[model.name] = Detection(
                name, DetectionStatus.WRONG_OUTLINE, f"no {name} {model.name} face, only {others}", candidates_xy_m=xy
            )
    return results


def detect_outline(detector: FaceSearch, view: PreparedView, colour: ColourRange, roi: WorldRegion | None) -> Detection:
    """``PartDetector``'s outcome for a prism part: the one part of ``colour`` whose face is its outline."""
    model = OutlineModel.of(detector.config.part)
    return detect_outlines(detector, view, colour, roi, [model])[model.name]
