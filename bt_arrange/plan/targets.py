"""A plan's targets: where each part should end, and the threshold its correction leaves.

``Target`` is one part's goal; ``check_threshold`` checks a threshold; ``parts_of`` hands targets to
the layout (``bt_arrange.plan.layout``). The checks of a whole plan are ``bt_arrange.plan.validate``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from bt_arrange.checks import positive_number
from bt_arrange.errors import PlanError
from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import ObjectType, PartOnTable, kind_of, object_type_of
from bt_arrange.plan.layout import Part
from bt_arrange.settings import ManipulationSettings

CORRECT_MODES = ("each", "after_all")
#: The yaw error (degrees) the correction loop leaves by default.
DEFAULT_YAW_THRESHOLD_DEG = 1.0


@dataclass(frozen=True)
class Target(PartOnTable):
    """Where one part should end up: ``colour`` (of its top face), ``x_m``, ``y_m`` and ``yaw_rad`` on the table.

    ``name`` is the object's blackboard namespace (``/<name>/pose``); it defaults to the colour.
    ``object_type`` is its size (default the paper's cube, ``bt_arrange.objects.CUBE``). Several
    targets may share a type and a colour (identical parts): each needs its own name.
    ``z_m`` is the height of the part's bottom face above the table (0: on the table; above, it
    stands on the parts below it, ``bt_arrange.plan.stacking``).
    """

    z_m: float = 0.0

    @property
    def planar(self) -> PlanarPose:
        """The target as a planar pose."""
        return PlanarPose(self.x_m, self.y_m, self.yaw_rad)


def kinds(targets: Iterable[Target]) -> dict[str, tuple[PlanarPose, ...]]:
    """For each target's object, the targets of every part of its kind (type and colour), its own among them.

    Only kinds of several parts (identical parts) are listed; an object alone in its kind is left out.
    """
    plan = list(targets)
    by_kind: dict[tuple[ObjectType, str], list[Target]] = {}
    for target in plan:
        by_kind.setdefault(kind_of(target), []).append(target)
    return {
        target.obj: tuple(t.planar for t in by_kind[kind_of(target)])
        for target in plan
        if len(by_kind[kind_of(target)]) > 1
    }


def footprint_m(target: Target) -> tuple[float, float]:
    """The part's size on the table (x, y in its own frame, metres): its shape's top face."""
    x_m, y_m = object_type_of(target).shape.extent_m
    return float(x_m), float(y_m)


def parts_of(targets: Iterable[Target], settings: ManipulationSettings | None = None) -> list[Part]:
    """The targets as parts for ``bt_arrange.plan.layout``, each asked of its shape, held by the settings' gripper."""
    gripper = (settings or ManipulationSettings()).gripper
    return [Part(t.obj, t.x_m, t.y_m, t.yaw_rad, t.object_type.shape, gripper) for t in targets]


def check_threshold(threshold_mm: object, settings: ManipulationSettings | None = None) -> float:
    """The threshold in millimetres, or a ``PlanError``: it must be a number a push can correct.

    The floor is ``settings.finest_threshold_mm`` (0.07 mm with the default ``finest_push_m`` of
    0.05 mm): below it a correction loop could "push" without moving the arm. A tree built for a
    threshold under ``min_threshold_mm`` (0.28 mm) lowers its ``min_push_m`` to fit
    (``ManipulationSettings.for_threshold``).
    """
    value_mm = positive_number("threshold_mm", threshold_mm, "mm")
    settings = settings or ManipulationSettings()
    floor_mm = settings.finest_threshold_mm
    if value_mm < floor_mm:
        raise PlanError(
            f"threshold {threshold_mm:g} mm is below {floor_mm:.2f} mm, the smallest offset a push can correct "
            f"(pushes shorter than finest_push_m = {settings.finest_push_m * 1000:.2f} mm along an axis are not made)"
        )
    return value_mm
