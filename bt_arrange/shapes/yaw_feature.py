"""How clearly an outline shows its yaw: the smallest feature that tells its turns apart, in metres.

The top camera registers a part's outline to its face at every yaw and keeps the one whose
sub-pixel edges fit (``bt_arrange.perception.outline``). Two yaws that are no symmetry turn of
each other can be told apart only by where the outline turned by their difference strays from
itself. :func:`yaw_feature_m` measures that: over every such turn, the largest distance between
the outline and itself turned about its area centroid, the least over the turns. A regular
polygon scores nothing to tell apart (its turns are symmetries, and every one of them is as good);
a rectangle with one corner a millimetre off scores about that millimetre.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from bt_arrange.geometry import FloatArray, fold_yaw
from bt_arrange.shapes.polygon import boundary_samples, distance_to_outline_m

#: Turns this close to a symmetry turn (or to none) are the same yaw to the registration.
SAME_YAW_RAD = math.radians(10.0)
#: The coarse turn grid, and how finely the best turns on it are refined.
COARSE_TURN_RAD = math.radians(2.0)
FINE_TURN_RAD = math.radians(0.05)
#: Points along the outline, evenly spaced, at which the distance is measured (the vertices too).
SAMPLES = 120


def _strays_m(points: FloatArray, samples: FloatArray, turns: FloatArray) -> FloatArray:
    """For each turn, the largest distance between the outline and itself turned (both ways)."""
    both = np.concatenate([turns, -turns])
    c, s = np.cos(both), np.sin(both)
    turned = np.stack(
        [
            c[:, None] * samples[None, :, 0] - s[:, None] * samples[None, :, 1],
            s[:, None] * samples[None, :, 0] + c[:, None] * samples[None, :, 1],
        ],
        axis=-1,
    )
    one_way = distance_to_outline_m(turned, points).max(axis=1)
    return np.maximum(one_way[: len(turns)], one_way[len(turns) :])


@functools.lru_cache(maxsize=1024)
def _feature(
    outline: tuple[tuple[float, float], ...], symmetry_rad: float, refine_below_m: float
) -> tuple[float, float]:
    points = np.asarray(outline, dtype=float)
    samples = np.vstack([points, boundary_samples(points, SAMPLES)])
    turns: FloatArray = np.arange(0.0, 2 * math.pi, COARSE_TURN_RAD, dtype=np.float64)
    strays = _strays_m(points, samples, turns)
    # The rival yaws: the turns where the outline comes back nearest itself, away from its symmetry turns
    # (a small turn strays little because it is small, not because it looks the same).
    count = len(turns)
    rivals = [
        k
        for k in range(count)
        if strays[k] <= strays[k - 1]
        and strays[k] <= strays[(k + 1) % count]
        and abs(fold_yaw(float(turns[k]), symmetry_rad)) >= SAME_YAW_RAD
    ]
    if not rivals:
        return math.inf, 0.0
    best_k = min(rivals, key=lambda k: strays[k])
    best, best_turn = float(strays[best_k]), float(turns[best_k])
    # Between two grid turns the distance changes by at most the farthest point's travel: a minimum that
    # could lie under the limit is refined, one well above it is its grid value.
    reach_m = float(np.max(np.hypot(points[:, 0], points[:, 1]))) * COARSE_TURN_RAD
    for k in sorted(rivals, key=lambda k: strays[k])[:4]:
        if strays[k] - reach_m > refine_below_m:
            continue
        fine: FloatArray = np.arange(
            turns[k] - COARSE_TURN_RAD, turns[k] + COARSE_TURN_RAD, FINE_TURN_RAD, dtype=np.float64
        )
        values = _strays_m(points, samples, fine)
        if float(values.min()) < best:
            best, best_turn = float(values.min()), float(fine[int(np.argmin(values))])
    return best, best_turn


def yaw_feature_m(outline_m: FloatArray, symmetry_rad: float, refine_below_m: float = math.inf) -> tuple[float, float]:
    """The smallest feature (metres) telling the outline's yaws apart, and the turn (radians) it tells apart.

    ``outline_m`` is about its area centroid (N x 2), ``symmetry_rad`` the turn that maps it onto
    itself (2 pi for none). Infinity when no turn but the symmetries brings the outline back near
    itself. The turns are searched on a 2 degree grid and refined near its best minima to 0.05 degree;
    with ``refine_below_m`` only a minimum that could lie under it is refined (the others are exact to
    the grid's step), which is all a check against a limit needs.
    """
    points = np.asarray(outline_m, dtype=float)
    # The feature is the shape's, whatever way its frame is turned: cached turned so that its first
    # vertex lies on +x (a fresco piece is judged as cut and again turned to its grasp's frame).
    angle = math.atan2(float(points[0, 1]), float(points[0, 0]))
    c, s = math.cos(angle), math.sin(angle)
    canonical = points @ np.array([[c, -s], [s, c]])
    key = tuple((round(float(x), 12), round(float(y), 12)) for x, y in canonical)
    return _feature(key, float(symmetry_rad), float(refine_below_m))
