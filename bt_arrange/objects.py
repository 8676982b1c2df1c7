"""Object types: what a user brings to the table, a named shape with the simulator's physics.

An :class:`ObjectType` is a name and a :class:`~bt_arrange.shapes.Shape`: a
:class:`~bt_arrange.shapes.Prism` of any outline, or the box ``Prism.box(x, y, z)`` that
``ObjectType(name, size_m)`` makes (metres; z is its height on the table). The paper's 5 cm
cube is the built-in default, :data:`CUBE`. Mass and friction are
settings of the simulator (``mass_kg``, ``lateral_friction``); the framework never reads them.

The geometry (top face, footprint, symmetry, grasps, pushed faces) is the shape's
(``bt_arrange.shapes``): this module only names types and says where a part starts in a scene
(:class:`ObjectStart`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from bt_arrange.errors import PlanError
from bt_arrange.shapes import ROBOTIQ_2F85, Prism, Shape
from bt_arrange.suggest import did_you_mean


@dataclass(frozen=True, init=False)
class ObjectType:
    """A named part type: its ``shape``, and the simulator's ``mass_kg`` and ``lateral_friction`` (None: the cell's).

    ``ObjectType(name, size_m)`` is the box prism of ``size_m = (x, y, z)`` metres; ``shape=`` takes
    any :class:`~bt_arrange.shapes.Shape`. A type's checks (positive size, one grasp the 2F-85 can
    take) run when it is made, so a bad type is a ``PlanError`` naming it.
    """

    name: str
    shape: Shape
    mass_kg: float | None = None
    lateral_friction: float | None = None

    def __init__(
        self,
        name: str,
        size_m: tuple[float, float, float] | None = None,
        mass_kg: float | None = None,
        lateral_friction: float | None = None,
        *,
        shape: Shape | None = None,
    ) -> None:
        if not isinstance(name, str) or not name:
            raise PlanError(f"an object type needs a name, got {name!r}")
        if shape is None:
            if (
                not isinstance(size_m, (tuple, list))
                or len(size_m) != 3
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in size_m)
            ):
                raise PlanError(f"object type {name!r}: size must be three numbers (x, y, z in metres), got {size_m!r}")
            shape = Prism.box(float(size_m[0]), float(size_m[1]), float(size_m[2]))
        elif size_m is not None:
            raise PlanError(f"object type {name!r}: give a size or a shape, not both")
        problems = shape.problems(ROBOTIQ_2F85)
        if problems:
            raise PlanError(f"object type {name!r}: {problems[0]}")
        for label, value in (("mass_kg", mass_kg), ("lateral_friction", lateral_friction)):
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise PlanError(f"object type {name!r}: {label} must be a positive number, got {value!r}")
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "shape", shape)
        object.__setattr__(self, "mass_kg", mass_kg)
        object.__setattr__(self, "lateral_friction", lateral_friction)

    @property
    def size_m(self) -> tuple[float, float, float]:
        """The part's bounding box (x, y along its frame, z its height): a cuboid's edges."""
        x_m, y_m = self.shape.extent_m
        return (float(x_m), float(y_m), float(self.shape.height_m))

    def mass_problem(self, settings: Any) -> str | None:
        """Why the arm or the pads cannot lift this part (``settings``: ``ManipulationSettings``), naming the limit.

        None when they can, or when the type gives no mass (the cell's parts are light).
        """
        if self.mass_kg is None:
            return None
        payload_kg = settings.max_payload_part_kg
        if self.mass_kg > payload_kg:
            return (
                f"{self.mass_kg:g} kg is more than the arm can carry: {payload_kg:.2f} kg (the UR5's "
                f"{settings.arm_payload_kg:g} kg payload less the gripper's {settings.gripper.mass_kg:g} kg)"
            )
        friction = self.lateral_friction if self.lateral_friction is not None else DEFAULT_PART_FRICTION
        lift_kg = settings.max_lift_kg(friction)
        if self.mass_kg > lift_kg:
            low, high = settings.gripper.force_range_n
            return (
                f"{self.mass_kg:g} kg is more than the pads can lift by friction: {lift_kg:.2f} kg (two pads, "
                f"friction {settings.gripper.pad_friction:g} x {friction:g}, grip {settings.grip_force_n:g} N, "
                f"{settings.lift_safety:g} x to spare); a grip force up to {high:g} N "
                f"(ManipulationSettings.grip_force_n) or a part of more friction lifts more"
            )
        return None

    @property
    def size_text(self) -> str:
        """The shape in millimetres, e.g. ``80 x 40 x 40 mm``."""
        return self.shape.describe()

    def resized(self, grown_m: float) -> ObjectType:
        """The same type with every edge ``grown_m`` longer (a real cell's machining error); boxes only."""
        if not self.shape.rectangular:
            return self
        x_m, y_m, z_m = self.shape.size_m
        grown = Prism.box(x_m + grown_m, y_m + grown_m, z_m + grown_m)
        return ObjectType(self.name, None, self.mass_kg, self.lateral_friction, shape=grown)


#: A part's friction coefficient when its type gives none (the simulated cell's parts: wood on rubber pads).
DEFAULT_PART_FRICTION = 0.5
#: A part's mass when its type gives none (the simulated cell's 5 cm wooden cube).
DEFAULT_PART_MASS_KG = 0.1

#: The paper's 5 cm cube of hard wood (the default type).
CUBE = ObjectType("cube", (0.05, 0.05, 0.05))
#: An 80 x 40 x 40 mm bar: the cuboid of the examples and of ``bt-arrange experiment --object bar``.
BAR = ObjectType("bar", (0.08, 0.04, 0.04))
#: The type of a target or a start that names none (XML writes it as an empty ``object_type``).
DEFAULT_TYPE = CUBE
#: The types known by name without a plan file.
BUILT_IN_TYPES: dict[str, ObjectType] = {t.name: t for t in (CUBE, BAR)}


def built_in_type(name: str) -> ObjectType:
    """The built-in type of this name; a ``PlanError`` naming the known ones otherwise."""
    try:
        return BUILT_IN_TYPES[name]
    except KeyError:
        known = ", ".join(sorted(BUILT_IN_TYPES))
        raise PlanError(
            f"unknown object type {name!r}{did_you_mean(name, BUILT_IN_TYPES)}: the built-in types are {known}"
        ) from None


@dataclass(frozen=True)
class PartOnTable:
    """A part at a planar pose: the colour of its top face, (x, y) in metres, yaw in radians, its name and type.

    ``name`` is the part's blackboard namespace (``/<name>/pose``); it defaults to the colour.
    The fields a target and a start share.
    """

    colour: str
    x_m: float
    y_m: float
    yaw_rad: float = 0.0
    name: str | None = None
    object_type: ObjectType = field(default=CUBE)

    @property
    def obj(self) -> str:
        """The part's name: its blackboard namespace."""
        return self.name or self.colour


@dataclass(frozen=True)
class ObjectStart(PartOnTable):
    """Where a part starts on the table (a target of the same name is the part's target)."""


def object_type_of(thing: object) -> ObjectType:
    """The type of a target or a start (anything with ``object_type``), the cube when it has none."""
    value = getattr(thing, "object_type", None)
    return value if isinstance(value, ObjectType) else CUBE


def kind_of(thing: object) -> tuple[ObjectType, str]:
    """A target's or start's kind: its type and colour (parts of one kind are identical)."""
    return object_type_of(thing), str(getattr(thing, "colour", ""))
