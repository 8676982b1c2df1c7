"""The frame every injector shares: ``Parameter``, ``Injector``, finding nodes by type, sampling, units.

An injector acts on the simulated world only, through the cell's ground-truth and injection
methods (``InjectableCell``: what the pybullet ``WorkCell`` and the ``MujocoCell`` both have, so
every injector works in either engine); it finds the behaviours it waits for by type and object,
and their stages by the constants of ``bt_arrange.behaviours.stages``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, TypeVar

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Detect, Inspect, keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.checks import finite_number
from bt_arrange.errors import OutOfRangeError, PlanError
from bt_arrange.geometry import Pose
from bt_arrange.motion import nearest_symmetric_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.runner import Transition
from bt_arrange.shapes import preferred_grasp


class InjectableCamera(Protocol):
    """What an injector uses of a cell's top camera."""

    @property
    def pose_world(self) -> Pose:
        """The calibrated pose, as frames report it."""
        ...

    def set_render_offset(self, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Render from a camera moved by (dx, dy) and turned by dyaw, frames still reporting ``pose_world``."""
        ...


class InjectableArm(Protocol):
    """What an injector uses of the arm: where the TCP truly is."""

    def tcp_pose(self) -> Pose:
        """The TCP's pose in the world."""
        ...


class InjectableCell(Protocol):
    """The seam between the injectors and a simulator: what they read and change of a cell, nothing else.

    ``bt_arrange_sim.pybullet.cell.WorkCell`` and ``bt_arrange_sim.mujoco.cell.MujocoCell`` have
    these with the same meanings; ``config.physics.pad_contact.lateral_friction`` is the pads'
    nominal coefficient (the cells share ``CellConfig``).
    """

    cubes: dict[str, int]
    finger_joint_indices: tuple[int, ...]
    config: Any

    @property
    def sim_time_s(self) -> float:
        """World seconds since the cell was built."""
        ...

    @property
    def arm(self) -> InjectableArm:
        """The arm (its true TCP pose)."""
        ...

    @property
    def camera(self) -> Any:
        """The top camera (``InjectableCamera``)."""
        ...

    def part_pose_truth(self, name: str) -> Pose:
        """A part's true pose."""
        ...

    def part_planar_truth(self, name: str) -> tuple[float, float, float]:
        """A part's true (x, y, yaw), yaw folded to its symmetry."""
        ...

    def displace_part(self, name: str, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Move a resting part by (dx, dy) and turn it by dyaw."""
        ...

    def place_part_truth(self, name: str, pose: Pose) -> None:
        """Put a part at ``pose``; physics moves it on."""
        ...

    def finger_opening_m(self, finger: int) -> float:
        """One finger joint's true value: its pad's distance from the centre."""
        ...

    def finger_pad_position_m(self, finger: int) -> np.ndarray:
        """One finger link's true world position."""
        ...

    def joint_name(self, index: int) -> str:
        """A joint's name by its index."""
        ...

    def set_pad_friction(self, cube: str, lateral_friction: float) -> None:
        """Give both pads a friction coefficient, effective at once for the held part."""
        ...

    def part_in_gripper_truth(self, name: str) -> bool:
        """True when both pads touch the part."""
        ...


class InjectableRun(Protocol):
    """What an injector uses of a run: its cell, its hooks, its tree and context (``InjectableRun``, ``MujocoRun``)."""

    transition_hooks: list[Any]
    tick_hooks: list[Any]
    root: py_trees.behaviour.Behaviour
    context: Any

    @property
    def cell(self) -> InjectableCell:
        """The cell the tree runs in."""
        ...

    def node(self, transition: Transition) -> py_trees.behaviour.Behaviour | None:
        """The behaviour a transition is about."""
        ...


#: Stages (feedback messages of the running behaviour) the injectors wait for: the behaviours' own names.
CLOSE_STAGE = stage.CLOSE_ON_PART
LIFT_STAGE = stage.LIFT_PART
CARRY_STAGE = stage.CARRY_ABOVE_TARGET
RELEASE_STAGE = stage.RELEASE_PART
T = TypeVar("T")
#: Draws tried before a picking injector gives up on finding one that still lets the pads grasp the cube.
MAX_DRAWS = 10_000


@dataclass(frozen=True)
class Parameter:
    """One number of an injector: its name, default and allowed range (``low`` excluded unless ``low_inclusive``)."""

    name: str
    default: float
    low: float
    high: float
    unit: str
    low_inclusive: bool = False

    def check(self, value: float, owner: str) -> float:
        """``value`` as a float, or an ``OutOfRangeError`` naming the injector, the parameter and its range."""
        finite_number(self.name, value, self.unit, where=f"{owner}: ", error=OutOfRangeError)
        above_low = value >= self.low if self.low_inclusive else value > self.low
        if not (above_low and value <= self.high):
            bracket = "[" if self.low_inclusive else "("
            allowed = f"{bracket}{self.low:g}, {self.high:g}] {self.unit}"
            raise OutOfRangeError(
                f"{owner}: {self.name}={value:g} {self.unit} is outside {allowed}",
                field=self.name,
                value=value,
                limit=(self.low, self.high),
                unit=self.unit,
            )
        return float(value)


class Injector(ABC):
    """One manipulation error, injected into one run's world at the moment the paper names.

    Subclasses declare ``name`` and ``PARAMETERS`` (the first is the magnitude), and register their
    hooks in ``_attach``. ``record()`` is JSON-able: the parameters, whether the error fired, when
    (world seconds), and what it did. An injector is attached to one run only.
    """

    name: ClassVar[str]
    PARAMETERS: ClassVar[tuple[Parameter, ...]]

    def __init__(self, **values: float) -> None:
        self.params: dict[str, float] = {}
        for parameter in self.PARAMETERS:
            self.params[parameter.name] = parameter.check(values.pop(parameter.name, parameter.default), self.name)
        if values:
            raise PlanError(f"{self.name}: unknown parameter(s) {', '.join(sorted(values))}")
        self.obj: str | None = None
        self.fired = False
        self.details: dict[str, Any] = {}
        self._run: InjectableRun | None = None
        self._rng: np.random.Generator | None = None

    @property
    def magnitude(self) -> float:
        """The injector's main parameter, in the unit of its spec (metres, degrees or seconds)."""
        return self.params[self.PARAMETERS[0].name]

    def attach(self, run: InjectableRun, obj: str, rng: np.random.Generator) -> None:
        """Register this injector's hooks on ``run`` for the cube ``obj``, drawing from ``rng``."""
        if self._run is not None:
            raise PlanError(f"{self.name} is already attached to a run: make one injector per run")
        if obj not in run.cell.parts:
            raise PlanError(f"{self.name}: no part {obj!r} in the cell; parts: {', '.join(sorted(run.cell.parts))}")
        self._run, self.obj, self._rng = run, obj, rng
        self._attach(run, obj)

    @abstractmethod
    def _attach(self, run: InjectableRun, obj: str) -> None:
        """Register the hooks (``run.transition_hooks``, ``run.tick_hooks``)."""

    def record(self) -> dict[str, Any]:
        """What was injected, JSON-able: ``injector``, ``obj``, the parameters, ``fired`` and the details."""
        return {"injector": self.name, "obj": self.obj, **self.params, "fired": self.fired, **self.details}

    def __repr__(self) -> str:
        values = ", ".join(f"{k}={v:g}" for k, v in self.params.items())
        return f"{type(self).__name__}({values})"

    # -- helpers shared by the injectors ---------------------------------------------------

    @property
    def run(self) -> InjectableRun:
        """The run attached to (after ``attach``)."""
        assert self._run is not None, "attach() first"
        return self._run

    @property
    def rng(self) -> np.random.Generator:
        """The injector's own random generator (after ``attach``)."""
        assert self._rng is not None, "attach() first"
        return self._rng

    @property
    def cube(self) -> str:
        """The cube injected into (after ``attach``)."""
        assert self.obj is not None, "attach() first"
        return self.obj

    def _now(self) -> float:
        return round(self.run.cell.sim_time_s, 4)

    def _is_detection(self, transition: Transition) -> bool:
        """True when ``transition`` is about the Detect before the pick of this cube (not an Inspect)."""
        return is_detection(self.run.node(transition), self.cube)

    def _on_first_detection(self, action: Callable[[], None]) -> None:
        """Call ``action`` once, right after the Detect of ``obj`` first succeeds (seen, not yet grasped)."""

        def hook(transition: Transition) -> None:
            if not self.fired and transition.new == Status.SUCCESS.value and self._is_detection(transition):
                self.fired = True
                self.details["time_s"] = round(transition.time_s, 4)
                action()

        self.run.transition_hooks.append(hook)

    def _on_stage(
        self,
        kind: type[py_trees.behaviour.Behaviour],
        stage_name: str,
        action: Callable[[py_trees.behaviour.Behaviour], bool],
    ) -> None:
        """Call ``action(node)`` after every tick in which the ``kind`` of this cube runs ``stage_name``, until True."""
        finder = _NodeFinder(kind, self.cube)
        state = {"done": False}

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            if state["done"]:
                return
            node = finder(root)
            if node is not None and node.status == Status.RUNNING and getattr(node, "stage", None) == stage_name:
                state["done"] = action(node)

        self.run.tick_hooks.append(hook)

    def _grasp_reference(self) -> tuple[float, float, float]:
        """Where the pads will come down (x, y) and the yaw of their closing axis.

        The position is the pose the robot measured (``/<obj>/pose``), else the true pose; the yaw is
        Pick's choice among the cube's quarter turns. Read only to keep a picking error graspable, as the
        paper's bounds do; never written.
        """
        measured = read_blackboard(keys.key(self.cube, keys.POSE))
        if isinstance(measured, Pose):
            x, y, yaw = measured.x_m, measured.y_m, measured.yaw_rad
        else:
            truth = self.run.cell.part_pose_truth(self.cube)
            x, y, yaw = truth.x_m, truth.y_m, truth.yaw_rad
        return x, y, self._closing_yaw(yaw)

    @property
    def object_type(self) -> ObjectType:
        """The type of the part injected into (its target's; the cube when the tree names none)."""
        for target in getattr(self.run.root, "targets", ()):
            if getattr(target, "obj", None) == self.cube:
                return target.object_type
        return CUBE

    def _closing_yaw(self, cube_yaw_rad: float) -> float:
        """The yaw Pick will close at for a part seen at ``cube_yaw_rad``, as Pick chooses it.

        Across the type's grasped side (``ObjectType.grasp_yaw_offset_rad``), the turn of its
        symmetry (a quarter for a cube, a half for a bar) nearest the wrist.
        """
        context = self.run.context
        wrist = context.planner.kinematics.wrist_yaw_rad(context.robot.arm.joint_positions())
        shape = self.object_type.shape
        grasp = preferred_grasp(shape, context.settings.gripper)
        return nearest_symmetric_yaw(cube_yaw_rad + grasp.yaw_offset_rad, wrist, shape.symmetry_rad)

    def _fits(self, x_m: float, y_m: float, yaw_rad: float, reference: tuple[float, float, float]) -> bool:
        """True when a part at (x, y, yaw) can still be grasped by pads closing around ``reference``."""
        settings = self.run.context.settings
        shape = self.object_type.shape
        grasp = preferred_grasp(shape, settings.gripper)
        x_extent_m, y_extent_m = shape.extent_m
        return grasp_fits(
            x_m,
            y_m,
            yaw_rad + grasp.yaw_offset_rad,
            reference,
            grasp.width_m,
            settings.open_width_m,
            along_pads_m=y_extent_m if grasp.axis == "x" else x_extent_m,
            symmetry_rad=shape.symmetry_rad,
        )


class _NodeFinder:
    """Finds the behaviour of a type (``Pick``, ``Place``) that handles an object, once.

    By type and object, not by name: a tree may hold two nodes of one name (trees/row_of_three.py
    has a Sequence and a Place both called "place red"). The first in tick order is taken.
    """

    def __init__(self, kind: type[py_trees.behaviour.Behaviour], obj: str) -> None:
        self.kind = kind
        self.obj = obj
        self.node: py_trees.behaviour.Behaviour | None = None

    def __call__(self, root: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour | None:
        if self.node is None:
            self.node = next(
                (n for n in root.iterate() if isinstance(n, self.kind) and getattr(n, "obj", None) == self.obj), None
            )
        return self.node


def is_detection(node: py_trees.behaviour.Behaviour | None, obj: str) -> bool:
    """True for the Detect of ``obj`` that finds it before the pick (an Inspect is a Detect too, but not this)."""
    return isinstance(node, Detect) and not isinstance(node, Inspect) and node.obj == obj


def read_blackboard(key: str) -> Any:
    """What the robot wrote at ``key`` (None if nothing), read through a client of the injectors' own.

    Read only: an injector never writes the blackboard.
    """
    client = py_trees.blackboard.Client(name="error injection")
    client.register_key(key, access=py_trees.common.Access.READ)
    return client.get(key) if client.exists(key) else None


def grasp_fits(
    x_m: float,
    y_m: float,
    yaw_rad: float,
    reference: tuple[float, float, float],
    edge_m: float,
    open_width_m: float,
    along_pads_m: float | None = None,
    symmetry_rad: float = math.pi / 2,
) -> bool:
    """The paper's grasp feasibility: the pads still close on the cube.

    The pads come down around ``reference`` (x_m, y_m, and yaw_rad: the direction of the closing
    axis) and close along that axis. The limit binds across the closing axis only: the cube's centre
    offset along it plus its half extent there (half an edge when square to the pads, up to
    edge / sqrt(2) turned by 45 degrees) must stay within half the opening; for an 85 mm opening
    and a 50 mm cube square to the pads, 17.5 mm. Along the pads the cube is still grasped while
    the pads' centre stays on the part of it they close on: up to half an edge (25 mm) off for a
    cube square to them; for a cube turned by ``a`` the pads first meet two vertical edges,
    ``edge / 2 * (cos a - sin a)`` either side of its centre along the pads, and the pads' centre
    must stay between them (measured: with the centre beyond, a cube turned by 37 deg and 15 mm
    off along the pads was squeezed out sideways and thrown off the table's view).

    A cuboid: ``edge_m`` is the side the pads close on (its extent along the closing axis when
    square to the pads, ``yaw_rad`` the direction of that side), ``along_pads_m`` the other one
    (default ``edge_m``), ``symmetry_rad`` its top face's (a half turn for a bar). Turned by ``a``,
    its half extent across is ``edge / 2 * cos a + along / 2 * sin a`` and the pads first meet the
    vertical edges ``along / 2 * cos a - edge / 2 * sin a`` either side of its centre.
    """
    rx, ry, closing_yaw = reference
    along_m = edge_m if along_pads_m is None else along_pads_m
    # Turned by more than half the symmetry is turned the other way: fold into [0, symmetry / 2].
    turn = abs((yaw_rad - closing_yaw + symmetry_rad / 2) % symmetry_rad - symmetry_rad / 2)
    half_extent_m = edge_m / 2 * math.cos(turn) + along_m / 2 * math.sin(turn)
    along_pads_limit_m = along_m / 2 * math.cos(turn) - edge_m / 2 * math.sin(turn)
    offset = np.array([x_m - rx, y_m - ry])
    across = abs(float(offset @ np.array([math.cos(closing_yaw), math.sin(closing_yaw)])))
    along_pads = abs(float(offset @ np.array([-math.sin(closing_yaw), math.cos(closing_yaw)])))
    return across + half_extent_m <= open_width_m / 2 + 1e-12 and along_pads <= along_pads_limit_m + 1e-12


def _sample(draw: Callable[[], T], fits: Callable[[T], bool]) -> tuple[T, int] | None:
    """Draw until ``fits``: the first draw that does and how many were drawn, or ``None`` after ``MAX_DRAWS``."""
    for draws in range(1, MAX_DRAWS + 1):
        value = draw()
        if fits(value):
            return value, draws
    return None


def _mm(value_m: float) -> float:
    return round(float(value_m) * 1000, 4)


def _deg(value_rad: float) -> float:
    return round(math.degrees(float(value_rad)), 4)


def _horizontal(vector: np.ndarray) -> np.ndarray:
    """The unit horizontal part of a world vector."""
    flat = np.array([vector[0], vector[1]], dtype=float)
    return flat / np.linalg.norm(flat)
