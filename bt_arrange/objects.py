"""Object types: what a user brings to the table, and the size-aware geometry every layer shares.

An :class:`ObjectType` is a name and a size (x, y, z in metres, the cuboid's edges along its own
axes; z is its height on the table). The paper's 5 cm cube is the built-in default, :data:`CUBE`.
Mass and friction are settings of the simulator (``mass_kg``, ``lateral_friction``); the
framework never reads them.

The geometry here is the one place that knows how big a part is:

- its top face, footprint and symmetry (90 degrees for a square top, 180 otherwise);
- how the 2F-85 grasps it (across the narrowest horizontal side that fits the stroke, at a height
  through the centre of mass where the pads allow) and pushes it (the opening and reach of the
  face pushed);
- where a part starts in a scene (:class:`ObjectStart`).

No pybullet, no OpenCV: perception, behaviours, plan checks and the cell all call this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray, fold_yaw, rotation_z

#: The 2F-85's stroke: the widest opening, metres.
GRIPPER_STROKE_M = 0.085
#: A side the fingers close across must leave this much of the stroke free (each side of the part
#: together): room for the part's measured position to be off a little as the pads come down.
GRASP_CLEARANCE_M = 0.005
#: The pads' half height (TCP at mid-pad) and the room kept between a pad's bottom and the
#: table when grasping or pushing (more than the 3 mm the kinematics demand of any pose).
PAD_HALF_HEIGHT_M = 0.01875
PAD_TABLE_CLEARANCE_M = 0.004
#: The thinnest part the camera and the pads handle (each edge), and the tallest (its height).
MIN_EDGE_M = 0.015
MAX_HEIGHT_M = 0.10


@dataclass(frozen=True)
class ObjectType:
    """A cuboid of ``size_m = (x, y, z)`` metres: ``x`` and ``y`` across its top face, ``z`` its height.

    ``mass_kg`` and ``lateral_friction`` are simulator settings (None: the cell's defaults).
    A type's checks (positive size, one side the gripper spans) run when it is made, so a bad type
    is a ``PlanError`` naming it.
    """

    name: str
    size_m: tuple[float, float, float]
    mass_kg: float | None = None
    lateral_friction: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise PlanError(f"an object type needs a name, got {self.name!r}")
        size = self.size_m
        if (
            not isinstance(size, (tuple, list))
            or len(size) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in size)
        ):
            raise PlanError(f"object type {self.name!r}: size must be three numbers (x, y, z in metres), got {size!r}")
        object.__setattr__(self, "size_m", tuple(float(v) for v in size))
        if min(self.size_m) <= 0:
            raise PlanError(f"object type {self.name!r}: size {self.size_text} has an edge that is not positive")
        if min(self.size_m) < MIN_EDGE_M:
            raise PlanError(
                f"object type {self.name!r}: size {self.size_text} has an edge under {MIN_EDGE_M * 1000:.0f} mm, "
                "too thin for the pads and the camera"
            )
        if self.size_m[2] > MAX_HEIGHT_M:
            raise PlanError(
                f"object type {self.name!r}: {self.size_m[2] * 1000:g} mm tall, "
                f"taller than {MAX_HEIGHT_M * 1000:.0f} mm"
            )
        if min(self.size_m[0], self.size_m[1]) > max_grasp_width_m():
            raise PlanError(
                f"object type {self.name!r}: size {self.size_text} has no horizontal side the gripper can span "
                f"(the 2F-85 closes across at most {max_grasp_width_m() * 1000:.0f} mm: its "
                f"{GRIPPER_STROKE_M * 1000:.0f} mm stroke less {GRASP_CLEARANCE_M * 1000:.0f} mm of clearance)"
            )
        for label, value in (("mass_kg", self.mass_kg), ("lateral_friction", self.lateral_friction)):
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise PlanError(f"object type {self.name!r}: {label} must be a positive number, got {value!r}")

    # -- shape -----------------------------------------------------------------------------

    @property
    def size_text(self) -> str:
        """The size in millimetres, e.g. ``80 x 40 x 40 mm``."""
        return " x ".join(f"{v * 1000:g}" for v in self.size_m) + " mm"

    @property
    def height_m(self) -> float:
        """The height of the top face above the table."""
        return self.size_m[2]

    @property
    def top_size_m(self) -> tuple[float, float]:
        """The top face's edges (x, y)."""
        return self.size_m[0], self.size_m[1]

    @property
    def square_top(self) -> bool:
        """True when the top face is a square (within 0.5 mm)."""
        return abs(self.size_m[0] - self.size_m[1]) < 0.0005

    @property
    def symmetry_rad(self) -> float:
        """The turn that shows the same top face: 90 degrees for a square top, 180 otherwise."""
        return math.pi / 2 if self.square_top else math.pi

    @property
    def half_diagonal_m(self) -> float:
        """Half the top face's diagonal: the radius of the circle the part sweeps as it turns."""
        return 0.5 * math.hypot(self.size_m[0], self.size_m[1])

    @property
    def is_cube(self) -> bool:
        """True for a cube (all three edges equal within 0.5 mm)."""
        return self.square_top and abs(self.size_m[0] - self.size_m[2]) < 0.0005

    def fold_yaw(self, yaw_rad: float) -> float:
        """A yaw folded to the shape's symmetry: ``[-45, 45)`` degrees for a square top, ``[-90, 90)`` otherwise."""
        return fold_yaw(yaw_rad, self.symmetry_rad)

    def yaw_error_rad(self, measured_yaw_rad: float, target_yaw_rad: float) -> float:
        """Measured minus target yaw, folded to the symmetry (signed)."""
        return fold_yaw(measured_yaw_rad - target_yaw_rad, self.symmetry_rad)

    def footprint_m(self, x_m: float, y_m: float, yaw_rad: float) -> FloatArray:
        """The four corners (4 x 2, counter-clockwise) of the part's footprint at (x, y, yaw) on the table."""
        hx, hy = self.size_m[0] / 2, self.size_m[1] / 2
        local = np.array([[-hx, -hy, 0.0], [hx, -hy, 0.0], [hx, hy, 0.0], [-hx, hy, 0.0]])
        return (rotation_z(yaw_rad) @ local.T).T[:, :2] + np.array([x_m, y_m])

    # -- grasp -----------------------------------------------------------------------------

    @property
    def grasp_axis(self) -> str:
        """The object axis ("x" or "y") the fingers close along: across the narrower side that fits."""
        return "x" if self.size_m[0] <= self.size_m[1] else "y"

    @property
    def grasp_width_m(self) -> float:
        """The side the pads close on."""
        return min(self.size_m[0], self.size_m[1])

    @property
    def grasp_yaw_offset_rad(self) -> float:
        """Gripper yaw minus object yaw for a grasp (the closing axis lies along the gripper's yaw)."""
        return 0.0 if self.grasp_axis == "x" else math.pi / 2

    @property
    def grasp_height_m(self) -> float:
        """TCP height (mid-pad) that holds the part through its centre of mass, or as low as the pads allow."""
        return max(self.size_m[2] / 2, PAD_HALF_HEIGHT_M + PAD_TABLE_CLEARANCE_M)

    def approach_height_m(self, cube_approach_height_m: float) -> float:
        """The height of moves above the table: the cube's, raised by however much taller the part is."""
        return cube_approach_height_m + max(0.0, self.size_m[2] - CUBE.size_m[2])

    # -- push ------------------------------------------------------------------------------

    def pushed_face(self, push_direction_rad: float, object_yaw_rad: float) -> tuple[float, float]:
        """(width, depth) of the face pushed along ``push_direction_rad``: across the push, and the part along it."""
        relative = fold_yaw(push_direction_rad - object_yaw_rad, math.pi)
        along_x = abs(math.cos(relative)) >= abs(math.sin(relative))
        # Pushing along the object's x axis meets the face that spans its y edge.
        return (self.size_m[1], self.size_m[0]) if along_x else (self.size_m[0], self.size_m[1])


def max_grasp_width_m() -> float:
    """The widest side the fingers close across (the stroke less the clearance)."""
    return GRIPPER_STROKE_M - GRASP_CLEARANCE_M


#: The paper's 5 cm cube of hard wood (the default type).
CUBE = ObjectType("cube", (0.05, 0.05, 0.05))
#: An 80 x 40 x 40 mm bar: the cuboid of the examples and of ``bt-arrange experiment --object bar``.
BAR = ObjectType("bar", (0.08, 0.04, 0.04))
#: The types known by name without a plan file.
BUILT_IN_TYPES: dict[str, ObjectType] = {t.name: t for t in (CUBE, BAR)}


def built_in_type(name: str) -> ObjectType:
    """The built-in type of this name; a ``PlanError`` naming the known ones otherwise."""
    try:
        return BUILT_IN_TYPES[name]
    except KeyError:
        known = ", ".join(sorted(BUILT_IN_TYPES))
        raise PlanError(f"unknown object type {name!r}: the built-in types are {known}") from None


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


def min_centre_distance_m(first: ObjectType, second: ObjectType) -> float:
    """Centres of two parts closer than this may overlap at some yaw (the sum of their half diagonals)."""
    return first.half_diagonal_m + second.half_diagonal_m


def kind_of(thing: object) -> tuple[ObjectType, str]:
    """A target's or start's kind: its type and colour (parts of one kind are identical)."""
    return object_type_of(thing), str(getattr(thing, "colour", ""))
