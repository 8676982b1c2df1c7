"""Plane polygons in metres: area, centroid, the simple-polygon check, convex pieces and turns.

The arithmetic under :class:`~bt_arrange.shapes.Prism`; nothing here knows of parts or grippers.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence

import numpy as np

from bt_arrange.filelimits import MAX_OUTLINE_POINTS
from bt_arrange.geometry import FloatArray


def signed_area_m2(points: FloatArray) -> float:
    """The polygon's area, positive when it runs counter-clockwise (N x 2 points)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def centroid_m(points: FloatArray) -> FloatArray:
    """The polygon's area centroid (x, y)."""
    x, y = points[:, 0], points[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * float(np.sum(cross))
    cx = float(np.sum((x + np.roll(x, -1)) * cross)) / (6.0 * area)
    cy = float(np.sum((y + np.roll(y, -1)) * cross)) / (6.0 * area)
    return np.array([cx, cy])


def boundary_samples(points: FloatArray, count: int = 160) -> FloatArray:
    """``count`` points spaced evenly along the closed outline through ``points`` (N x 2)."""
    closed = np.vstack([points, points[:1]])
    edges = np.diff(closed, axis=0)
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    start = np.concatenate([[0.0], np.cumsum(lengths)])
    at = np.linspace(0.0, start[-1], count, endpoint=False)
    k = np.searchsorted(start, at, side="right") - 1
    return closed[k] + edges[k] * ((at - start[k]) / lengths[k])[:, None]


def distance_to_outline_m(queries: FloatArray, points: FloatArray) -> FloatArray:
    """Each query point's distance (queries ... x 2) to the closed outline through ``points`` (its nearest edge).

    Written coordinate by coordinate (no einsum, no norm of pairs): the same figures to the last bit,
    in half the time, for the batches of the yaw checks (every turn of a piece at once).
    """
    ax, ay = points[:, 0], points[:, 1]
    edges = np.roll(points, -1, axis=0) - points
    dx, dy = edges[:, 0], edges[:, 1]
    qx, qy = queries[..., 0, None], queries[..., 1, None]
    t = np.minimum(np.maximum(((qx - ax) * dx + (qy - ay) * dy) / (dx * dx + dy * dy), 0.0), 1.0)
    ex, ey = qx - (ax + t * dx), qy - (ay + t * dy)
    return np.sqrt(np.min(ex * ex + ey * ey, axis=-1))


def segments_cross(p1: FloatArray, p2: FloatArray, q1: FloatArray, q2: FloatArray) -> bool:
    """True when the closed segments p1-p2 and q1-q2 meet (touching counts)."""

    def orient(a: FloatArray, b: FloatArray, c: FloatArray) -> float:
        return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    def on(a: FloatArray, b: FloatArray, c: FloatArray) -> bool:
        return min(a[0], b[0]) - 1e-12 <= c[0] <= max(a[0], b[0]) + 1e-12 and (
            min(a[1], b[1]) - 1e-12 <= c[1] <= max(a[1], b[1]) + 1e-12
        )

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    if ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4)):
        return True
    return any(
        abs(d) <= 1e-18 and on(a, b, c)
        for d, a, b, c in ((d1, q1, q2, p1), (d2, q1, q2, p2), (d3, p1, p2, q1), (d4, p1, p2, q2))
    )


def outline_problem(points: Sequence[Sequence[float]]) -> str | None:
    """Why ``points`` (N x 2, metres) is no simple polygon: too many or too few points, degenerate, self-intersecting.

    Over ``MAX_OUTLINE_POINTS`` is refused before anything else is computed; the other checks take
    O(n log n) (``first_crossing``, a sweep line), so any outline within the limit is judged at once.
    """
    count = len(points)
    if count > MAX_OUTLINE_POINTS:
        return (
            f"the outline has {count:,} points, over the limit of {MAX_OUTLINE_POINTS} "
            "(bt_arrange.filelimits.MAX_OUTLINE_POINTS)"
        )
    array = np.asarray(points, dtype=float)
    if array.ndim != 2 or array.shape[1] != 2 or len(array) < 3:
        return f"an outline needs at least three points [x, y], got {len(array) if array.ndim == 2 else 0}"
    if not np.all(np.isfinite(array)):
        return "an outline's points must be finite numbers"
    edges = np.roll(array, -1, axis=0) - array
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    if np.any(lengths < 1e-6):
        index = int(np.argmin(lengths))
        return f"the outline repeats point {index + 1} (an edge of no length)"
    # Points on one line first: a symmetric bow tie also has no signed area, but it crosses itself.
    if np.linalg.svd(array - array.mean(axis=0), compute_uv=False)[1] < 1e-6:
        return "the outline encloses no area (its points lie on a line)"
    crossing = first_crossing(array)
    if crossing is not None:
        i, j = crossing
        return f"the outline crosses itself (edges {i + 1} and {j + 1} meet)"
    if abs(signed_area_m2(array)) < 1e-8:
        return "the outline encloses no area"
    return None


def first_crossing(points: FloatArray) -> tuple[int, int] | None:
    """Two edges ``(i, j)``, ``i < j``, that meet without being neighbours, or None: the polygon is simple.

    Edge ``k`` runs from point ``k`` to point ``k + 1`` (N x 2 points, no edge of no length). Shamos
    and Hoey's sweep line: O(n log n) comparisons and at most 3n ``segments_cross`` tests, where
    testing every pair took n^2 / 2. First, in O(n log n), a point written twice (two edges would
    meet there without being tested) and an edge that folds back along its neighbour; then the
    endpoints are swept left to right (then bottom to top), the edges under the sweep kept in order
    of height. An edge is tested against the ones just above and below it when it comes in, and
    those two against each other when it leaves: the first meeting is always between two edges
    that were neighbours in that order before the sweep reached it.
    """
    count = len(points)
    # A point written twice (not as neighbours: the edge between them has a length).
    order = np.lexsort((points[:, 1], points[:, 0]))
    ranked = points[order]
    same = np.flatnonzero(np.all(np.abs(np.diff(ranked, axis=0)) <= 1e-12, axis=1))
    if len(same):
        a, b = sorted((int(order[same[0]]), int(order[same[0] + 1])))
        return (a, b - 1)  # edge a leaves the point, edge b - 1 comes back to it (b > a + 1: edges have lengths)
    # An edge folding back along its neighbour (they overlap, which the sweep does not test).
    after = np.roll(points, -1, axis=0) - points
    before = np.roll(after, 1, axis=0)
    cross = before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0]
    dot = np.sum(before * after, axis=1)
    norms = np.hypot(*before.T) * np.hypot(*after.T)
    folds = np.flatnonzero((np.abs(cross) <= 1e-12 * norms) & (dot < 0))
    if len(folds):
        k = int(folds[0])
        return (k - 1, k) if k else (0, count - 1)
    return _sweep(points)


def _adjacent(i: int, j: int, count: int) -> bool:
    return abs(i - j) == 1 or abs(i - j) == count - 1


def _sweep(points: FloatArray) -> tuple[int, int] | None:
    """The sweep of ``first_crossing`` once no point is written twice and no edge folds back."""
    count = len(points)
    xy = [(float(x), float(y)) for x, y in points]
    lefts: list[tuple[float, float]] = []
    rights: list[tuple[float, float]] = []
    slopes: list[float] = []
    events: list[tuple[float, float, int, int]] = []  # (x, y, 0 leaves / 1 comes in, edge)
    for k in range(count):
        a, b = xy[k], xy[(k + 1) % count]
        left, right = (a, b) if a <= b else (b, a)
        lefts.append(left)
        rights.append(right)
        dx = right[0] - left[0]
        slopes.append((right[1] - left[1]) / dx if dx > 0 else math.inf)
        events += [(left[0], left[1], 1, k), (right[0], right[1], 0, k)]
    events.sort()  # left to right, bottom to top; at one point, edges leave before others come in
    active: list[int] = []  # the edges under the sweep, lowest first

    def height(k: int, x: float, y: float) -> tuple[float, float]:
        """Where edge ``k`` meets the sweep at point (x, y) (a vertical edge: y, within it), then its slope."""
        (xa, ya), (xb, yb) = lefts[k], rights[k]
        if xb == xa:
            return min(max(y, ya), yb), math.inf
        if x == xb:
            return yb, slopes[k]
        return ya + (x - xa) * slopes[k], slopes[k]

    def meet(i: int, j: int) -> tuple[int, int] | None:
        if _adjacent(i, j, count):
            return None
        if segments_cross(points[i], points[(i + 1) % count], points[j], points[(j + 1) % count]):
            return (min(i, j), max(i, j))
        return None

    for x, y, comes_in, k in events:
        key = height(k, x, y)
        place = bisect.bisect_left(active, key, key=lambda other: height(other, x, y))
        if comes_in:
            active.insert(place, k)
            for other in (place - 1, place + 1):
                if 0 <= other < len(active) and (found := meet(k, active[other])) is not None:
                    return found
            continue
        # Edges of the same height at this point lie from ``place`` on: find this one among them.
        while place < len(active) and active[place] != k and height(active[place], x, y) == key:
            place += 1
        if place >= len(active) or active[place] != k:
            place = active.index(k)  # rounding put it a step away; the order is still right
        del active[place]
        if 0 < place < len(active) and (found := meet(active[place - 1], active[place])) is not None:
            return found
    return None


def _cross_z(o: FloatArray, a: FloatArray, b: FloatArray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def ear_clip(points: FloatArray) -> list[tuple[int, int, int]]:
    """Triangles (vertex indices, counter-clockwise) covering a simple counter-clockwise polygon."""
    remaining = list(range(len(points)))
    triangles: list[tuple[int, int, int]] = []
    while len(remaining) > 3:
        for k in range(len(remaining)):
            i, j, n = remaining[k - 1], remaining[k], remaining[(k + 1) % len(remaining)]
            a, b, c = points[i], points[j], points[n]
            if _cross_z(a, b, c) <= 1e-14:
                continue  # a reflex or flat corner is no ear
            inside = any(
                _cross_z(a, b, points[m]) >= 0 and _cross_z(b, c, points[m]) >= 0 and _cross_z(c, a, points[m]) >= 0
                for m in remaining
                if m not in (i, j, n)
            )
            if not inside:
                triangles.append((i, j, n))
                del remaining[k]
                break
        else:  # numerically degenerate: fan out what is left
            break
    for k in range(1, len(remaining) - 1):
        triangles.append((remaining[0], remaining[k], remaining[k + 1]))
    return triangles


def merge_if_convex(points: FloatArray, first: list[int], second: list[int]) -> list[int] | None:
    """The union of two convex pieces sharing an edge (vertex indices), if it is convex; else None."""
    for a in range(len(first)):
        u, v = first[a], first[(a + 1) % len(first)]
        if v in second and second[(second.index(v) + 1) % len(second)] == u:
            start = second.index(u)
            rest = [second[(start + k) % len(second)] for k in range(1, len(second) - 1)]
            union = first[: a + 1] + rest + first[a + 1 :]
            return union if _is_convex(points[union]) else None
    return None


def _is_convex(points: FloatArray) -> bool:
    count = len(points)
    return all(_cross_z(points[k - 1], points[k], points[(k + 1) % count]) >= -1e-14 for k in range(count))


def turn_rad(before: FloatArray, here: FloatArray, after: FloatArray) -> float:
    """How far the outline turns at ``here`` (signed, radians)."""
    a, b = here - before, after - here
    return math.atan2(float(a[0] * b[1] - a[1] * b[0]), float(a @ b))


def convex_pieces(points: FloatArray) -> list[FloatArray]:
    """A simple counter-clockwise polygon split into convex polygons (counter-clockwise).

    Ear clipping gives triangles; neighbouring pieces are then merged while the union stays
    convex (Hertel and Mehlhorn), so a convex outline is one piece and an L two. The clipping
    is started at each vertex in turn and the split kept that has the fewest pieces, then the
    widest narrowest corner: a sliver piece at an outline corner is a contact the physics
    engines resolve sideways (a pad pressed on the corner of a 44 deg sliver of the fragment was
    pushed shut along the sliver's inner side and held the part, docs/irregular.md).
    """
    count = len(points)
    best: tuple[tuple[int, float], list[list[int]]] | None = None
    for start in range(count):
        order = [(start + k) % count for k in range(count)]
        pieces = _merged([[order[i] for i in triangle] for triangle in ear_clip(points[order])], points)
        score = (len(pieces), min(_narrowest_corner_rad(points[piece]) for piece in pieces))
        # Fewer pieces, or as many with a corner wider by more than rounding: the first clipping keeps ties.
        if best is None or score[0] < best[0][0] or (score[0] == best[0][0] and score[1] > best[0][1] + 1e-9):
            best = (score, pieces)
    assert best is not None
    return [points[piece] for piece in best[1]]


def _merged(pieces: list[list[int]], points: FloatArray) -> list[list[int]]:
    """Neighbouring convex pieces merged while their union stays convex (the first pair found first)."""
    merged = True
    while merged:
        merged = False
        for i in range(len(pieces)):
            for j in range(i + 1, len(pieces)):
                union = merge_if_convex(points, pieces[i], pieces[j])
                if union is not None:
                    pieces[i] = union
                    del pieces[j]
                    merged = True
                    break
            if merged:
                break
    return pieces


def _narrowest_corner_rad(piece: FloatArray) -> float:
    """The smallest interior angle of a convex piece (a flat corner counts as pi)."""
    count = len(piece)
    return min(math.pi - abs(turn_rad(piece[k - 1], piece[k], piece[(k + 1) % count])) for k in range(count))
