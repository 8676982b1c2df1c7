"""Arrangements in layers: which part stands on which, whether it stays there, in which order to build.

A target's ``z_m`` is the height of its part's bottom face above the table (``Target.z_m``; a
plan's ``z_mm``). Targets at one height (within ``LEVEL_TOLERANCE_M``) are a **layer**; the
layers are built bottom-up, each by the planar layout of ``bt_arrange.plan.layout`` among its own
parts (``layered_steps``), so that every part below a raised one is down (and corrected) first.

``check_layers`` refuses, before anything moves, one ``PlanError`` per problem naming the target:

- a raised part that stands on nothing: no part's top face lies at its ``z_m`` under its footprint;
- a raised part whose centre of mass (with everything that stands on it alone) lies less than
  ``SUPPORT_MARGIN_M`` inside its support polygon, the convex hull of where its bottom face meets
  the top faces below it;
- two parts that share heights (their vertical extents overlap) and whose footprints overlap;
- a tower taller than the arm allows: the grasp or the approach above a raised target out of reach.

``check_pads_clear`` (after the layout chose each release) refuses a layer the pads cannot reach
without touching a lower part, and ``check_camera_range`` a tower whose top comes closer to the
camera than its depth range. All geometry is planar (the footprints of ``bt_arrange.plan.footprints``)
plus heights; no simulator.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from bt_arrange.errors import PlanError, UnreachableError
from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.plan.footprints import Footprint, Rect, overlap
from bt_arrange.plan.layout import Pads, Step, plan_layout, release_pads
from bt_arrange.plan.layout_part import Part

if TYPE_CHECKING:
    from bt_arrange.plan.camera_view import CameraView
    from bt_arrange.plan.targets import Target
    from bt_arrange.settings import ManipulationSettings

#: Two heights within this (m) are one: a part's bottom meets a top face there. Half a millimetre is
#: what a plan written in whole or tenth millimetres can mean by "the same height".
LEVEL_TOLERANCE_M = 0.0005
#: A raised part's centre of mass must lie at least this far (m) inside its support polygon. It is
#: placed with the error of a centred pick (the part is set down and picked again before it goes on
#: a stack): 0.47 +- 0.29 mm in the paper's simulation, 3.72 +- 2.30 mm on its real cell (Table 1,
#: row 1, after placing). 10 mm covers the real cell's mean plus two standard deviations (8.3 mm)
#: and leaves a push's overshoot to spare, so a part placed that far off still rests until the
#: correction brings it home; a 5 cm cube on a 5 cm cube has 25 mm.
SUPPORT_MARGIN_M = 0.010
#: The top camera's depth does not measure nearer than this (m): the L515's minimum range
#: (shared/FACTS.md), so a top face must stay at least this far from the camera.
CAMERA_MIN_RANGE_M = 0.25
#: The highest TCP searched above a target when saying how high the arm reaches (m), in 5 mm steps.
HIGHEST_SEARCHED_M = 1.5


def layered(targets: Sequence[Target]) -> bool:
    """True when any target stands above the table."""
    return any(t.z_m > LEVEL_TOLERANCE_M for t in targets)


def top_m(target: Target) -> float:
    """The height of the part's top face above the table (m)."""
    return target.z_m + target.object_type.shape.height_m


def layers(targets: Sequence[Target]) -> list[list[Target]]:
    """The targets grouped by height, bottom-up; within a layer, in the plan's order."""
    out: list[list[Target]] = []
    for target in sorted(targets, key=lambda t: t.z_m):
        if out and abs(out[-1][0].z_m - target.z_m) <= LEVEL_TOLERANCE_M:
            out[-1].append(target)
        else:
            out.append([target])
    index = {t.obj: i for i, t in enumerate(targets)}
    return [sorted(layer, key=lambda t: index[t.obj]) for layer in out]


def footprint_of(target: Target, settings: ManipulationSettings) -> Footprint:
    """The target's footprint on the table (a box's rectangle, an outline's convex pieces)."""
    return Part(
        target.obj, target.x_m, target.y_m, target.yaw_rad, target.object_type.shape, settings.gripper
    ).footprint


def polygons(footprint: Footprint) -> list[np.ndarray]:
    """The footprint's convex polygons (each K x 2, counter-clockwise, metres)."""
    if isinstance(footprint, Rect):
        return [np.array(footprint.corners(), dtype=float)]
    return [np.array(piece, dtype=float) for piece in footprint.world_pieces()]


def clip(subject: np.ndarray, clipper: np.ndarray) -> np.ndarray:
    """The intersection of two convex polygons (counter-clockwise), Sutherland-Hodgman; may be empty."""
    out = subject
    for k in range(len(clipper)):
        if len(out) == 0:
            break
        a, b = clipper[k], clipper[(k + 1) % len(clipper)]
        edge = b - a

        def inside(p: np.ndarray, a: np.ndarray = a, edge: np.ndarray = edge) -> bool:
            return bool(edge[0] * (p[1] - a[1]) - edge[1] * (p[0] - a[0]) >= -1e-12)

        points = []
        for i in range(len(out)):
            p, q = out[i], out[(i + 1) % len(out)]
            p_in, q_in = inside(p), inside(q)
            if p_in:
                points.append(p)
            if p_in != q_in:
                d = q - p
                denominator = edge[0] * d[1] - edge[1] * d[0]
                if abs(denominator) > 1e-15:
                    t = (edge[1] * (p[0] - a[0]) - edge[0] * (p[1] - a[1])) / denominator
                    points.append(p + t * d)
        out = np.array(points, dtype=float).reshape(-1, 2)
    return out


def hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of points (N x 2), counter-clockwise (Andrew's monotone chain)."""
    unique = sorted({(round(float(x), 12), round(float(y), 12)) for x, y in points})
    if len(unique) <= 2:
        return np.array(unique, dtype=float).reshape(-1, 2)

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    for p in unique:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, float]] = []
    for p in reversed(unique):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def depth_inside_m(polygon: np.ndarray, x_m: float, y_m: float) -> float:
    """How far ``(x, y)`` lies inside a convex counter-clockwise polygon (m; negative: outside, -inf: no area)."""
    if len(polygon) < 3:
        return -math.inf
    depth = math.inf
    for k in range(len(polygon)):
        a, b = polygon[k], polygon[(k + 1) % len(polygon)]
        edge = b - a
        length = float(np.hypot(*edge))
        if length < 1e-12:
            continue
        depth = min(depth, float(edge[0] * (y_m - a[1]) - edge[1] * (x_m - a[0])) / length)
    return depth


@dataclass(frozen=True)
class Support:
    """What a raised target stands on: the parts below whose top faces meet its bottom, and the polygon of contact."""

    target: Target
    below: tuple[Target, ...]
    #: The convex hull of the contact areas (K x 2, metres), empty when it stands on nothing.
    polygon: np.ndarray


def support_of(target: Target, plan: Sequence[Target], settings: ManipulationSettings) -> Support:
    """The parts whose top face lies at ``target.z_m`` under its footprint, and their contact polygon."""
    mine = polygons(footprint_of(target, settings))
    below: list[Target] = []
    contact: list[np.ndarray] = []
    for other in plan:
        if other.obj == target.obj or abs(top_m(other) - target.z_m) > LEVEL_TOLERANCE_M:
            continue
        touching = [clip(a, b) for a in mine for b in polygons(footprint_of(other, settings))]
        touching = [piece for piece in touching if len(piece) >= 3]
        if touching:
            below.append(other)
            contact.extend(touching)
    polygon = hull(np.vstack(contact)) if contact else np.zeros((0, 2))
    return Support(target, tuple(below), polygon)


def _mass(target: Target) -> float:
    """A part's weight in the balance: its mass, else its volume (one density for every part)."""
    shape = target.object_type.shape
    if target.object_type.mass_kg is not None:
        return target.object_type.mass_kg
    outline = np.asarray(shape.outline_m, dtype=float)
    x, y = outline[:, 0], outline[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    return area * shape.height_m * 700.0  # wood, kg/m^3: only the ratios count


def _carried(target: Target, supports: dict[str, Support]) -> list[Target]:
    """The parts that stand on ``target`` alone, directly or through others that do (it carries all their weight)."""
    carried: dict[str, Target] = {target.obj: target}
    grew = True
    while grew:
        grew = False
        for support in supports.values():
            name = support.target.obj
            if name in carried or not support.below:
                continue
            if all(b.obj in carried for b in support.below):
                carried[name] = support.target
                grew = True
    return list(carried.values())


def _mm(value_m: float) -> str:
    return (
        f"{value_m * 1000:.0f} mm" if abs(value_m * 1000 - round(value_m * 1000)) < 0.05 else f"{value_m * 1000:.1f} mm"
    )


def check_layers(
    plan: Sequence[Target], settings: ManipulationSettings, kinematics: ArmKinematics | None = None
) -> None:
    """Refuse a layered plan no cell could build: see the module's list. Nothing for a plan on the table alone."""
    for target in plan:
        if not math.isfinite(target.z_m) or target.z_m < 0.0:
            raise PlanError(
                f"target {target.obj}: z_m = {target.z_m!r} must be 0 (on the table) or more, the height of its "
                "bottom face",
                parts=(("target", target.obj),),
            )
    if not layered(plan):
        return
    _check_overlaps(plan, settings)
    supports = {t.obj: support_of(t, plan, settings) for t in plan if t.z_m > LEVEL_TOLERANCE_M}
    for target in plan:
        support = supports.get(target.obj)
        if support is None:
            continue
        if not support.below:
            tops = sorted(
                {
                    _mm(top_m(o))
                    for o in plan
                    if o.obj != target.obj and overlap(footprint_of(o, settings), footprint_of(target, settings))
                }
            )
            under = f" (the tops under it lie at {', '.join(tops)})" if tops else " (nothing lies under its footprint)"
            raise PlanError(
                f"target {target.obj} at z {_mm(target.z_m)} stands on nothing: no part's top face is at "
                f"{_mm(target.z_m)} under its footprint{under}",
                parts=(("target", target.obj),),
            )
    for target in plan:
        support = supports.get(target.obj)
        if support is None:
            continue
        carried = _carried(target, supports)
        weights = [_mass(t) for t in carried]
        x_m = sum(w * t.x_m for w, t in zip(weights, carried, strict=True)) / sum(weights)
        y_m = sum(w * t.y_m for w, t in zip(weights, carried, strict=True)) / sum(weights)
        depth = depth_inside_m(support.polygon, x_m, y_m)
        if depth < SUPPORT_MARGIN_M:
            on = ", ".join(b.obj for b in support.below)
            others = len(carried) - 1
            whose = f" (with the {others} part{'s' if others > 1 else ''} standing on it)" if others else ""
            where = "outside" if depth < 0 else "inside"
            raise PlanError(
                f"target {target.obj} at z {_mm(target.z_m)}: its centre of mass{whose} lies "
                f"{abs(depth) * 1000:.1f} mm {where} the support of {on} below it, and must lie at least "
                f"{SUPPORT_MARGIN_M * 1000:.0f} mm inside (bt_arrange.plan.stacking.SUPPORT_MARGIN_M: the placing "
                "error before a correction): move it over its support",
                parts=(("target", target.obj), *(("target", b.obj) for b in support.below)),
            )
    _check_arm_height(plan, settings, kinematics or ArmKinematics())


def _check_overlaps(plan: Sequence[Target], settings: ManipulationSettings) -> None:
    """Two parts whose vertical extents overlap must not overlap on the table."""
    for i, first in enumerate(plan):
        for second in plan[i + 1 :]:
            shared_m = min(top_m(first), top_m(second)) - max(first.z_m, second.z_m)
            if shared_m <= LEVEL_TOLERANCE_M:
                continue
            if overlap(footprint_of(first, settings), footprint_of(second, settings)):
                same = abs(first.z_m - second.z_m) <= LEVEL_TOLERANCE_M
                heights = (
                    f"both at z {_mm(first.z_m)}"
                    if same
                    else f"at z {_mm(first.z_m)} to {_mm(top_m(first))} and {_mm(second.z_m)} to {_mm(top_m(second))}"
                )
                raise PlanError(
                    f"targets {first.obj} and {second.obj} overlap, {heights}: two parts at one height cannot "
                    "share a place on the table",
                    parts=(("target", first.obj), ("target", second.obj)),
                )


def _check_arm_height(plan: Sequence[Target], settings: ManipulationSettings, kinematics: ArmKinematics) -> None:
    """Every raised target's grasp and approach must be reachable: else the tower is taller than the arm allows."""
    for target in plan:
        if target.z_m <= LEVEL_TOLERANCE_M:
            continue
        grasp_m, approach_m, _ = raised_heights_m(settings, target)
        for height_m in (grasp_m, approach_m):
            try:
                kinematics.check_reachable(gripper_down_pose(target.x_m, target.y_m, height_m, target.yaw_rad))
            except UnreachableError:
                highest = _highest_reach_m(kinematics, target)
                reach = (
                    "the arm reaches no height there"
                    if highest is None
                    else f"the TCP reaches up to {_mm(highest)} there"
                )
                raise PlanError(
                    f"target {target.obj} at z {_mm(target.z_m)}: the tower is taller than the arm allows: "
                    f"the pads must come to {_mm(height_m)} above it ({'grasp' if height_m == grasp_m else 'approach'}"
                    f"), {reach}",
                    parts=(("target", target.obj),),
                ) from None


def _highest_reach_m(kinematics: ArmKinematics, target: Target) -> float | None:
    highest = None
    for step in range(int(HIGHEST_SEARCHED_M / 0.005) + 1):
        height_m = step * 0.005
        try:
            kinematics.check_reachable(gripper_down_pose(target.x_m, target.y_m, height_m, target.yaw_rad))
        except UnreachableError:
            continue
        highest = height_m
    return highest


def raised_heights_m(settings: ManipulationSettings, target: Target) -> tuple[float, float, float]:
    """(grasp, approach, push) TCP heights above the table for a part standing at ``target.z_m``."""
    return heights_at_m(settings, target.object_type.shape, target.z_m)


def heights_at_m(settings: ManipulationSettings, shape: object, z_m: float) -> tuple[float, float, float]:
    """(grasp, approach, push) TCP heights for a part of ``shape`` whose bottom face is ``z_m`` above the table.

    The grasp and the push keep their height above the part's bottom; the approach keeps
    ``approach_clearance_m`` above its top, never lower than ``approach_height_m``.
    """
    grasp_m, approach_m, push_m = settings.tcp_heights_m(shape)  # type: ignore[arg-type]
    if z_m == 0.0:
        return grasp_m, approach_m, push_m
    height_m = float(shape.height_m)  # type: ignore[attr-defined]
    return grasp_m + z_m, max(approach_m, z_m + height_m + settings.approach_clearance_m), push_m + z_m


def layered_steps(
    plan: Sequence[Target], settings: ManipulationSettings, order: Sequence[str] | None = None
) -> list[Step]:
    """The build order, bottom-up by layer, each layer laid out by ``plan_layout`` among its own parts.

    ``order`` (object names) orders the parts within each layer; it must name every part once.
    """
    from bt_arrange.plan.targets import parts_of

    pads = Pads.from_settings(settings)
    if order is not None:
        names = list(order)
        if sorted(names) != sorted(t.obj for t in plan):
            raise PlanError(f"order {names} must name each part once: {', '.join(t.obj for t in plan)}")
    steps: list[Step] = []
    for layer in layers(plan):
        within = None if order is None else [n for n in order if n in {t.obj for t in layer}]
        steps.extend(plan_layout(parts_of(layer, settings), pads, within))
    by_obj = {t.obj: t for t in plan}
    check_pads_clear([(by_obj[st.part.name], st) for st in steps], plan, settings)
    return steps


def check_pads_clear(
    steps: Sequence[tuple[Target, Step]], plan: Sequence[Target], settings: ManipulationSettings
) -> None:
    """Refuse a raised part whose pads, releasing it, come down onto a lower part taller than their bottoms."""
    pads = Pads.from_settings(settings)
    clearance_m = settings.gripper.table_clearance_m
    for target, step in steps:
        if target.z_m <= LEVEL_TOLERANCE_M:
            continue
        if step.release.staged:
            _check_staged_support(target, step, plan, settings)
        grasp_m, _, _ = raised_heights_m(settings, target)
        pad_bottom_m = grasp_m - settings.gripper.pad_half_height_m
        volumes = release_pads(step.part, step.part.footprint, step.release.axis, pads)
        for other in plan:
            if other.z_m >= target.z_m - LEVEL_TOLERANCE_M or top_m(other) <= pad_bottom_m - clearance_m + 1e-9:
                continue
            if any(
                overlap(volume, footprint_of(other, settings), settings.gripper.neighbour_clearance_m)
                for volume in volumes
            ):
                raise PlanError(
                    f"target {target.obj} at z {_mm(target.z_m)}: the pads releasing it come down to "
                    f"{_mm(pad_bottom_m)}, onto {other.obj} below, whose top is at {_mm(top_m(other))}: the gripper "
                    f"cannot reach this layer "
                    f"without touching a lower part (keep the lower part's top {clearance_m * 1000:.0f} mm under the "
                    "pads, or move it out of their way)",
                    parts=(("target", target.obj), ("target", other.obj)),
                )


def _check_staged_support(target: Target, step: Step, plan: Sequence[Target], settings: ManipulationSettings) -> None:
    """A raised part released off its target (to be pushed home) must stand there too, with the margin."""
    dx_m, dy_m = step.release.staging_m
    c, s = math.cos(target.yaw_rad), math.sin(target.yaw_rad)
    staged = dataclasses.replace(target, x_m=target.x_m + c * dx_m - s * dy_m, y_m=target.y_m + s * dx_m + c * dy_m)
    others = [t for t in plan if t.obj != target.obj]
    depth = depth_inside_m(support_of(staged, [*others, staged], settings).polygon, staged.x_m, staged.y_m)
    if depth < SUPPORT_MARGIN_M:
        raise PlanError(
            f"target {target.obj} at z {_mm(target.z_m)}: its neighbours leave the pads no room at its target, and "
            f"released {math.hypot(dx_m, dy_m) * 1000:.0f} mm off it to be pushed home its centre of mass would lie "
            f"{depth * 1000:.1f} mm inside its support, under the {SUPPORT_MARGIN_M * 1000:.0f} mm margin: leave "
            "room for the pads beside it (a gap of two pads and their clearances), or support it further out",
            parts=(("target", target.obj),),
        )


def check_camera_range(plan: Sequence[Target], view: CameraView) -> None:
    """Refuse a top face nearer the camera than ``CAMERA_MIN_RANGE_M`` along its optical axis."""
    position = view.camera_pose_world.position_m
    axis = view.camera_pose_world.rotation[:, 2]
    for target in plan:
        point = np.array([target.x_m, target.y_m, top_m(target)])
        range_m = float((point - position) @ axis)
        if range_m < CAMERA_MIN_RANGE_M:
            highest_m = top_m(target) - (CAMERA_MIN_RANGE_M - range_m)
            raise PlanError(
                f"target {target.obj}: its top face at {_mm(top_m(target))} is {range_m * 1000:.0f} mm from the "
                f"camera, nearer than its depth's {CAMERA_MIN_RANGE_M * 1000:.0f} mm: the tower is taller than "
                f"the camera allows (top faces up to {_mm(highest_m)} there)",
                parts=(("target", target.obj),),
            )


#: A lower part's top face counts as hidden when a part above comes within this (m) of its footprint:
#: the top camera looks down at a slant, so a part 5 cm higher and 10 cm off the optical axis hides
#: about 8 mm more of what lies beside it (70 cm camera: 50 mm x 100 / 600).
OCCLUSION_MARGIN_M = 0.01
#: A lower part counts as below a raised one when their footprints come within this (m): the layout's
#: neighbours (``bt_arrange.plan.layout.neighbours_of``), so a tower's base and the parts around it, not a far one.
BELOW_WITHIN_M = 0.03


def stack_settings(plan: Sequence[Target], settings: ManipulationSettings) -> ManipulationSettings:
    """The settings with ``approach_height_m`` over the plan's highest top face (unchanged on the table alone)."""
    if not layered(plan):
        return settings
    highest_m = max(top_m(t) for t in plan)
    approach_m = highest_m + settings.approach_clearance_m
    if approach_m <= settings.approach_height_m:
        return settings
    return dataclasses.replace(settings, approach_height_m=approach_m)


def check_correct_mode(plan: Sequence[Target], correct: str) -> None:
    """A plan in layers is corrected part by part: ``correct="after_all"`` is refused for it."""
    if correct == "after_all" and layered(plan):
        raised = next(t for t in plan if t.z_m > LEVEL_TOLERANCE_M)
        raise PlanError(
            f'correct = "after_all" places every part before correcting any, but target {raised.obj} stands on '
            'others: a plan in layers corrects each part before the next is put on it (correct = "each")',
            parts=(("target", raised.obj),),
        )


def same_layer(first: Target, second: Target) -> bool:
    """True when two targets stand at one height."""
    return abs(first.z_m - second.z_m) <= LEVEL_TOLERANCE_M


def hidden(lower: Target, placed: Sequence[Target], settings: ManipulationSettings) -> bool:
    """True when a part placed above ``lower`` comes within ``OCCLUSION_MARGIN_M`` of its footprint."""
    footprint = footprint_of(lower, settings)
    return any(
        other.z_m > lower.z_m + LEVEL_TOLERANCE_M
        and overlap(footprint, footprint_of(other, settings), OCCLUSION_MARGIN_M)
        for other in placed
    )


def watched_below(target: Target, placed: Sequence[Target], settings: ManipulationSettings) -> list[Target]:
    """The parts placed before ``target``, lower than it, that the camera still sees once it is down.

    Only for a raised target: placing one on the table is the planar layout's business (neighbours).
    """
    if target.z_m <= LEVEL_TOLERANCE_M:
        return []
    down = [*placed, target]
    near = footprint_of(target, settings)
    return [
        p
        for p in placed
        if p.z_m < target.z_m - LEVEL_TOLERANCE_M
        and overlap(near, footprint_of(p, settings), BELOW_WITHIN_M)
        and not hidden(p, down, settings)
    ]
