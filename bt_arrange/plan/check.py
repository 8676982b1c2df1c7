"""The plan check that knows the cell: one function, run before anything moves.

``check_plan`` takes what a run is about to do (the targets, the threshold, where the parts start)
and what the cell is (the top camera's view, the colours it can tell apart) and raises one
``PlanError`` naming the first problem:

- every target is well formed and reachable, and the plan can be built among neighbours: an order
  and, per part, where the pads go (``validate_targets``, by the geometry of ``bt_arrange.plan.layout``);
- the threshold is one a push can correct (``check_threshold``: not below
  ``ManipulationSettings.min_threshold_mm``);
- every start is well formed, of a known colour, alone in its colour and name, clear of the other
  parts, and far enough from the other objects' targets for the pads picking it and working there
  (``layout.start_clearance_m``), and reachable;
- every target's object is in the scene, in the target's colour;
- every target and every start lies inside the top camera's view with a margin
  (``CameraView.margin_m``).

The camera's view is data: a ``CameraView`` is the camera's intrinsics and pose, which the backend
hands in (the simulated cell builds one from its camera configuration without starting a world; a
real cell would from its calibration). Tree files, the Python API (``bt_arrange_sim.pybullet.runs.SimulatedRun``)
and plan files all call this one function.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from bt_arrange.checks import at_mm, finite_number
from bt_arrange.errors import PlanError, UnreachableError
from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.objects import ObjectType, object_type_of
from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.plan import stacking
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.plan.footprints import overlap
from bt_arrange.plan.layout import Pads, Rect, gap_m, start_clearance_m
from bt_arrange.plan.targets import Target, check_threshold, parts_of
from bt_arrange.plan.validate import reach_text, validate_targets
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import folded_yaw, min_centre_distance_m, told_apart
from bt_arrange.suggest import did_you_mean


@dataclass(frozen=True)
class PlanSource:
    """Where a plan's parts were written: a file and, per ``(role, name)`` of ``PlanError.parts``, its entry.

    ``locate(error)`` puts the file and the entries in front of a plan check's message
    (``four_cubes.toml: [[targets]] 3: target blue ...``): a plan file's errors name where to fix them.
    """

    path: str
    entries: Mapping[tuple[str, str], str]

    def locate(self, error: PlanError) -> PlanError:
        """The error with the file and its entries in front (unchanged when it names the file already)."""
        if str(error).startswith(f"{self.path}:"):
            return error
        found: list[str] = []
        for part in getattr(error, "parts", ()):
            entry = self.entries.get(part)
            if entry is not None and entry not in found:
                found.append(entry)
        where = f" {' and '.join(found)}:" if found else ""
        located = PlanError(
            f"{self.path}:{where} {error}",
            parts=error.parts,
            field=error.field,
            value=error.value,
            limit=error.limit,
            unit=error.unit,
        )
        return located


def _start_name(start: Any) -> str:
    return getattr(start, "name", None) or start.colour


def check_scene(
    starts: Iterable[object],
    *,
    view: CameraView | None = None,
    colours: Iterable[str] | None = None,
    kinematics: ArmKinematics | None = None,
    settings: ManipulationSettings | None = None,
) -> list[Any]:
    """Check where the parts start; parts of one colour must be of one type (identical parts).

    A start is anything with ``colour``, ``x_m``, ``y_m``, ``yaw_rad``, ``name`` and optionally
    ``object_type``.
    """
    if isinstance(starts, (str, bytes)) or not isinstance(starts, Iterable):
        raise PlanError(f"the scene must be a list of part starts (colour, x_m, y_m, yaw_rad), got {starts!r}")
    scene: list[Any] = list(starts)
    known = list(colours) if colours is not None else list(DEFAULT_COLOUR_TABLE.names)
    settings = settings or ManipulationSettings()
    kinematics = kinematics or ArmKinematics()
    names: dict[str, int] = {}
    by_colour: dict[str, list[tuple[ObjectType, int]]] = {}
    for index, start in enumerate(scene, start=1):
        colour = getattr(start, "colour", None)
        if not isinstance(colour, str):
            raise PlanError(f"part {index} of the scene is {start!r}, not a part start (colour, x_m, y_m, yaw_rad)")
        for field in ("x_m", "y_m", "yaw_rad"):
            finite_number(field, getattr(start, field, None), where=f"part {index} of the scene ({colour}): ")
        name = getattr(start, "name", None)
        if name is not None and (not isinstance(name, str) or not name):
            raise PlanError(f"part {index} of the scene ({colour}): name={name!r} is not a non-empty string")
        if colour not in known:
            raise PlanError(
                f"part {index} of the scene: unknown colour {colour!r}{did_you_mean(colour, known)}; "
                f"the cell knows {', '.join(known)}",
                parts=(("start", _start_name(start)),),
            )
        if _start_name(start) in names:
            raise PlanError(
                f"parts {names[_start_name(start)]} and {index} of the scene are both named {_start_name(start)!r}",
                parts=(("start", _start_name(start)),),
            )
        kind = object_type_of(start)
        seen = next(
            (
                (other, first)
                for other, first in by_colour.get(colour, [])
                if other != kind and not told_apart(other.shape, kind.shape)
            ),
            None,
        )
        if seen is not None:
            raise PlanError(
                f"parts {seen[1]} and {index} of the scene are both {colour} but of types {seen[0].name!r} and "
                f"{kind.name!r}: the camera tells parts apart by colour, so one colour is one type "
                "(irregular parts of different outlines may share one)",
                parts=(("start", _start_name(scene[seen[1] - 1])), ("start", _start_name(start))),
            )
        names[_start_name(start)] = index
        by_colour.setdefault(colour, []).append((kind, index))
    for index, start in enumerate(scene, start=1):
        kind = object_type_of(start)
        where = f"part {_start_name(start)} starts at {at_mm(start.x_m, start.y_m)}"
        this = (("start", _start_name(start)),)
        if view is not None and not view.sees_part(start.x_m, start.y_m, start.yaw_rad, kind):
            raise PlanError(f"{where}, outside the camera's view{_view_text(view, kind.shape.height_m)}", parts=this)
        grasp_m, _, _ = settings.tcp_heights_m(kind.shape)
        yaw = folded_yaw(kind.shape, start.yaw_rad)
        pick = gripper_down_pose(start.x_m, start.y_m, grasp_m, yaw)
        try:
            kinematics.check_reachable(pick)
        except UnreachableError as error:
            raise PlanError(
                f"{where}, out of the arm's reach: {reach_text(kinematics, start.x_m, start.y_m, grasp_m, yaw, error)}",
                parts=this,
            ) from error
        for other in scene[index:]:
            distance_m = math.hypot(start.x_m - other.x_m, start.y_m - other.y_m)
            other_shape = object_type_of(other).shape
            least_m = min_centre_distance_m(kind.shape, other_shape)
            # Closer than their sweep radii, two parts may still lie side by side: only footprints that
            # overlap (beyond the contact's tolerance) are refused. Parts that touch at the start are
            # a real table's, and the tree separates them before it picks them (``Separate``).
            if distance_m < least_m and starts_overlap(start, other, settings):
                both_cubes = kind.shape == other_shape and other_shape.is_cube
                what = "a cube's diagonal" if both_cubes else "their half diagonals"
                raise PlanError(
                    f"parts {_start_name(start)} and {_start_name(other)} start {distance_m * 1000:.0f} mm apart: "
                    f"closer than {what} ({least_m * 1000:.0f} mm), they would overlap: move them "
                    f"{(least_m - distance_m) * 1000:.0f} mm further apart",
                    parts=(("start", _start_name(start)), ("start", _start_name(other))),
                )
    return scene


#: Two starts' footprints may interpenetrate this much (m) and still count as touching, not overlapping:
#: a scene written in millimetres that sets two faces against each other rounds to a tenth or so.
TOUCHING_TOLERANCE_M = 0.0002


def starts_overlap(first: Any, second: Any, settings: ManipulationSettings) -> bool:
    """True when two starts' footprints overlap by more than ``TOUCHING_TOLERANCE_M`` (touching is no overlap)."""
    return overlap(
        stacking.footprint_of(_as_target(first), settings),
        stacking.footprint_of(_as_target(second), settings),
        -TOUCHING_TOLERANCE_M,
    )


def _as_target(start: Any) -> Target:
    """A start as a target at its pose (the footprint's only inputs: where, how turned, which shape)."""
    return Target(
        start.colour, start.x_m, start.y_m, start.yaw_rad, name=_start_name(start), object_type=object_type_of(start)
    )


def _view_text(view: CameraView, top_z_m: float) -> str:
    x0, x1, y0, y1 = view.table_extent_m(top_z_m)
    if not all(math.isfinite(v) for v in (x0, x1, y0, y1)):
        return ""
    return (
        f" (at the height of its top face it sees about x {x0 * 1000:.0f} to {x1 * 1000:.0f} mm, "
        f"y {y0 * 1000:.0f} to {y1 * 1000:.0f} mm; the whole top face and {view.margin_m * 1000:.0f} mm around it "
        "must be in the image: the usable area is drawn in docs/plans.md)"
    )


def check_plan(
    targets: Iterable[object],
    *,
    threshold_mm: object = None,
    starts: Iterable[object] | None = None,
    view: CameraView | None = None,
    colours: Iterable[str] | None = None,
    kinematics: ArmKinematics | None = None,
    settings: ManipulationSettings | None = None,
) -> list[Target]:
    """Check a whole run before anything moves; return the targets. A ``PlanError`` names the first problem.

    ``threshold_mm``, ``starts`` and ``view`` are checked when given: a tree builder knows only the
    targets and the threshold, a run in a cell knows the scene and the camera too.
    """
    settings = settings or ManipulationSettings()
    kinematics = kinematics or ArmKinematics()
    plan = validate_targets(targets, colours=colours, kinematics=kinematics, settings=settings)
    if threshold_mm is not None:
        check_threshold(threshold_mm, settings)
    if view is not None:
        stacking.check_camera_range(plan, view)
        for target in plan:
            if not view.sees_part(target.x_m, target.y_m, target.yaw_rad, target.object_type, target.z_m):
                height_m = target.z_m + target.object_type.shape.height_m
                raise PlanError(
                    f"target {target.obj} at {at_mm(target.x_m, target.y_m)} is outside the camera's view"
                    f"{_view_text(view, height_m)}: the part could be placed there but never inspected",
                    parts=(("target", target.obj),),
                )
    if starts is None:
        return plan
    scene = check_scene(starts, view=view, colours=colours, kinematics=kinematics, settings=settings)
    by_name = {_start_name(start): start for start in scene}
    for target in plan:
        start = by_name.get(target.obj)
        if start is None:
            present = ", ".join(sorted(by_name)) or "none"
            raise PlanError(
                f"target {target.obj}: no part {target.obj!r} in the scene (the scene has {present})"
                f"{did_you_mean(target.obj, by_name)}",
                parts=(("target", target.obj),),
            )
        if start.colour != target.colour:
            raise PlanError(
                f"target {target.obj} is {target.colour} but the scene's part {target.obj} is {start.colour}",
                parts=(("target", target.obj), ("start", target.obj)),
            )
        if object_type_of(start) != target.object_type:
            raise PlanError(
                f"target {target.obj} is a {target.object_type.name} ({target.object_type.size_text}) but the "
                f"scene's {target.obj} is a {object_type_of(start).name} ({object_type_of(start).size_text})",
                parts=(("target", target.obj), ("start", target.obj)),
            )
    pads = Pads.from_settings(settings)
    for part in parts_of(plan, settings):
        for start in scene:
            if _start_name(start) == part.name:
                continue
            start_kind = object_type_of(start)
            # The circle the start's top face sweeps as it turns.
            need_m = start_clearance_m(start_kind.shape.sweep_radius_m, pads)
            gap = gap_m(Rect(start.x_m, start.y_m, 0.0, 0.0, 0.0), part.footprint)
            if gap < need_m:
                raise PlanError(
                    f"part {_start_name(start)} starts {gap * 1000:.0f} mm from {part.name}'s target: the pads picking "
                    f"it or working at that target need {need_m * 1000:.0f} mm between its centre and the target's "
                    f"footprint: move it {(need_m - gap) * 1000:.0f} mm further away",
                    parts=(("start", _start_name(start)), ("target", part.name)),
                )
    return plan


def check_puzzles(
    puzzles: Iterable[Any],
    targets: Iterable[Target],
    threshold_mm: float,
    settings: ManipulationSettings | None = None,
) -> None:
    """A ``PlanError`` for a puzzle that the run would fail on for sure, named as the plan names it.

    A slab's gap under twice the threshold (two pieces, each within the threshold, could meet and
    the layout would refuse the solved places); a slab that overlaps another slab or a target (its
    pieces would land on them); a target of a slab's colour (the camera tells parts apart by colour).
    """
    settings = settings or ManipulationSettings()
    specs = list(puzzles)
    plan = list(targets)
    clearance_m = settings.gap_for_threshold_m(threshold_mm)

    def slab(spec: Any) -> Rect:
        # The reassembled whole: its size and a gap along each side for the fractures' gaps it carries.
        return Rect(spec.x_m, spec.y_m, spec.yaw_rad, spec.size_m[0] / 2 + spec.gap_m, spec.size_m[1] / 2 + spec.gap_m)

    for index, spec in enumerate(specs):
        gap_mm = spec.gap_m * 1000
        if gap_mm < 2 * threshold_mm - 1e-9:
            raise PlanError(
                f"[puzzle.{spec.name}]: gap_mm = {gap_mm:g} is under twice the threshold ({2 * threshold_mm:g} mm at "
                f"threshold_mm = {threshold_mm:g}): two pieces each within the threshold could meet; make gap_mm at "
                f"least {2 * threshold_mm:g} or threshold_mm at most {gap_mm / 2:g}",
                parts=(("puzzle", spec.name),),
            )
        for other in specs[index + 1 :]:
            if overlap(slab(spec), slab(other), clearance_m):
                raise PlanError(
                    f"[puzzle.{spec.name}] and [puzzle.{other.name}]: the two slabs overlap where they are put "
                    "back together: move one of them",
                    parts=(("puzzle", spec.name), ("puzzle", other.name)),
                )
        for number, target in enumerate(plan, start=1):
            if target.colour == spec.colour:
                raise PlanError(
                    f"target {number} ({target.obj}) is {target.colour}, the colour of [puzzle.{spec.name}]'s pieces: "
                    "the camera tells parts apart by colour, so a puzzle's colour is its own",
                    parts=(("target", target.obj), ("puzzle", spec.name)),
                )
            if overlap(slab(spec), stacking.footprint_of(target, settings), clearance_m):
                raise PlanError(
                    f"target {number} ({target.obj}) lies where [puzzle.{spec.name}] is put back together: "
                    "move the target or the slab",
                    parts=(("target", target.obj), ("puzzle", spec.name)),
                )
