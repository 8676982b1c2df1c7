"""From a solved puzzle to the targets the arrangement steps reach: each piece's place, its outline as its type."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray
from bt_arrange.objects import ObjectType
from bt_arrange.puzzle.spec import PuzzleSpec
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes.polygon import centroid_m

#: The camera's pixel on the table, about (m): where ``edge_colours`` took their samples, in metres.
_PIXEL_M = 0.00047


def _sample_points(outline_m: FloatArray, counts: Sequence[int]) -> FloatArray:
    """Where the survey sampled each edge's colours (``outline_unknown_edges.edge_colours``), on the table."""
    from bt_arrange.perception.outline_unknown_edges import COLOUR_DEPTH_PX, COLOUR_END_PX

    centre = outline_m.mean(axis=0)
    points = []
    for k, count in enumerate(counts):
        p, q = outline_m[k], outline_m[(k + 1) % len(outline_m)]
        length = float(np.hypot(*(q - p)))
        direction = (q - p) / max(length, 1e-12)
        inward = np.array([-direction[1], direction[0]])
        if inward @ (centre - p) < 0:
            inward = -inward
        end = min(COLOUR_END_PX * _PIXEL_M, length / 2)
        along = np.linspace(end, length - end, count) if count else np.empty(0)
        points.append(p + along[:, None] * direction + COLOUR_DEPTH_PX * _PIXEL_M * inward)
    return np.concatenate(points) if points else np.empty((0, 2))


def picture_turn(spec: PuzzleSpec, surveyed: Sequence[Any], placements: dict[str, Any]) -> float:
    """Of the whole's symmetric turns, the one under which the pieces' colours best match the picture (radians)."""
    from bt_arrange.puzzle.picture import hue_distance, picture_file, picture_rgb_at, read_picture

    assert spec.picture is not None
    picture = read_picture(picture_file(spec.picture))
    seen, where = [], []
    for piece in surveyed:
        colours = [np.asarray(c, dtype=float).reshape(-1, 3) for c in piece.edge_colours]
        if len(colours) != len(piece.outline_m):
            continue
        seen.append(np.concatenate(colours))
        where.append(
            placements[piece.name].to_slab(
                _sample_points(np.asarray(piece.outline_m, float), [len(c) for c in colours])
            )
        )
    if not seen:
        raise PlanError(f"{spec.name}: the survey kept no colours of the painted pieces to hold against the picture")
    colours_seen, points = np.concatenate(seen), np.concatenate(where)
    length, width, _ = spec.size_m
    turns = (0.0, math.pi, math.pi / 2, -math.pi / 2) if math.isclose(length, width, abs_tol=1e-6) else (0.0, math.pi)

    def misfit(turn: float) -> float:
        c, s = math.cos(turn), math.sin(turn)
        turned = points @ np.array([[c, s], [-s, c]])
        return float(np.median(hue_distance(colours_seen, picture_rgb_at(picture, turned, spec.size_m))))

    return min(turns, key=misfit)


def solved_targets(
    spec: PuzzleSpec, surveyed: Sequence[Any], settings: ManipulationSettings | None = None
) -> list[Any]:
    """Solve ``spec`` from the ``surveyed`` pieces (``SurveyedPiece``s) and return a ``Target`` per piece.

    Each target is the piece's area centroid in the whole, on the table where the plan puts the
    whole; its yaw turns the piece's frame (its x axis along its preferred grasp's closing axis, as
    a fresco piece's) to its place. A ``PuzzleError`` (a ``PlanError``) says why there is none.
    """
    from bt_arrange.plan.targets import Target
    from bt_arrange.puzzle.solve import MeasuredPiece, solve
    from bt_arrange.shapes.fracture import in_grasp_frame

    gripper = (settings or ManipulationSettings()).gripper
    measured = [MeasuredPiece(p.name, p.outline_m, tuple(p.edge_colours) or None) for p in surveyed]
    assembly = solve(measured, (spec.size_m[0], spec.size_m[1]), spec.gap_m)
    by_name = {p.label: p for p in assembly.placements}
    # A painted slab's picture tells the whole's symmetric turns apart: the one whose colours the pieces show.
    turn = picture_turn(spec, surveyed, by_name) if spec.picture is not None else 0.0
    c, s = math.cos(turn), math.sin(turn)
    targets = []
    for piece in surveyed:
        placement = by_name[piece.name]
        in_slab = placement.to_slab(np.asarray(piece.outline_m, dtype=float)) @ np.array([[c, s], [-s, c]])
        centre = centroid_m(in_slab)
        framed = in_grasp_frame(in_slab - centre, spec.height_m, gripper)
        if framed is None:
            raise PlanError(f"piece {piece.name}: as measured, not a part the gripper can grasp across its frame's x")
        prism, turn = framed
        x_m, y_m = spec.to_table(float(centre[0]), float(centre[1]))
        yaw = spec.yaw_rad + turn
        targets.append(
            Target(
                spec.colour,
                x_m,
                y_m,
                math.atan2(math.sin(yaw), math.cos(yaw)),
                name=piece.name,
                object_type=ObjectType(piece.name, shape=prism),
            )
        )
    return spread_to_gap(targets, spec, settings)


#: How far beyond the layout's least gap (m) the solved places are spread: clear of its check's rounding.
SPREAD_MARGIN_M = 1e-5


def spread_to_gap(targets: list[Any], spec: PuzzleSpec, settings: ManipulationSettings | None = None) -> list[Any]:
    """The solved targets moved out from the whole's centre until every two lie the layout's least gap apart.

    The pieces' outlines are measured, so a solve along a 2 mm gap can put two neighbours 1.99 mm
    apart, and the layout (``min_target_gap_m``, twice a 1 mm threshold) would refuse every seed:
    the measurement's noise is the solver's to absorb, not the user's. The whole is spread evenly
    (every centre scaled out from the slab's place by one factor, the least that clears the gap);
    solved places that already clear it are returned as they are.
    """
    from bt_arrange.plan.footprints import gap_m
    from bt_arrange.plan.targets import parts_of

    settings = settings or ManipulationSettings()
    needed_m = settings.min_target_gap_m + SPREAD_MARGIN_M
    scale = 1.0
    spread = targets
    for _ in range(12):
        parts = parts_of(spread, settings)
        worst = min(
            (
                (gap_m(a.footprint, b.footprint), math.hypot(a.x_m - b.x_m, a.y_m - b.y_m))
                for i, a in enumerate(parts)
                for b in parts[i + 1 :]
            ),
            default=(math.inf, 0.0),
        )
        gap, apart_m = worst
        if gap >= needed_m or apart_m <= 0.0:
            return spread
        scale *= 1.0 + (needed_m - gap) / apart_m
        spread = [
            dataclasses.replace(t, x_m=spec.x_m + scale * (t.x_m - spec.x_m), y_m=spec.y_m + scale * (t.y_m - spec.y_m))
            for t in targets
        ]
    return spread


__all__ = ["solved_targets", "spread_to_gap"]
