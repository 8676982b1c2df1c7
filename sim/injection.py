"""Error injection: one injector per manipulation error of the paper's Sec. 3, at the moment it names.

Every injector acts on the simulated world only: a cube's true pose (``WorkCell.displace_cube``
or pybullet's reset), the pads' friction, the camera's physical pose (``SimCamera.set_render_offset``)
or an execution parameter of the robot (the release height). The robot learns of an error only
through its camera; nothing the tree reports is touched, and no cube is ever fixed to the gripper.

| name | error (paper, Fig. 2) | when | magnitude (default) |
|---|---|---|---|
| ``perception_offset`` | a) pose estimation | detection before the pick | ``max_m`` = 0.010 m camera shift |
| ``pick_translation`` | b) translation | after that detection | ``max_m`` = 0.025 m per axis |
| ``pick_rotation`` | c) orientation | after that detection | ``max_deg`` = 40 deg |
| ``surface_shift`` | d) surface | "close on the cube" | ``max_m`` = 0.003 m along the pads |
| ``transport_slip`` | e) grip | "carry above the target" | ``duration_s`` = 0.05 s, ``friction_scale`` = 0 |
| ``release_stick`` | f) friction | "release the cube" | ``max_m`` = 0.003 m toward one finger |
| ``release_height`` | g) release | the first placing | ``height_m`` = 0.005 m |
| ``release_tilt`` | h) tilting | "release the cube" | ``max_deg`` = 5 deg |

Use::

    injectors = [make_injector("pick_translation:0.025"), make_injector("release_tilt")]
    attach_all(run, "red", injectors, seed=7)
    report = run.run()
    log = [injector.record() for injector in injectors]  # JSON-able: what was injected

**Once per run.** Each injector fires at the first occurrence of its moment for its object and
never again: a regrasp after a slip, a second placing, and the pushes of the correction run
without injected errors, so a trial measures the correction of one error. ``record()`` says
whether it fired (``"fired"``) and what it did, in millimetres and degrees.

**Seeds.** Each injector draws from its own ``numpy.random.Generator``; ``attach_all`` derives
one per injector from the seed and the injector's name (not its position), so an injector draws
the same values whatever else is attached. The draws of the picking injectors are resampled until
the cube fits between the open pads, which depends on where the camera saw the cube, so the same
seed reproduces a record for the same scene.

An injector finds the behaviours it waits for by their type and object (the ``Detect``, ``Pick``
and ``Place`` of ``obj`` that ``bt_arrange.trees.transfer`` builds), never by their names, and a
stage by the running behaviour's feedback, compared with the constants of
``bt_arrange.behaviours.stages`` the behaviours themselves use; in a tree without them an
injector never fires.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Detect, Inspect, Pick, Place, keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.checks import finite_number, whole_number
from bt_arrange.errors import OutOfRangeError, PlanError
from bt_arrange.geometry import Pose, quaternion_to_matrix, rotation_z
from bt_arrange.runner import Transition

if TYPE_CHECKING:
    from bt_arrange_sim.runs import SimulatedRun

#: Stages (feedback messages of the running behaviour) the injectors wait for: the behaviours' own names.
CLOSE_STAGE = stage.CLOSE_ON_CUBE
LIFT_STAGE = stage.LIFT_CUBE
CARRY_STAGE = stage.CARRY_ABOVE_TARGET
RELEASE_STAGE = stage.RELEASE_CUBE
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
        self._run: SimulatedRun | None = None
        self._rng: np.random.Generator | None = None

    @property
    def magnitude(self) -> float:
        """The injector's main parameter, in the unit of its spec (metres, degrees or seconds)."""
        return self.params[self.PARAMETERS[0].name]

    def attach(self, run: SimulatedRun, obj: str, rng: np.random.Generator) -> None:
        """Register this injector's hooks on ``run`` for the cube ``obj``, drawing from ``rng``."""
        if self._run is not None:
            raise PlanError(f"{self.name} is already attached to a run: make one injector per run")
        if obj not in run.cell.cubes:
            raise PlanError(f"{self.name}: no cube {obj!r} in the cell; cubes: {', '.join(sorted(run.cell.cubes))}")
        self._run, self.obj, self._rng = run, obj, rng
        self._attach(run, obj)

    @abstractmethod
    def _attach(self, run: SimulatedRun, obj: str) -> None:
        """Register the hooks (``run.transition_hooks``, ``run.tick_hooks``)."""

    def record(self) -> dict[str, Any]:
        """What was injected, JSON-able: ``injector``, ``obj``, the parameters, ``fired`` and the details."""
        return {"injector": self.name, "obj": self.obj, **self.params, "fired": self.fired, **self.details}

    def __repr__(self) -> str:
        values = ", ".join(f"{k}={v:g}" for k, v in self.params.items())
        return f"{type(self).__name__}({values})"

    # -- helpers shared by the injectors ---------------------------------------------------

    @property
    def run(self) -> SimulatedRun:
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
            if node is not None and node.status == Status.RUNNING and node.feedback_message == stage_name:
                state["done"] = action(node)

        self.run.tick_hooks.append(hook)

    def _grasp_reference(self) -> tuple[float, float, float]:
        """Where the pads will come down: the pose the robot measured (``/<obj>/pose``), else the true pose.

        Read only to keep a picking error graspable, as the paper's bounds do; never written.
        """
        measured = read_blackboard(keys.key(self.cube, keys.POSE))
        if isinstance(measured, Pose):
            return measured.x_m, measured.y_m, measured.yaw_rad
        truth = self.run.cell.cube_pose_truth(self.cube)
        return truth.x_m, truth.y_m, truth.yaw_rad

    def _fits(self, x_m: float, y_m: float, yaw_rad: float, reference: tuple[float, float, float]) -> bool:
        """True when a cube at (x, y, yaw) lies between pads opened around ``reference`` along either of its axes."""
        settings = self.run.context.settings
        return grasp_fits(x_m, y_m, yaw_rad, reference, settings.cube_edge_m, settings.open_width_m)


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
) -> bool:
    """The paper's grasp feasibility: the cube still lies between the open pads.

    The pads come down around ``reference`` (x_m, y_m, yaw_rad: where the robot saw the cube),
    closing along one of its axes. Along both of them, the cube's centre offset plus its half
    extent (half an edge when square to the pads, up to edge / sqrt(2) turned by 45 degrees) must
    stay within half the opening: for an 85 mm opening and a 50 mm cube square to the pads, the
    centre may be at most 17.5 mm off along either axis.
    """
    rx, ry, ryaw = reference
    relative_yaw = yaw_rad - ryaw
    half_extent_m = edge_m / 2 * (abs(math.cos(relative_yaw)) + abs(math.sin(relative_yaw)))
    offset = np.array([x_m - rx, y_m - ry])
    for axis in (np.array([math.cos(ryaw), math.sin(ryaw)]), np.array([-math.sin(ryaw), math.cos(ryaw)])):
        if abs(float(offset @ axis)) + half_extent_m > open_width_m / 2:
            return False
    return True


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


# -- 1) perception ------------------------------------------------------------------------------


class PerceptionOffset(Injector):
    """Object detection and pose estimation error (Fig. 2a): the detection before the pick is off.

    From ``attach`` until ``detect <obj>`` first succeeds, the camera renders from a pose moved by
    up to ``max_m`` (uniform in a disc, world x and y) and turned by up to ``max_deg`` about the
    vertical (uniform, default 0), while its frames still report the calibrated pose: the robot
    measures the cube about (dx, dy) off (and turned by -dyaw about the point below the camera),
    so it picks off-centre. The camera is put back right after that detection: inspection is exact.
    The draw is resampled while the estimate it causes would put a pad on the cube.

    Note: the camera is displaced from ``attach``; in a tree that handles other objects before
    ``obj``, their detections and inspections see the displaced camera too. ``record()`` lists
    them under ``"also_seen_by"``; attach this injector to the first object handled.

    Record: ``camera_dx_mm``, ``camera_dy_mm``, ``camera_dyaw_deg`` (the displacement);
    ``estimate_error_dx_mm``, ``estimate_error_dy_mm``, ``estimate_error_dyaw_deg`` (the measured
    minus the true pose of that detection, for the log).
    """

    name = "perception_offset"
    PARAMETERS = (
        Parameter("max_m", 0.010, 0.0, 0.0175, "m"),
        Parameter("max_deg", 0.0, 0.0, 10.0, "deg", low_inclusive=True),
    )

    def __init__(self, max_m: float = 0.010, max_deg: float = 0.0) -> None:
        super().__init__(max_m=max_m, max_deg=max_deg)

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        camera = run.cell.camera
        cx, cy = camera.pose_world.x_m, camera.pose_world.y_m
        truth = run.cell.cube_pose_truth(obj)
        max_m, max_rad = self.params["max_m"], math.radians(self.params["max_deg"])

        def draw() -> tuple[float, float, float]:
            radius = max_m * math.sqrt(self.rng.uniform())
            direction = self.rng.uniform(-math.pi, math.pi)
            dyaw = self.rng.uniform(-max_rad, max_rad) if max_rad > 0 else 0.0
            return radius * math.cos(direction), radius * math.sin(direction), dyaw

        def fits(offset: tuple[float, float, float]) -> bool:
            dx, dy, dyaw = offset
            # What the calibrated camera will report for the cube (see SimCamera.set_render_offset).
            seen = rotation_z(-dyaw)[:2, :2] @ np.array([truth.x_m - cx - dx, truth.y_m - cy - dy]) + (cx, cy)
            return self._fits(truth.x_m, truth.y_m, truth.yaw_rad, (seen[0], seen[1], truth.yaw_rad - dyaw))

        drawn = _sample(draw, fits)
        (dx, dy, dyaw), draws = drawn or ((0.0, 0.0, 0.0), MAX_DRAWS)
        camera.set_render_offset(dx, dy, dyaw)
        self.details.update(
            camera_dx_mm=_mm(dx), camera_dy_mm=_mm(dy), camera_dyaw_deg=_deg(dyaw), draws=draws, also_seen_by=[]
        )
        if drawn is None:
            self.details["skipped"] = "no draw keeps the pads off the cube"

        def hook(transition: Transition) -> None:
            if self.fired or transition.new != Status.SUCCESS.value:
                return
            if not self._is_detection(transition):
                if isinstance(run.node(transition), Detect):  # another look through the displaced camera
                    self.details["also_seen_by"].append(transition.behaviour)
                return
            self.fired = True
            camera.set_render_offset()
            now = run.cell.cube_pose_truth(obj)
            measured = read_blackboard(keys.key(obj, keys.POSE))
            self.details["time_s"] = round(transition.time_s, 4)
            if isinstance(measured, Pose):
                dyaw_seen = (measured.yaw_rad - now.yaw_rad + math.pi / 4) % (math.pi / 2) - math.pi / 4
                self.details.update(
                    estimate_error_dx_mm=_mm(measured.x_m - now.x_m),
                    estimate_error_dy_mm=_mm(measured.y_m - now.y_m),
                    estimate_error_dyaw_deg=_deg(dyaw_seen),
                )

        run.transition_hooks.append(hook)


# -- 2) picking ---------------------------------------------------------------------------------


class PickTranslation(Injector):
    """Translation error (Fig. 2b): the gripper is not centred above the cube.

    Right after ``detect <obj>`` first succeeds (seen, not yet grasped) the cube is moved by dx, dy,
    each uniform in +-``max_m`` along world x and y (the paper: up to +-2.5 cm, half a cube),
    resampled while the cube would not fit between the open pads (``grasp_fits``: at most 17.5 mm
    off along either of its axes). The closing pads drag it back to the centre along their
    closing axis; the offset along the pads remains and shows up after placing.

    Record: ``dx_mm``, ``dy_mm`` (world), ``draws`` (samples drawn), ``time_s``.
    """

    name = "pick_translation"
    PARAMETERS = (Parameter("max_m", 0.025, 0.0, 0.05, "m"),)

    def __init__(self, max_m: float = 0.025) -> None:
        super().__init__(max_m=max_m)

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        self._on_first_detection(self._inject)

    def _inject(self) -> None:
        cell, max_m = self.run.cell, self.params["max_m"]
        x, y, yaw = cell.cube_planar_truth(self.cube)
        reference = self._grasp_reference()

        def draw() -> tuple[float, float]:
            dx, dy = self.rng.uniform(-max_m, max_m, size=2)
            return float(dx), float(dy)

        drawn = _sample(draw, lambda d: self._fits(x + d[0], y + d[1], yaw, reference))
        if drawn is None:
            self.details.update(dx_mm=0.0, dy_mm=0.0, draws=MAX_DRAWS, skipped="no draw fits between the pads")
            return
        (dx, dy), draws = drawn
        cell.displace_cube(self.cube, float(dx), float(dy))
        self.details.update(dx_mm=_mm(dx), dy_mm=_mm(dy), draws=draws)


class PickRotation(Injector):
    """Orientation error (Fig. 2c): the pads are not aligned with the cube's faces.

    Right after ``detect <obj>`` first succeeds the cube is turned about the vertical through its
    centre by an angle uniform in +-``max_deg`` (the paper: up to +-40 deg), resampled while it
    would not fit between the open pads (with another picking error already injected). The
    closing pads turn it back towards square, which moves it.

    Measured in this cell (trees/single_cube.py): turned by about 24 deg, the cube is held about
    7 deg off square and placed 1 to 6 mm off; turned by 29 deg or more it can stay
    wedged across two vertical edges (fingers about 68 mm apart, which Pick's width check accepts)
    and is placed turned by the full angle but only about 0.2 mm off: the position threshold alone
    does not see it.

    Record: ``dyaw_deg``, ``draws``, ``time_s``.
    """

    name = "pick_rotation"
    PARAMETERS = (Parameter("max_deg", 40.0, 0.0, 45.0, "deg"),)

    def __init__(self, max_deg: float = 40.0) -> None:
        super().__init__(max_deg=max_deg)

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        self._on_first_detection(self._inject)

    def _inject(self) -> None:
        cell, max_rad = self.run.cell, math.radians(self.params["max_deg"])
        x, y, yaw = cell.cube_planar_truth(self.cube)
        reference = self._grasp_reference()
        drawn = _sample(
            lambda: float(self.rng.uniform(-max_rad, max_rad)), lambda d: self._fits(x, y, yaw + d, reference)
        )
        if drawn is None:
            self.details.update(dyaw_deg=0.0, draws=MAX_DRAWS, skipped="no draw fits between the pads")
            return
        dyaw, draws = drawn
        cell.displace_cube(self.cube, dyaw_rad=dyaw)
        self.details.update(dyaw_deg=_deg(dyaw), draws=draws)


class SurfaceShift(Injector):
    """Surface error (Fig. 2d): an uneven face moves the cube as the fingers close.

    When ``pick <obj>`` starts "close on the cube" (the pads around the cube, not yet touching it)
    the cube is shifted by a distance uniform in +-``max_m`` along the pads, i.e. the horizontal
    axis across the closing axis (the TCP's y axis), where the closing pads do not centre it.

    Record: ``shift_mm`` (signed, along ``pad_axis``), ``dx_mm``, ``dy_mm`` (world), ``pad_axis``, ``time_s``.
    """

    name = "surface_shift"
    PARAMETERS = (Parameter("max_m", 0.003, 0.0, 0.010, "m"),)

    def __init__(self, max_m: float = 0.003) -> None:
        super().__init__(max_m=max_m)

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        self._on_stage(Pick, CLOSE_STAGE, self._inject)

    def _inject(self, node: py_trees.behaviour.Behaviour) -> bool:
        cell = self.run.cell
        pad_axis = _horizontal(cell.arm.tcp_pose().rotation[:, 1])
        shift = float(self.rng.uniform(-self.params["max_m"], self.params["max_m"]))
        dx, dy = shift * pad_axis
        cell.displace_cube(self.cube, float(dx), float(dy))
        self.fired = True
        self.details.update(
            time_s=self._now(),
            shift_mm=_mm(shift),
            dx_mm=_mm(dx),
            dy_mm=_mm(dy),
            pad_axis=[round(float(v), 6) for v in pad_axis],
        )
        return True


# -- 3) transport -------------------------------------------------------------------------------


class TransportSlip(Injector):
    """Grip error (Fig. 2e): the cube slips in the gripper during transport.

    At a random point of the carry (while ``place <obj>`` runs "carry above the target", once the
    TCP has covered a fraction, uniform in [0.1, 0.9], of its horizontal distance to the target)
    the pads' lateral friction is scaled by ``friction_scale`` for ``duration_s`` of world time, then
    restored to ``pad_contact``; it is restored early if the carry stops (the cube fell out and
    the guard interrupted it). Defaults: the grip is lost (scale 0) for 50 ms, so the cube falls
    about 16 mm down the pads and slides along them under the carry's acceleration, then is caught
    again. Windows of 0.1 s or more drop it: the guard and a regrasp take over. The 40 N grip holds
    the 0.1 kg cube down to a scale of about 0.04; above that nothing slips.

    Record: ``carry_fraction``, ``lateral_friction`` (during the window), ``start_s``, ``end_s``,
    ``slip_mm`` (the cube's true displacement in the TCP frame over the window, for the log:
    x along the closing axis, y along the pads, z down the pads), ``held_after`` (both pads touch it).
    """

    name = "transport_slip"
    PARAMETERS = (
        Parameter("duration_s", 0.05, 0.0, 10.0, "s"),
        Parameter("friction_scale", 0.0, 0.0, 1.0, "", low_inclusive=True),
    )
    #: Range of the carry's progress (fraction of the horizontal distance to the target) where the slip begins.
    CARRY_FRACTION = (0.1, 0.9)

    def __init__(self, duration_s: float = 0.05, friction_scale: float = 0.0) -> None:
        super().__init__(duration_s=duration_s, friction_scale=friction_scale)
        self._start: tuple[float, np.ndarray] | None = None
        self._carry: dict[str, Any] | None = None

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        finder = _NodeFinder(Place, obj)

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            node = finder(root)
            if node is None:
                return
            if self._start is None:
                if not self.fired and node.status == Status.RUNNING and node.feedback_message == CARRY_STAGE:
                    self._maybe_begin()
                return
            elapsed = run.cell.sim_time_s - self._start[0]
            if elapsed >= self.params["duration_s"] - 1e-9 or node.status != Status.RUNNING:
                self._end()

        run.tick_hooks.append(hook)

    def _maybe_begin(self) -> None:
        """Begin the slip once the carry has covered the drawn fraction of its way."""
        tcp_xy = self.run.cell.arm.tcp_pose().position_m[:2]
        if self._carry is None:
            target = read_blackboard(keys.key(self.cube, keys.TARGET))
            goal = np.array([target.x_m, target.y_m]) if target is not None else tcp_xy
            self._carry = {
                "from": tcp_xy.copy(),
                "distance": float(np.linalg.norm(goal - tcp_xy)),
                "fraction": float(self.rng.uniform(*self.CARRY_FRACTION)),
            }
        travelled = float(np.linalg.norm(tcp_xy - self._carry["from"]))
        if travelled >= self._carry["fraction"] * self._carry["distance"]:
            self._begin()

    def _set_pad_friction(self, friction: float) -> None:
        """Give both pads ``friction``, effective at once for the held cube (``WorkCell.set_pad_friction``)."""
        self.run.cell.set_pad_friction(self.cube, friction)

    def _cube_in_tcp(self) -> np.ndarray:
        cell = self.run.cell
        return cell.arm.tcp_pose().inverse().transform_point(cell.cube_pose_truth(self.cube).position_m)

    def _begin(self) -> None:
        cell = self.run.cell
        friction = cell.config.physics.pad_contact.lateral_friction * self.params["friction_scale"]
        self._set_pad_friction(friction)
        self.fired = True
        self._start = (cell.sim_time_s, self._cube_in_tcp())
        assert self._carry is not None
        self.details.update(
            carry_fraction=round(self._carry["fraction"], 4), start_s=self._now(), lateral_friction=round(friction, 6)
        )

    def _end(self) -> None:
        assert self._start is not None
        cell = self.run.cell
        slip = self._cube_in_tcp() - self._start[1]
        held = bool(cell.cube_in_gripper_truth(self.cube))
        self._set_pad_friction(cell.config.physics.pad_contact.lateral_friction)
        self.details.update(end_s=self._now(), slip_mm=[_mm(v) for v in slip], held_after=held)
        self._start = None


# -- 4) placement -------------------------------------------------------------------------------


class ReleaseStick(Injector):
    """Friction error (Fig. 2f): the cube sticks to one finger as the gripper opens.

    When ``place <obj>`` starts "release the cube", one finger is chosen at random and a distance
    uniform in [0, ``max_m``]; for the following ticks the cube follows that finger's opening: it is
    put (``displace_cube``) where it was when the release began plus the finger's travel since, along
    the closing axis, until it has been dragged that far; then it stays where it was let go.

    Record: ``finger`` (joint name), ``drag_mm``, ``dx_mm``, ``dy_mm`` (world), ``ticks``, ``start_s``, ``end_s``.
    """

    name = "release_stick"
    PARAMETERS = (Parameter("max_m", 0.003, 0.0, 0.015, "m"),)

    def __init__(self, max_m: float = 0.003) -> None:
        super().__init__(max_m=max_m)
        self._drag: dict[str, Any] | None = None

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        finder = _NodeFinder(Place, obj)

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            node = finder(root)
            if node is None:
                return
            if self._drag is None:
                if not self.fired and node.status == Status.RUNNING and node.feedback_message == RELEASE_STAGE:
                    self._begin()
                return
            if node.status != Status.RUNNING:  # interrupted: the cube is no longer there to drag
                self._finish()
                return
            self._follow(finish=node.feedback_message != RELEASE_STAGE)

        run.tick_hooks.append(hook)

    def _finger_state(self, finger: int) -> float:
        cell = self.run.cell
        return cell.finger_opening_m(finger)

    def _begin(self) -> None:
        cell = self.run.cell
        side = int(self.rng.integers(2))
        distance = float(self.rng.uniform(0.0, self.params["max_m"]))
        finger = cell.finger_joint_indices[side]
        tcp = cell.arm.tcp_pose()
        closing = _horizontal(tcp.rotation[:, 0])
        pad = cell.finger_pad_position_m(finger)
        direction = closing * math.copysign(1.0, float((pad - tcp.position_m)[:2] @ closing))
        self.fired = True
        self._drag = {
            "finger": finger,
            "direction": direction,
            "distance": distance,
            "opening_at_start": self._finger_state(finger),
            "from_xy": cell.cube_pose_truth(self.cube).position_m[:2].copy(),
            "applied": 0.0,
            "ticks": 0,
        }
        self.details.update(
            start_s=self._now(),
            finger=cell.joint_name(finger),
            drag_mm=_mm(distance),
            dx_mm=_mm(distance * direction[0]),
            dy_mm=_mm(distance * direction[1]),
        )
        self._follow(finish=False)

    def _follow(self, finish: bool) -> None:
        drag = self._drag
        assert drag is not None
        travel = max(0.0, self._finger_state(drag["finger"]) - drag["opening_at_start"])
        target = drag["distance"] if finish else min(travel, drag["distance"])
        if target > drag["applied"]:
            # Absolute, not by increments: the pad's contact pushes the cube back a little every step.
            here = self.run.cell.cube_pose_truth(self.cube).position_m[:2]
            dx, dy = drag["from_xy"] + target * drag["direction"] - here
            self.run.cell.displace_cube(self.cube, float(dx), float(dy))
            drag["applied"] = target
            drag["ticks"] += 1
        if finish or drag["applied"] >= drag["distance"] - 1e-12:
            self._finish()

    def _finish(self) -> None:
        assert self._drag is not None
        self.details.update(end_s=self._now(), ticks=self._drag["ticks"], dragged_mm=_mm(self._drag["applied"]))
        self._drag = None


class ReleaseHeight(Injector):
    """Release error (Fig. 2g): the cube is let go above the table and drops.

    An execution error of the robot, not of its reports: the context's ``release_clearance_m``
    becomes ``height_m`` from the first "lift the cube" of ``pick <obj>`` until the first
    ``place <obj>`` ends, then the nominal clearance is restored, so only that placing drops the
    cube (not another object's, nor the placing after a regrasp). Deterministic: no draw.

    Record: ``release_clearance_mm`` (injected), ``nominal_clearance_mm``, ``start_s``, ``end_s``.
    """

    name = "release_height"
    PARAMETERS = (Parameter("height_m", 0.005, 0.0, 0.030, "m", low_inclusive=True),)

    def __init__(self, height_m: float = 0.005) -> None:
        super().__init__(height_m=height_m)
        self._nominal_m: float | None = None

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        self._on_stage(Pick, LIFT_STAGE, self._apply)

        def restore(transition: Transition) -> None:
            node = run.node(transition)
            if (
                self._nominal_m is not None
                and isinstance(node, Place)
                and node.obj == obj
                and transition.old == Status.RUNNING.value
                and transition.new != Status.RUNNING.value
            ):
                run.context.settings = dataclasses.replace(run.context.settings, release_clearance_m=self._nominal_m)
                self._nominal_m = None
                self.details["end_s"] = round(transition.time_s, 4)

        run.transition_hooks.append(restore)

    def _apply(self, node: py_trees.behaviour.Behaviour) -> bool:
        context = self.run.context
        self._nominal_m = context.settings.release_clearance_m
        context.settings = dataclasses.replace(context.settings, release_clearance_m=self.params["height_m"])
        self.fired = True
        self.details.update(
            start_s=self._now(),
            release_clearance_mm=_mm(self.params["height_m"]),
            nominal_clearance_mm=_mm(self._nominal_m),
        )
        return True


class ReleaseTilt(Injector):
    """Tilting error (Fig. 2h): the cube tips as the gripper opens, falls back flat and moves.

    When ``place <obj>`` runs "release the cube", as soon as the opening pads are clear of the
    tilted cube, it is turned about a random horizontal axis through its centre (direction uniform)
    by an angle uniform in [0, ``max_deg``], lifted just enough to keep its lowest corner above the
    table (pybullet reset of the cube's true pose), and left to fall back.

    Record: ``tilt_deg``, ``axis_deg`` (direction of the axis in the table plane, from world x),
    ``lift_mm``, ``time_s``.
    """

    name = "release_tilt"
    PARAMETERS = (Parameter("max_deg", 5.0, 0.0, 30.0, "deg"),)
    #: Gap kept between a pad and the tilted cube when it is turned, in metres.
    PAD_GAP_M = 0.0005

    def __init__(self, max_deg: float = 5.0) -> None:
        super().__init__(max_deg=max_deg)
        self._draw: tuple[float, float] | None = None

    def _attach(self, run: SimulatedRun, obj: str) -> None:
        finder = _NodeFinder(Place, obj)

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            node = finder(root)
            if self.fired or node is None or node.status != Status.RUNNING:
                return
            if self._draw is None:
                if node.feedback_message != RELEASE_STAGE:
                    return
                self._draw = (
                    float(self.rng.uniform(-math.pi, math.pi)),
                    float(self.rng.uniform(0.0, math.radians(self.params["max_deg"]))),
                )
            if self._pads_clear() or node.feedback_message != RELEASE_STAGE:
                self._tilt()

        run.tick_hooks.append(hook)

    def _tilted(self) -> tuple[np.ndarray, np.ndarray]:
        """The cube's rotation after the tilt, and its current position."""
        assert self._draw is not None
        axis_rad, tilt_rad = self._draw
        truth = self.run.cell.cube_pose_truth(self.cube)
        axis = np.array([math.cos(axis_rad), math.sin(axis_rad), 0.0])
        return _axis_angle(axis, tilt_rad) @ quaternion_to_matrix(truth.quaternion_xyzw), truth.position_m.copy()

    def _pads_clear(self) -> bool:
        cell = self.run.cell
        rotation, position = self._tilted()
        tcp = cell.arm.tcp_pose()
        closing = tcp.rotation[:, 0]
        half_edge_m = self.run.context.settings.cube_edge_m / 2
        centre_off_m = abs(float((position - tcp.position_m) @ closing))
        reach = half_edge_m * float(np.sum(np.abs(rotation.T @ closing))) + centre_off_m
        pads = [cell.finger_opening_m(f) for f in cell.finger_joint_indices]
        return min(pads) >= reach + self.PAD_GAP_M

    def _tilt(self) -> None:
        assert self._draw is not None
        cell = self.run.cell
        rotation, position = self._tilted()
        lowest_m = self.run.context.settings.cube_edge_m / 2 * float(np.sum(np.abs(rotation[2, :])))
        z = max(float(position[2]), lowest_m + 1e-4)
        moved = Pose.from_rotation([position[0], position[1], z], rotation)
        cell.place_cube_truth(self.cube, moved)
        self.fired = True
        axis_rad, tilt_rad = self._draw
        self.details.update(
            time_s=self._now(), tilt_deg=_deg(tilt_rad), axis_deg=_deg(axis_rad), lift_mm=_mm(z - position[2])
        )


def _axis_angle(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Rotation matrix of ``angle_rad`` about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle_rad) * k + (1.0 - math.cos(angle_rad)) * (k @ k)


# -- registry and composition -------------------------------------------------------------------

#: Every injector by its spec name.
INJECTORS: dict[str, type[Injector]] = {
    cls.name: cls
    for cls in (
        PerceptionOffset,
        PickTranslation,
        PickRotation,
        SurfaceShift,
        TransportSlip,
        ReleaseStick,
        ReleaseHeight,
        ReleaseTilt,
    )
}


def make_injector(spec: str) -> Injector:
    """An injector from a spec ``name[:value[,value...]]``, values in the order of its parameters.

    Metres, seconds, and degrees for angles: ``"pick_translation:0.025"``, ``"pick_rotation:40"``,
    ``"transport_slip:0.3,0.005"``, ``"release_tilt"`` (defaults). A ``PlanError`` names a malformed
    spec or an unknown injector; an ``OutOfRangeError`` a value outside the injector's range.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise PlanError(f"injector spec {spec!r} is empty; use name[:value], names: {', '.join(INJECTORS)}")
    name, _, rest = spec.strip().partition(":")
    cls = INJECTORS.get(name.strip())
    if cls is None:
        raise PlanError(f"injector spec {spec!r}: unknown injector {name.strip()!r}; known: {', '.join(INJECTORS)}")
    usage = f"{cls.name}[:{','.join(p.name for p in cls.PARAMETERS)}]"
    texts = [t.strip() for t in rest.split(",")] if rest.strip() else []
    if len(texts) > len(cls.PARAMETERS):
        raise PlanError(f"injector spec {spec!r}: too many values, expected {usage}")
    values: dict[str, float] = {}
    for parameter, text in zip(cls.PARAMETERS, texts, strict=False):
        try:
            values[parameter.name] = float(text)
        except ValueError:
            raise PlanError(
                f"injector spec {spec!r}: {parameter.name}={text!r} is not a number, expected {usage}"
            ) from None
    try:
        return cls(**values)
    except OutOfRangeError as error:
        raise OutOfRangeError(f"injector spec {spec!r}: {error}") from error


def make_injectors(specs: Iterable[str]) -> list[Injector]:
    """One injector per spec (see ``make_injector``)."""
    return [make_injector(spec) for spec in specs]


def child_generator(seed: int, name: str, index: int = 0) -> np.random.Generator:
    """The generator ``attach_all`` gives the ``index``-th injector called ``name`` for ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(zlib.crc32(name.encode()), index)))


def attach_all(run: SimulatedRun, obj: str, injectors: Sequence[Injector], seed: int) -> None:
    """Attach several injectors to one run for the cube ``obj``, each with its own generator from ``seed``.

    The generator depends on the seed and the injector's name (and its rank among injectors of
    that name), so adding another injector does not change the others' draws. Hooks run in the
    order given: of two picking errors, the later one is drawn to fit with the earlier.
    """
    whole_number("injection seed", seed, style="unit")
    seen: dict[str, int] = {}
    for injector in injectors:
        index = seen.get(injector.name, 0)
        seen[injector.name] = index + 1
        injector.attach(run, obj, child_generator(int(seed), injector.name, index))
