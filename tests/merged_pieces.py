"""Two neighbouring fresco pieces, one moved towards the other until their gap is under a millimetre.

Shared by the synthetic-frame tests (``test_perception_merged.py``) and the cell's
(``integration/test_merged_cell.py``).
"""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.shapes.base import footprint_m
from bt_arrange.shapes.fracture import Piece, fracture, polygon_gap_m


def neighbours(seed: int, slab_yaw_rad: float = 0.0) -> tuple[Piece, Piece]:
    """The two pieces of a 6-piece fracture of ``seed`` whose centroids lie nearest each other."""
    pieces = fracture((0.16, 0.12, 0.02), 6, 0.002, seed, pose=(0.5, 0.0, slab_yaw_rad))
    pairs = [(a, b) for a in pieces for b in pieces if a.index < b.index]
    return min(pairs, key=lambda pair: math.hypot(pair[0].x_m - pair[1].x_m, pair[0].y_m - pair[1].y_m))


def moved_towards(a: Piece, b: Piece, gap_m: float) -> tuple[float, float]:
    """Where ``a`` stands, moved along the line to ``b``'s centroid, when its gap to ``b`` is ``gap_m`` (bisection)."""
    direction = np.array([b.x_m - a.x_m, b.y_m - a.y_m])
    direction /= np.linalg.norm(direction)
    low, high = 0.0, 0.002
    for _ in range(40):
        middle = (low + high) / 2
        x, y = a.x_m + direction[0] * middle, a.y_m + direction[1] * middle
        gap = polygon_gap_m(footprint_m(a.prism, x, y, a.yaw_rad), footprint_m(b.prism, b.x_m, b.y_m, b.yaw_rad))
        low, high = (middle, high) if gap > gap_m else (low, middle)
    return a.x_m + direction[0] * low, a.y_m + direction[1] * low
