"""Dense layouts by geometry: where the pads go, in which order the parts are placed, from which sides they are pushed.

Everything is planar and in metres: a part is its shape's footprint on the table
(``bt_arrange.plan.layout_part.Part``: a box's oriented rectangle, another outline's convex pieces),
the pads are the rectangles they sweep while grasping, releasing, pushing and
backing off. The pads reach below a resting part's top face (they hold a 5 cm cube at mid
height), so a pad volume that meets a neighbour's footprint means a collision. A plan is checked
step by step against what is already on the table at that point:

- **release** across two faces of the target's frame (``axis`` "x" or "y": the pads close along
  it) when both pads fit beside the part (``release_gap_m`` each side, opened to the part's size
  plus twice that), the part itself lowered with ``place_clearance_m`` to spare;
- else a **staging** release: offset away from the neighbours (in the target's frame) where the
  pads fit, then pushed home from its free sides;
- **pushes** only from free sides: the pads start ``push_clearance_m`` behind a face and are a
  pad's width deep; a side whose volume meets a neighbour cannot be pushed from. A correction
  that needs such a side is released again at a ``restage`` pose on the other side.

``plan_layout(parts, settings, order=None)`` chooses an order (a depth-first search that keeps
every remaining part placeable; the user's order when given) and returns the steps, or raises one
``PlanError`` naming the parts in the way. No pybullet, no shapely: separating axes on rectangles
and on the convex pieces of an irregular part's outline (``bt_arrange.plan.footprints.Outline``, from
``Shape.convex_pieces``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from bt_arrange.errors import PlanError
from bt_arrange.plan.footprints import Footprint, Outline, Rect, gap_m, overlap, radius_of
from bt_arrange.plan.layout_judged import KeptLayouts, blocked, blockers, current_targets, judging
from bt_arrange.plan.layout_part import DIRECTIONS, Part
from bt_arrange.plan.release_room import ReleaseRoom, release_pads, release_room
from bt_arrange.shapes.gripper import ROBOTIQ_2F85, Gripper

if TYPE_CHECKING:
    from bt_arrange.settings import ManipulationSettings


@dataclass(frozen=True)
class Pads:
    """What the pads and the placing need among neighbours, in metres.

    The gripper's own figures (pad size, finger depth, stroke, the clearance to a neighbour) are
    its :class:`~bt_arrange.shapes.Gripper`'s; the rest is how the layout places and pushes.
    """

    gripper: Gripper = ROBOTIQ_2F85
    #: Widest opening: the settings' open width (the stroke).
    max_opening_m: float = ROBOTIQ_2F85.stroke_m
    #: Each pad opens this far from the face it released.
    release_gap_m: float = 0.003
    #: A part is lowered with this much room to a neighbour (the placing error).
    place_clearance_m: float = 0.0015
    #: The pads start this far behind a face they push.
    push_clearance_m: float = 0.010
    #: Two targets closer than this could touch once each lies within the threshold.
    min_gap_m: float = 0.002
    #: Staging offsets tried, from the smallest.
    staging_steps_m: tuple[float, ...] = tuple(0.002 * k for k in range(2, 16))

    @classmethod
    def from_settings(cls, settings: ManipulationSettings) -> Pads:
        """From ``ManipulationSettings`` (the gripper, the open width, the push clearance, the least gap)."""
        return cls(
            gripper=settings.gripper,
            max_opening_m=settings.open_width_m,
            push_clearance_m=settings.push_clearance_m,
            min_gap_m=settings.min_target_gap_m,
        )

    @property
    def width_m(self) -> float:
        """A pad's width along the face it touches."""
        return self.gripper.pad_width_m

    @property
    def thickness_m(self) -> float:
        """A pad's thickness out from the face it touches."""
        return self.gripper.pad_thickness_m

    @property
    def finger_depth_m(self) -> float:
        """How far a finger reaches out from the face its pad touches (``Gripper.finger_depth_m``)."""
        return self.gripper.finger_depth_m

    @property
    def pad_clearance_m(self) -> float:
        """How far a finger keeps from a neighbour's face (``Gripper.neighbour_clearance_m``)."""
        return self.gripper.neighbour_clearance_m

    def neighbour_push_opening_m(self, part: Part, along: str) -> float:
        """The opening for a push along ``along`` among neighbours (``Gripper.neighbour_push_opening_m``)."""
        if part.by_outline:
            return part.push_opening_m
        return self.gripper.neighbour_push_opening_m(2 * part.half("y" if along == "x" else "x"))

    def release_opening_m(self, part: Part, axis: str) -> float:
        """How far the pads open to release a part held across ``axis``."""
        return min(self.max_opening_m, 2 * part.grasp_half(axis) + 2 * self.release_gap_m)


def push_pads(part: Part, at: Footprint, towards: str, distance_m: float, pads: Pads) -> Rect:
    """The rectangle the pads sweep pushing ``part`` (at ``at``) ``distance_m`` towards ``towards``, then backing off.

    The pads stand side by side along the face behind it (opened to ``Pads.neighbour_push_opening_m``, so
    the fingers stay within the face's width), start ``push_clearance_m`` behind it, are a pad's
    width deep, and travel with the face.
    """
    if part.by_outline:
        return _square_push_pads(part, at, towards, distance_m, pads)
    ux, uy = DIRECTIONS[towards]
    along = "x" if ux else "y"
    half_along = part.back(towards)
    half_across = pads.neighbour_push_opening_m(part, along) / 2 + pads.finger_depth_m
    sign = ux + uy
    # Behind the face, from the face's final place back to the start of the pads.
    near = half_along - distance_m
    far = half_along + pads.push_clearance_m + pads.width_m
    centre = -sign * (near + far) / 2
    depth = (far - near) / 2
    if along == "x":
        return at.local(centre, 0.0, depth, half_across)
    return at.local(0.0, centre, half_across, depth)


def _square_push_pads(part: Part, at: Footprint, towards: str, distance_m: float, pads: Pads) -> Rect:
    """``push_pads`` for a square push of an irregular part: the pads behind its edge, along the push's heading."""
    heading_rad, back_m = part.push_heading_rad(towards), part.back(towards)
    near = back_m - distance_m
    far = back_m + pads.push_clearance_m + pads.width_m
    middle = -(near + far) / 2
    ux, uy = math.cos(heading_rad), math.sin(heading_rad)
    centre = at.local(middle * ux, middle * uy, 0.0, 0.0)
    half_across = part.push_opening(towards) / 2 + pads.finger_depth_m
    return Rect(centre.x_m, centre.y_m, at.yaw_rad + heading_rad, (far - near) / 2, half_across)


def free_push_directions(part: Part, placed: Sequence[tuple[str, Footprint]], pads: Pads) -> tuple[str, ...]:
    """The directions ``part`` (at its target) can be pushed towards with nothing of ``placed`` in the pads' way."""
    at = part.footprint
    others = [(n, r) for n, r in placed if n != part.name]
    free = []
    for towards in part.push_directions:

        def volumes(towards: str = towards) -> list[Footprint]:
            return [push_pads(part, at, towards, 0.0, pads)]

        if not blocked((part.name, "push", towards), volumes, others, pads.pad_clearance_m):
            free.append(towards)
    return tuple(free)


def push_blockers(part: Part, placed: Sequence[tuple[str, Footprint]], pads: Pads) -> dict[str, str]:
    """Per direction ``part`` (at its target) cannot be pushed towards, the nearest of ``placed`` in the pads' way."""
    others = [(n, r) for n, r in placed if n != part.name]
    footprints = dict(others)
    out: dict[str, str] = {}
    for towards in part.push_directions:
        names = blockers([push_pads(part, part.footprint, towards, 0.0, pads)], others, pads.pad_clearance_m)
        if names:
            out[towards] = min(names, key=lambda name: gap_m(part.footprint, footprints[name]))
    return out


@dataclass(frozen=True)
class Release:
    """Where and how a part is let go.

    The pads close across ``axis`` of its target's frame and open to ``opening_m``, at ``offset_m``
    (target frame) from the target; a staged release (an offset) is pushed home from free sides.
    ``centre_m`` is where the pads' centre stands from the part's origin (an irregular part's
    grasp may be off its centroid): ``offset_m`` includes it, so the TCP goes to the target plus
    ``offset_m`` and the part's origin lands ``offset_m - centre_m`` from its target.
    """

    axis: str
    opening_m: float
    offset_m: tuple[float, float] = (0.0, 0.0)
    centre_m: tuple[float, float] = (0.0, 0.0)
    #: The neighbours as the layout saw them (``release_room``): where the pads may slide along the part.
    room: ReleaseRoom | None = field(default=None, compare=False, repr=False)

    @property
    def staged(self) -> bool:
        """True when released away from the target, to be pushed home."""
        return self.offset_m != self.centre_m

    @property
    def staging_m(self) -> tuple[float, float]:
        """How far from its target the part's origin is released (target frame)."""
        return (self.offset_m[0] - self.centre_m[0], self.offset_m[1] - self.centre_m[1])


@dataclass(frozen=True)
class Step:
    """One part's step.

    How it is released, which directions it may be pushed towards afterwards, its neighbours on
    the table then, and how to release it again when a correction needs a blocked side.
    """

    part: Part
    release: Release
    push_towards: tuple[str, ...]
    neighbours: tuple[str, ...]
    #: Per blocked direction: the release on the other side, from where a push towards it is free.
    restage: dict[str, Release] = field(default_factory=dict)


def _release_at(
    part: Part, at: Footprint, placed: Sequence[tuple[str, Footprint]], pads: Pads, axes: Sequence[str] = ("x", "y")
) -> tuple[str | None, list[str]]:
    """An axis across which the pads fit releasing ``part`` at ``at`` (None) and who stands in the way."""
    if blockers([at], placed, pads.place_clearance_m):
        return None, blockers([at], placed, pads.place_clearance_m)
    in_way: list[str] = []
    for axis in axes:
        names = blockers(release_pads(part, at, axis, pads), placed, pads.pad_clearance_m)
        if not names:
            return axis, []
        in_way += [n for n in names if n not in in_way]
    return None, in_way


def _staged_release(
    part: Part,
    placed: Sequence[tuple[str, Footprint]],
    pads: Pads,
    directions: Sequence[tuple[int, int]] | None = None,
    axes: Sequence[str] = ("x", "y"),
) -> Release | None:
    """The smallest offset away from the neighbours where the pads fit and pushes home go from free sides."""
    free = free_push_directions(part, placed, pads)
    if part.by_outline:
        return _staged_prism_release(part, placed, pads, free, axes)
    candidates = directions or [(sx, sy) for sx in (-1, 0, 1) for sy in (-1, 0, 1) if (sx, sy) != (0, 0)]
    best: tuple[float, Release] | None = None
    for distance in pads.staging_steps_m:
        for sx, sy in candidates:
            # Pushed home towards -s on each axis it is offset along: that side must be free.
            needed = [d for d, s in (("-x" if sx > 0 else "+x", sx), ("-y" if sy > 0 else "+y", sy)) if s]
            if any(d not in free for d in needed):
                continue
            offset = (sx * distance, sy * distance)
            staged = part.footprint.moved(*offset)
            axis, _ = _release_at(part, staged, placed, pads, axes)
            if axis is None:
                continue
            # The pushes home sweep the pads from the staged pose to the target.
            if any(
                blockers(
                    [
                        push_pads(part, part.footprint.moved(*offset), d, distance, pads),
                        push_pads(part, part.footprint, d, 0.0, pads),
                    ],
                    placed,
                    pads.pad_clearance_m,
                )
                for d in needed
            ):
                continue
            cost = math.hypot(*offset)
            if best is None or cost < best[0]:
                best = (cost, _release(part, axis, pads, offset))
        if best is not None:
            return best[1]
    return None


def _staged_prism_release(
    part: Part, placed: Sequence[tuple[str, Footprint]], pads: Pads, free: Sequence[str], axes: Sequence[str]
) -> Release | None:
    """An irregular part's staging: back from its target against a free square push, which brings it home.

    One push along the edge's normal, squarely, so that the way home neither turns it nor needs
    a second side.
    """
    targets = current_targets()
    names = targets.placed_names(placed) if targets is not None else None

    def blocked_here(key: tuple[object, ...], volumes: Callable[[], Sequence[Footprint]], clearance_m: float) -> bool:
        if targets is None or names is None:
            return bool(blockers(volumes(), placed, clearance_m))
        return not targets.meeting((part.name, "staged", *key), volumes, clearance_m).isdisjoint(names)

    for distance in pads.staging_steps_m:
        for towards in free:
            ux, uy = part.push_vector(towards)
            offset = (-ux * distance, -uy * distance)

            def staged(offset: tuple[float, float] = offset) -> Footprint:
                return part.footprint.moved(*offset)

            def sweep(towards: str = towards, distance: float = distance) -> list[Footprint]:
                return [
                    push_pads(part, staged(), towards, distance, pads),
                    push_pads(part, part.footprint, towards, 0.0, pads),
                ]

            # What ``_release_at`` judges, each volume under its own key (``_Targets``).
            if blocked_here((distance, towards, "part"), lambda: [staged()], pads.place_clearance_m):
                continue
            axis = None
            for a in axes:

                def pads_at(a: str = a) -> list[Rect]:
                    return release_pads(part, staged(), a, pads)

                if not blocked_here((distance, towards, "pads", a), pads_at, pads.pad_clearance_m):
                    axis = a
                    break
            if axis is None or blocked_here((distance, towards, "sweep"), sweep, pads.pad_clearance_m):
                continue
            return _release(part, axis, pads, offset)
    return None


def _release(part: Part, axis: str, pads: Pads, staging_m: tuple[float, float] = (0.0, 0.0)) -> Release:
    """The release across ``axis`` with the part's origin ``staging_m`` from its target (the TCP at its grasp)."""
    opening_m = pads.release_opening_m(part, axis)
    if not part.by_outline:
        return Release(axis, opening_m, staging_m)
    cx, cy = part.grasp_centre(axis)
    return Release(axis, opening_m, (staging_m[0] + cx, staging_m[1] + cy), (cx, cy))


def choose_release(part: Part, placed: Sequence[tuple[str, Footprint]], pads: Pads) -> tuple[Release | None, list[str]]:
    """Release at the target across free faces, else at a staging pose; None and who is in the way if neither fits."""
    axis, in_way = _release_at(part, part.footprint, placed, pads, part.grasp_axes)
    if axis is not None:
        return _release(part, axis, pads), []
    staged = _staged_release(part, placed, pads, axes=part.grasp_axes)
    return staged, ([] if staged is not None else in_way)


def restage_releases(part: Part, placed: Sequence[tuple[str, Footprint]], pads: Pads) -> dict[str, Release]:
    """For each direction a push cannot go (its pads' side is blocked), a release past the target from which it can."""
    others = [(n, r) for n, r in placed if n != part.name]
    if part.by_outline:
        # Picked up again across a grasp, Pick stands the pads' centre on the part's origin (a
        # cuboid's grasp centre): an irregular part is pushed only from its free sides instead.
        return {}
    free = free_push_directions(part, others, pads)
    # Picked up where it lies (near its target) across faces whose pads fit there, and held so.
    pick_axes = [
        a
        for a in part.grasp_axes
        if not blockers(release_pads(part, part.footprint, a, pads), others, pads.pad_clearance_m)
    ]
    out: dict[str, Release] = {}
    if not pick_axes:
        return out
    for towards, (ux, uy) in DIRECTIONS.items():
        if towards in free:
            continue
        # The part must move towards (ux, uy): release it on that side, past the target, and push back.
        release = _staged_release(part, others, pads, directions=[(int(ux), int(uy))], axes=pick_axes)
        if release is not None:
            out[towards] = release
    return out


def neighbours_of(part: Part, placed: Sequence[tuple[str, Footprint]], within_m: float = 0.03) -> tuple[str, ...]:
    """Placed parts within ``within_m`` of ``part``'s footprint: a push or a release there could move them."""
    return tuple(name for name, rect in placed if name != part.name and gap_m(part.footprint, rect) <= within_m)


def check_gaps(parts: Sequence[Part], pads: Pads) -> None:
    """Two targets that overlap, or closer than ``pads.min_gap_m``: a ``PlanError`` naming both."""
    for i, first in enumerate(parts):
        for second in parts[i + 1 :]:
            gap = gap_m(first.footprint, second.footprint)
            both = (("target", first.name), ("target", second.name))
            if gap <= 0.0:
                raise PlanError(
                    f"targets {first.name} and {second.name} overlap: two parts cannot stand there; "
                    f"{_apart_text(first, second, pads)}",
                    parts=both,
                )
            if gap < pads.min_gap_m - 1e-9:
                raise PlanError(
                    f"targets {first.name} and {second.name} are {gap * 1000:.1f} mm apart, under the "
                    f"{pads.min_gap_m * 1000:g} mm two parts need so that each can lie within the threshold "
                    f"without touching; {_apart_text(first, second, pads)}",
                    parts=both,
                )


def centre_distance_needed_m(first: Part, second: Part, pads: Pads) -> float:
    """How far apart the two targets' centres must be, along the line between them, for the least gap."""
    dx, dy = second.x_m - first.x_m, second.y_m - first.y_m
    length = math.hypot(dx, dy)
    ux, uy = (dx / length, dy / length) if length > 1e-12 else (1.0, 0.0)
    a = first.footprint
    b = second.footprint

    def gap_at(distance_m: float) -> float:
        return gap_m(a, dataclasses.replace(b, x_m=a.x_m + ux * distance_m, y_m=a.y_m + uy * distance_m))

    low, high = 0.0, radius_of(a) + radius_of(b) + pads.min_gap_m
    for _ in range(40):  # the gap grows with the distance along the line: bisect
        middle = (low + high) / 2
        if gap_at(middle) >= pads.min_gap_m:
            high = middle
        else:
            low = middle
    return high


def _apart_text(first: Part, second: Part, pads: Pads) -> str:
    distance_mm = math.hypot(second.x_m - first.x_m, second.y_m - first.y_m) * 1000
    need_mm = centre_distance_needed_m(first, second, pads) * 1000
    return (
        f"their centres are {distance_mm:.1f} mm apart and must be at least {need_mm:.1f} mm apart along that "
        f"line (their footprints and the {pads.min_gap_m * 1000:g} mm gap): move them "
        f"{need_mm - distance_mm:.1f} mm further apart"
    )


def plan_layout(parts: Sequence[Part], pads: Pads | None = None, order: Sequence[str] | None = None) -> list[Step]:
    """The steps of a buildable plan, in placing order, or one ``PlanError`` naming the parts in the way.

    With ``order`` (the parts' names) that order is checked; without, a depth-first search takes
    the plan's own order where it can and backtracks where it cannot: a step is tried only while
    every part not yet placed can still be released (parts only ever add obstacles, so a part that
    cannot be released now never can later).
    """
    parts, pads = list(parts), pads or Pads()
    key = (
        tuple((p.name, p.x_m, p.y_m, p.yaw_rad, id(p.shape), p.gripper) for p in parts),
        pads,
        None if order is None else tuple(order),
    )
    kept = _LAYOUTS.get(key)
    if kept is not None:
        return list(kept[1])  # type: ignore[index]
    with judging({p.name: p.footprint for p in parts}):
        steps = _plan_layout(parts, pads, order)
    _LAYOUTS.put(key, (parts, steps))  # the parts keep their shapes, whose ids the key holds
    return list(steps)


#: Layouts kept, the latest first out last: a run asks for the same one four times (the plan
#: file's check and tree as it loads, the run's tree, the session's plan check), and a 12-piece
#: fresco's search takes a second.
KEPT_LAYOUTS = 8
_LAYOUTS = KeptLayouts(KEPT_LAYOUTS)


def _plan_layout(parts: list[Part], pads: Pads, order: Sequence[str] | None) -> list[Step]:
    check_gaps(parts, pads)
    by_name = {p.name: p for p in parts}
    if order is not None:
        names = list(order)
        if sorted(names) != sorted(by_name):
            raise PlanError(f"order {names} must name each part once: {', '.join(by_name)}")
        sequence = [by_name[n] for n in names]
        placed: list[tuple[str, Footprint]] = []
        for part in sequence:
            release, in_way = choose_release(part, placed, pads)
            if release is None:
                raise PlanError(_no_room(part, in_way, pads, after=True), parts=_parts_of(part, in_way))
            placed.append((part.name, part.footprint))
        return _steps(sequence, pads)

    memo: dict[tuple[str, frozenset[str]], tuple[Release | None, list[str]]] = {}

    def release_of(part: Part, placed_names: frozenset[str]) -> tuple[Release | None, list[str]]:
        key = (part.name, placed_names)
        if key not in memo:
            memo[key] = choose_release(part, [(n, by_name[n].footprint) for n in placed_names], pads)
        return memo[key]

    worst: list[tuple[int, Part, list[str]]] = []
    # The placed sets searched from without an order: what follows depends on the set alone (the
    # parts left keep the plan's order), so a set that failed once fails again, the same way.
    failed: set[frozenset[str]] = set()

    def search(done: list[Part], left: list[Part]) -> list[Part] | None:
        if not left:
            return done
        names = frozenset(p.name for p in done)
        if names in failed:
            return None
        options = []
        for index, part in enumerate(left):
            release, in_way = release_of(part, names)
            if release is None:
                worst.append((len(done), part, in_way))
                return None  # it will never fit later either: obstacles only grow
            options.append((index, part))
        for _, part in options:
            found = search([*done, part], [p for p in left if p is not part])
            if found is not None:
                return found
        failed.add(names)
        return None

    found = search([], parts)
    if found is None:
        depth, part, in_way = max(worst, key=lambda w: w[0])
        raise PlanError(_no_room(part, in_way, pads, after=False), parts=_parts_of(part, in_way))
    return _steps(found, pads)


def _parts_of(part: Part, in_way: Sequence[str]) -> tuple[tuple[str, str], ...]:
    return (("target", part.name), *(("target", name) for name in sorted(in_way)))


def _no_room(part: Part, in_way: Sequence[str], pads: Pads, after: bool) -> str:
    names = sorted(in_way)
    who = (", ".join(names[:-1]) + " and " + names[-1]) if len(names) > 1 else (names[0] if names else "its neighbours")
    when = "in this order" if after else "in any order"
    return (
        f"no order and approach builds this plan ({when}): {part.name} has no room for the pads, {who} "
        f"{'stand' if len(in_way) > 1 else 'stands'} in the way (a pad is {pads.thickness_m * 1000:.0f} mm thick, "
        f"{pads.width_m * 1000:.0f} mm wide) and no staging pose can push it home from a free side"
    )


def _steps(sequence: Sequence[Part], pads: Pads) -> list[Step]:
    steps = []
    placed: list[tuple[str, Footprint]] = []
    for part in sequence:
        release, _ = choose_release(part, placed, pads)
        assert release is not None
        release = dataclasses.replace(release, room=release_room(part, release, placed, pads))
        after = [*placed, (part.name, part.footprint)]
        steps.append(
            Step(
                part=part,
                release=release,
                push_towards=free_push_directions(part, after, pads),
                neighbours=neighbours_of(part, placed),
                restage=restage_releases(part, after, pads),
            )
        )
        placed = after
    return steps


def start_clearance_m(start_half_diagonal_m: float, pads: Pads) -> float:
    """How far a part's start (its centre) keeps from another part's target footprint.

    Two things come near: the pads picking it (open to the stroke, at any yaw) must not reach the
    other target's footprint, and the pads working at that target (a push starts
    ``push_clearance_m`` behind a face and is a pad's width deep) must not reach it.
    """
    picking = math.hypot(pads.max_opening_m / 2 + pads.thickness_m, pads.width_m / 2)
    working = start_half_diagonal_m + pads.push_clearance_m + pads.width_m
    return max(picking, working) + pads.pad_clearance_m


__all__ = [
    "DIRECTIONS",
    "Footprint",
    "Outline",
    "Pads",
    "Part",
    "Rect",
    "Release",
    "Step",
    "blockers",
    "check_gaps",
    "choose_release",
    "free_push_directions",
    "gap_m",
    "neighbours_of",
    "overlap",
    "plan_layout",
    "push_pads",
    "release_pads",
    "restage_releases",
    "start_clearance_m",
]
