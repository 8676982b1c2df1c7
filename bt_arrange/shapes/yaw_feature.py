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
from scipy.spatial import cKDTree

from bt_arrange.geometry import FloatArray, fold_yaw
from bt_arrange.shapes.polygon import boundary_samples, distance_to_outline_m

#: Turns this close to a symmetry turn (or to none) are the same yaw to the registration.
SAME_YAW_RAD = math.radians(10.0)
#: The coarse turn grid, and how finely the best turns on it are refined.
COARSE_TURN_RAD = math.radians(2.0)
FINE_TURN_RAD = math.radians(0.05)
#: Points along the outline, evenly spaced, at which the distance is measured (the vertices too).
SAMPLES = 120


class _Distances:
    """Each query point's distance to the closed outline, to the last bit as ``distance_to_outline_m`` gives it.

    The edges are cut into pieces no longer than the outline's mean edge, their middles kept in a
    k-d tree: a query is measured exactly (the same arithmetic) to the edges of its ``NEAREST``
    nearest pieces, and that is its distance when no other piece can come nearer (the next piece's
    middle is farther than the distance found and half a piece). The few queries left are measured
    to every edge. O(queries log n), where every query against every edge took O(queries n).
    """

    NEAREST = 4

    def __init__(self, points: FloatArray) -> None:
        self.points = points
        edges = np.roll(points, -1, axis=0) - points
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        pieces = np.maximum(1, np.ceil(lengths / (lengths.sum() / len(points)))).astype(int)
        self.edge_of = np.repeat(np.arange(len(points)), pieces)
        within = np.arange(len(self.edge_of)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        share = (within + 0.5) / pieces[self.edge_of]
        middles = points[self.edge_of] + share[:, None] * edges[self.edge_of]
        self.half_piece_m = float(np.max(lengths / pieces)) / 2 * (1 + 1e-9) + 1e-12
        self.tree = cKDTree(middles)
        self.ax, self.ay, self.dx, self.dy = points[:, 0], points[:, 1], edges[:, 0], edges[:, 1]
        self.squared = self.dx * self.dx + self.dy * self.dy

    def __call__(self, queries: FloatArray) -> FloatArray:
        flat = queries.reshape(-1, 2)
        found = np.empty(len(flat))
        todo = np.arange(len(flat))
        for nearest in (self.NEAREST, 8 * self.NEAREST):
            if not len(todo) or nearest >= len(self.edge_of):
                break
            middle_m, piece = self.tree.query(flat[todo], k=nearest)
            edge = self.edge_of[piece]
            qx, qy = flat[todo, 0, None], flat[todo, 1, None]
            ax, ay, dx, dy = self.ax[edge], self.ay[edge], self.dx[edge], self.dy[edge]
            t = np.minimum(np.maximum(((qx - ax) * dx + (qy - ay) * dy) / self.squared[edge], 0.0), 1.0)
            ex, ey = qx - (ax + t * dx), qy - (ay + t * dy)
            distance = np.sqrt(np.min(ex * ex + ey * ey, axis=-1))
            sure = middle_m[:, -1] - self.half_piece_m >= distance + 1e-12
            found[todo[sure]] = distance[sure]
            todo = todo[~sure]
        if len(todo):
            found[todo] = distance_to_outline_m(flat[todo], self.points)
        return found.reshape(queries.shape[:-1])


def _strays_m(distances: _Distances, samples: FloatArray, turns: FloatArray) -> FloatArray:
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
    one_way = distances(turned).max(axis=1)
    return np.maximum(one_way[: len(turns)], one_way[len(turns) :])


def _least_stray(
    distances: _Distances, samples: FloatArray, turns: FloatArray, slope_m: float, best: float
) -> tuple[float, float]:
    """The least stray over ``turns`` and its first turn, as measuring every turn gives them, when under ``best``.

    Every eighth turn is measured first; a stray changes by at most ``slope_m`` a radian (the
    farthest sample's travel), so a turn whose bound from those lies above the least found (or
    ``best``) cannot be the least and is not measured.
    """
    known = np.full(len(turns), np.nan)
    first = np.arange(0, len(turns), 8)
    known[first] = _strays_m(distances, samples, turns[first])
    ceiling = min(best, float(np.min(known[first])))
    bound = np.max(known[first][None, :] - slope_m * np.abs(turns[:, None] - turns[first][None, :]), axis=1) - 1e-12
    left = np.isnan(known) & (bound <= ceiling)
    if np.any(left):
        known[left] = _strays_m(distances, samples, turns[left])
    known[np.isnan(known)] = np.inf
    index = int(np.argmin(known))
    return float(known[index]), float(turns[index])


@functools.lru_cache(maxsize=1024)
def _feature(
    outline: tuple[tuple[float, float], ...], symmetry_rad: float, refine_below_m: float
) -> tuple[float, float]:
    points = np.asarray(outline, dtype=float)
    samples = np.vstack([points, boundary_samples(points, SAMPLES)])
    distances = _Distances(points)
    turns: FloatArray = np.arange(0.0, 2 * math.pi, COARSE_TURN_RAD, dtype=np.float64)
    strays = _strays_m(distances, samples, turns)
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
    radius_m = float(np.max(np.hypot(points[:, 0], points[:, 1])))
    reach_m = radius_m * COARSE_TURN_RAD
    slope_m = float(np.max(np.hypot(samples[:, 0], samples[:, 1]))) * (1 + 1e-9)
    for k in sorted(rivals, key=lambda k: strays[k])[:4]:
        if strays[k] - reach_m > refine_below_m:
            continue
        fine: FloatArray = np.arange(
            turns[k] - COARSE_TURN_RAD, turns[k] + COARSE_TURN_RAD, FINE_TURN_RAD, dtype=np.float64
        )
        least, turn = _least_stray(distances, samples, fine, slope_m, best)
        if least < best:
            best, best_turn = least, turn
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
