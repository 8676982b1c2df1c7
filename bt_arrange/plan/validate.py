"""The checks of a whole plan before anything moves, and its layout's steps.

``validate_targets`` checks fields, colours, names, reach, layers and the layout of ``plan_steps``;
``reach_text`` says in millimetres why a point is out of the arm's reach.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from bt_arrange.checks import at_mm, finite_number
from bt_arrange.errors import PlanError, UnreachableError
from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.objects import ObjectType
from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.plan import stacking
from bt_arrange.plan.layout import Pads, Step, plan_layout
from bt_arrange.plan.targets import Target, parts_of
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import told_apart
from bt_arrange.suggest import did_you_mean


def validate_targets(
    targets: Iterable[object],
    *,
    colours: Iterable[str] | None = None,
    kinematics: ArmKinematics | None = None,
    settings: ManipulationSettings | None = None,
) -> list[Target]:
    """Check a plan before anything moves; a ``PlanError`` names the first problem.

    Malformed entries, unknown colours, two targets for one object, one colour on two types, a
    target out of the arm's reach, and a plan no order and approach can build (``plan_steps``:
    targets that overlap or lie closer than 2 mm, a part the pads find no room beside, each part's
    footprint its type's size) are each a clear error. Targets of one type and colour are
    identical parts (each with its own name).
    """
    if isinstance(targets, (str, bytes)) or not isinstance(targets, Iterable):
        raise PlanError(f"targets must be a list of Target(colour, x_m, y_m, yaw_rad), got {targets!r}")
    plan = list(targets)
    if not plan:
        raise PlanError("no targets: an arrangement needs at least one Target(colour, x_m, y_m, yaw_rad)")
    known = list(colours) if colours is not None else list(DEFAULT_COLOUR_TABLE.names)
    settings = settings or ManipulationSettings()
    names: dict[str, int] = {}
    type_of_colour: dict[str, list[tuple[ObjectType, int]]] = {}
    for index, target in enumerate(plan, start=1):
        if not isinstance(target, Target):
            raise PlanError(f"target {index} is {target!r}, not a Target(colour, x_m, y_m, yaw_rad)")
        for field_name in ("x_m", "y_m", "yaw_rad", "z_m"):
            finite_number(field_name, getattr(target, field_name), where=f"target {index} ({target.colour}): ")
        _check_metres(target, index)
        if not isinstance(target.object_type, ObjectType):
            raise PlanError(f"target {index} ({target.obj}): object_type {target.object_type!r} is not an ObjectType")
        if target.colour not in known:
            raise PlanError(
                f"target {index}: unknown colour {target.colour!r}{did_you_mean(target.colour, known)}; "
                f"known colours: {', '.join(known)}",
                parts=(("target", target.obj),),
            )
        if target.obj in names:
            first_index = names[target.obj]
            hint = (
                f" (identical parts need a name each, e.g. name='{target.colour} 1' and name='{target.colour} 2')"
                if target.name is None
                else ""
            )
            raise PlanError(
                f"targets {first_index} and {index} are both named {target.obj!r}{hint}",
                parts=(("target", target.obj),),
            )
        names[target.obj] = index
        seen = next(
            (
                (kind, first)
                for kind, first in type_of_colour.get(target.colour, [])
                if kind != target.object_type and not told_apart(kind.shape, target.object_type.shape)
            ),
            None,
        )
        if seen is not None:
            raise PlanError(
                f"targets {seen[1]} and {index} are both {target.colour} but of types {seen[0].name!r} and "
                f"{target.object_type.name!r}: the camera tells parts apart by colour, so one colour is one type "
                "(irregular parts of different outlines may share one)",
                parts=(("target", str(getattr(plan[seen[1] - 1], "obj", ""))), ("target", target.obj)),
            )
        type_of_colour.setdefault(target.colour, []).append((target.object_type, index))
    checked = [target for target in plan if isinstance(target, Target)]
    for target in checked:
        problem = target.object_type.mass_problem(settings)
        if problem is not None:
            raise PlanError(
                f"target {target.obj}: a {target.object_type.name} of {problem}",
                parts=(("object", target.object_type.name), ("target", target.obj)),
            )
    kinematics = kinematics or ArmKinematics()
    # Layers: heights, support, overlaps between heights, the arm's reach above a tower.
    stacking.check_layers(checked, settings, kinematics)
    for target in checked:
        grasp_m, approach_m, _ = stacking.raised_heights_m(settings, target)
        for height_m in (grasp_m, approach_m):
            try:
                kinematics.check_reachable(gripper_down_pose(target.x_m, target.y_m, height_m, target.yaw_rad))
            except UnreachableError as error:
                raise PlanError(
                    f"target {target.obj} at {at_mm(target.x_m, target.y_m)} is out of reach: "
                    f"{reach_text(kinematics, target.x_m, target.y_m, height_m, target.yaw_rad, error)}",
                    parts=(("target", target.obj),),
                ) from error
    plan_steps(checked, settings)
    return checked


#: A position in metres beyond this (m) looks like millimetres: the UR5 reaches 0.85 m from its base.
LOOKS_LIKE_MILLIMETRES_M = 3.0


def _check_metres(target: Target, index: int) -> None:
    """A ``PlanError`` for a position written in millimetres where metres are meant (``x_m=500`` for 0.5 m)."""
    for field_name in ("x_m", "y_m", "z_m"):
        value = float(getattr(target, field_name))
        if abs(value) > LOOKS_LIKE_MILLIMETRES_M:
            raise PlanError(
                f"target {index} ({target.obj}): {field_name}={value:g} looks like millimetres: a Target is in "
                f"metres ({field_name}={value / 1000:g} for {value:g} mm)",
                parts=(("target", target.obj),),
            )


def reach_band_m(
    kinematics: ArmKinematics, x_m: float, y_m: float, height_m: float, yaw_rad: float
) -> tuple[float, float] | None:
    """How near and how far from the arm's base axis, towards (x, y), the pads reach at ``height_m``.

    ``(nearest, farthest)`` in metres on the table (the geometric checks of ``check_reachable``,
    no inverse kinematics: cheap), or None when no distance up to 2 m is reachable that way.
    """
    base = kinematics.base_pose_world.position_m
    dx, dy = x_m - float(base[0]), y_m - float(base[1])
    length = math.hypot(dx, dy)
    ux, uy = (dx / length, dy / length) if length > 1e-9 else (1.0, 0.0)
    reachable = []
    for step in range(401):  # every 5 mm out to 2 m
        r_m = step * 0.005
        pose = gripper_down_pose(float(base[0]) + ux * r_m, float(base[1]) + uy * r_m, height_m, yaw_rad)
        try:
            kinematics.check_reachable(pose)
        except UnreachableError:
            continue
        reachable.append(r_m)
    return (min(reachable), max(reachable)) if reachable else None


def reach_text(
    kinematics: ArmKinematics, x_m: float, y_m: float, height_m: float, yaw_rad: float, error: UnreachableError
) -> str:
    """Why (x, y) is out of reach, in mm, with the fix: how far the arm reaches that way (no raw pose)."""
    base = kinematics.base_pose_world.position_m
    r_mm = math.hypot(x_m - float(base[0]), y_m - float(base[1])) * 1000
    band = reach_band_m(kinematics, x_m, y_m, height_m, yaw_rad)
    if band is None:
        return f"the arm reaches no point that way at a TCP height of {height_m * 1000:.0f} mm"
    near_mm, far_mm = band[0] * 1000, band[1] * 1000
    reaches = f"in that direction the arm reaches {near_mm:.0f} to {far_mm:.0f} mm from its base axis"
    if r_mm > far_mm:
        return f"it lies {r_mm:.0f} mm from the base axis; {reaches}: move it at least {r_mm - far_mm:.0f} mm closer"
    if r_mm < near_mm:
        return f"it lies {r_mm:.0f} mm from the base axis; {reaches}: move it at least {near_mm - r_mm:.0f} mm out"
    reason = str(error).split(": ", 1)[-1] if "Pose(" in str(error) else str(error)
    return f"{reason} ({reaches})"


def plan_steps(
    targets: Sequence[Target], settings: ManipulationSettings | None = None, order: Sequence[str] | None = None
) -> list[Step]:
    """The layout's steps (``bt_arrange.plan.layout.plan_layout``): the placing order and each part's approach.

    A plan in layers is laid out layer by layer, bottom-up (``bt_arrange.plan.stacking.layered_steps``).
    """
    settings = settings or ManipulationSettings()
    if stacking.layered(targets):
        return stacking.layered_steps(targets, settings, order)
    return plan_layout(parts_of(targets, settings), Pads.from_settings(settings), order)
