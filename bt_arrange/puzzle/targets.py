"""From a solved puzzle to the targets the arrangement steps reach: each piece's place, its outline as its type."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray
from bt_arrange.objects import ObjectType
from bt_arrange.puzzle.spec import PuzzleSpec
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes.gripper import ROBOTIQ_2F85


def _centroid(points: FloatArray) -> FloatArray:
    x, y = points[:, 0], points[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = cross.sum() / 2
    return np.array(
        [((x + np.roll(x, -1)) * cross).sum() / (6 * area), ((y + np.roll(y, -1)) * cross).sum() / (6 * area)]
    )


def solved_targets(
    spec: PuzzleSpec, surveyed: Sequence[Any], settings: ManipulationSettings | None = None
) -> list[Any]:
    """Solve ``spec`` from the ``surveyed`` pieces (``SurveyedPiece``s) and return a ``Target`` per piece.

    Each target is the piece's area centroid in the whole, on the table where the plan puts the
    whole; its yaw turns the piece's frame (its x axis along its preferred grasp's closing axis, as
    a fresco piece's) to its place. A ``PuzzleError`` (a ``PlanError``) says why there is none.
    """
    from bt_arrange.puzzle.solve import MeasuredPiece, solve
    from bt_arrange.shapes.fracture import _in_grasp_frame
    from bt_arrange.trees import Target

    del settings  # the gripper's figures are the cell's; kept for a gripper in the settings later
    measured = [MeasuredPiece(p.name, p.outline_m, tuple(p.edge_colours) or None) for p in surveyed]
    assembly = solve(measured, (spec.size_m[0], spec.size_m[1]), spec.gap_m)
    by_name = {p.label: p for p in assembly.placements}
    targets = []
    for piece in surveyed:
        placement = by_name[piece.name]
        in_slab = placement.to_slab(np.asarray(piece.outline_m, dtype=float))
        centre = _centroid(in_slab)
        framed = _in_grasp_frame(in_slab - centre, spec.height_m, ROBOTIQ_2F85)
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
    return targets


__all__ = ["solved_targets"]
