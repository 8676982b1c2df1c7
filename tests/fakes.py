"""Fake devices for testing behaviours without a simulator: a clock, an arm, a gripper and a camera.

Each fake implements its protocol of ``bt_arrange.robot`` and records what it was told to do:

- ``FakeClock``: world time that moves only when a test calls ``advance(dt)``.
- ``FakeArm``: tracks every setpoint perfectly (the measured joints are the last command) and
  records each command with the clock's time; its TCP pose comes from the real kinematics.
- ``FakeGripper``: the fingers move at a fixed speed as the clock advances; a close stops at
  ``object_width_m`` (a cube between the pads) or at 0 (nothing); ``slip()`` lets the cube go,
  ``stuck=True`` makes the fingers never report standing still.
- ``FakeCamera``: frames rendered by ``bt_arrange.perception.synthetic`` for a list of cubes, at a
  reduced resolution (960 x 540, about 20 ms per frame and detection); a window renders only its
  pixels, through the window's intrinsics.

``make_context()`` puts them together with the real ``MotionPlanner`` and ``PartDetector``;
``tick_until_done()`` drives a behaviour the way the runner does: tick, brake step, clock step.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Context
from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion import (
    ARM_JOINT_NAMES,
    DEFAULT_HOME_Q,
    ArmKinematics,
    CartesianLimits,
    JointLimits,
    MotionPlanner,
)
from bt_arrange.perception import PartDetector
from bt_arrange.perception.synthetic import SyntheticCube, render_frame, sim_intrinsics, top_down_camera_pose
from bt_arrange.robot import (
    GRIPPER_FORCE_RANGE_N,
    GRIPPER_MAX_WIDTH_M,
    CameraFrame,
    CameraIntrinsics,
    PixelWindow,
    Robot,
)
from bt_arrange.settings import ManipulationSettings

#: The UR CB3's 125 Hz, as in the simulated cell.
CONTROL_PERIOD_S = 0.008
#: Fingers of the fake gripper move at this speed (within the 2F-85's 20 to 150 mm/s).
GRIPPER_SPEED_M_S = 0.05
#: Smaller than the cell's 1920 x 1080: four times fewer pixels, still about 1 mm per pixel.
CAMERA_WIDTH_PX, CAMERA_HEIGHT_PX = 960, 540


class FakeClock:
    """World time, in seconds, that advances only when told to."""

    def __init__(self, start_s: float = 0.0) -> None:
        self._now_s = start_s

    def now(self) -> float:
        """Seconds of world time."""
        return self._now_s

    def advance(self, dt_s: float) -> None:
        """Let ``dt_s`` seconds pass."""
        if dt_s < 0:
            raise ValueError(f"time does not run backwards: dt = {dt_s} s")
        self._now_s += dt_s


@dataclass(frozen=True)
class ArmCommand:
    """One setpoint the arm received, with the world time it was sent at."""

    time_s: float
    positions_rad: FloatArray
    velocities_rad_s: FloatArray | None


class FakeArm:
    """A UR5 that tracks every setpoint perfectly: the measured joints are the last commanded ones."""

    def __init__(
        self,
        clock: FakeClock,
        q: Sequence[float] | FloatArray = DEFAULT_HOME_Q,
        kinematics: ArmKinematics | None = None,
        control_period_s: float = CONTROL_PERIOD_S,
    ) -> None:
        self._clock = clock
        self._q = np.array(q, dtype=float)
        self._v = np.zeros(len(ARM_JOINT_NAMES))
        self._kinematics = kinematics or ArmKinematics()
        self._control_period_s = control_period_s
        self.commands: list[ArmCommand] = []

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The six UR5 joints."""
        return ARM_JOINT_NAMES

    @property
    def control_period_s(self) -> float:
        """Seconds between two setpoints."""
        return self._control_period_s

    def joint_positions(self) -> FloatArray:
        """The last commanded positions (perfect tracking)."""
        return self._q.copy()

    def joint_velocities(self) -> FloatArray:
        """The last commanded velocities."""
        return self._v.copy()

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Record the setpoint and be there at once."""
        positions = np.array(positions_rad, dtype=float)
        velocities = None if velocities_rad_s is None else np.array(velocities_rad_s, dtype=float)
        self.commands.append(ArmCommand(self._clock.now(), positions, velocities))
        self._q = positions
        self._v = np.zeros_like(positions) if velocities is None else velocities

    def tcp_pose(self) -> Pose:
        """TCP pose of the current joints, from the real forward kinematics."""
        return self._kinematics.forward(self._q)

    def tcp_pose_at(self, q: FloatArray) -> Pose:
        """TCP pose of any joint vector (to check recorded commands)."""
        return self._kinematics.forward(q)


@dataclass(frozen=True)
class GripperCommand:
    """One gripper command: ``("open", width_m)`` or ``("close", force_n)``, with its world time."""

    time_s: float
    kind: str
    value: float
    #: The finger speed asked for (None: the gripper's own).
    speed_m_s: float | None = None


class FakeGripper:
    """A 2F-85 whose fingers move at ``speed_m_s`` as the clock advances.

    A close stops at ``object_width_m`` (a cube between the pads) or at 0 when it is ``None``.
    ``slip()`` takes the cube away: closed fingers go on closing towards 0. With ``stuck=True``
    the fingers never report standing still. ``wedge(width_m, opens)`` holds the next ``opens``
    openings at ``width_m`` (a part wedged between the pads).
    """

    def __init__(
        self,
        clock: FakeClock,
        width_m: float = GRIPPER_MAX_WIDTH_M,
        object_width_m: float | None = None,
        speed_m_s: float = GRIPPER_SPEED_M_S,
        stuck: bool = False,
    ) -> None:
        self._clock = clock
        self.object_width_m = object_width_m
        self.speed_m_s = speed_m_s
        self.stuck = stuck
        self._from_m = width_m
        self._to_m = width_m
        self._since_s = clock.now()
        self._closing = False
        self.commands: list[GripperCommand] = []
        self._wedged_m: float | None = None
        self._wedged_opens = 0

    @property
    def max_width_m(self) -> float:
        """The 2F-85 stroke."""
        return GRIPPER_MAX_WIDTH_M

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Move to ``width_m`` (at the fake's own speed: ``speed_m_s`` is recorded, not modelled)."""
        if not 0.0 <= width_m <= GRIPPER_MAX_WIDTH_M:
            raise OutOfRangeError(f"gripper width {width_m * 1000:.1f} mm is outside 0 to 85 mm")
        self.commands.append(GripperCommand(self._clock.now(), "open", width_m, speed_m_s))
        self._closing = False
        if self._wedged_m is not None and self._wedged_opens > 0 and width_m > self._wedged_m:
            self._wedged_opens -= 1
            width_m = self._wedged_m
        self._move_to(width_m)

    def wedge(self, width_m: float, opens: int = 1) -> None:
        """The next ``opens`` openings stop at ``width_m``: the part holds the pads apart."""
        self._wedged_m, self._wedged_opens = width_m, opens

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Close until the pads meet the object, or each other (at the fake's own speed)."""
        low, high = GRIPPER_FORCE_RANGE_N
        if not low <= force_n <= high:
            raise OutOfRangeError(f"grip force {force_n:.1f} N is outside {low:.0f} to {high:.0f} N")
        self.commands.append(GripperCommand(self._clock.now(), "close", force_n, speed_m_s))
        self._closing = True
        self._move_to(self._closed_width())

    def width(self) -> float:
        """The opening now."""
        travel = self.speed_m_s * (self._clock.now() - self._since_s)
        if abs(self._to_m - self._from_m) <= travel:
            return self._to_m
        return self._from_m + np.sign(self._to_m - self._from_m) * travel

    def is_moving(self) -> bool:
        """True while the fingers travel (always, when stuck)."""
        return self.stuck or self.width() != self._to_m

    def slip(self) -> None:
        """The cube slips out: no object between the pads any more; closed fingers close on."""
        self.object_width_m = None
        if self._closing:
            self._move_to(self._closed_width())

    def _closed_width(self) -> float:
        return 0.0 if self.object_width_m is None else self.object_width_m

    def _move_to(self, width_m: float) -> None:
        self._from_m = self.width()
        self._to_m = width_m
        self._since_s = self._clock.now()


class FakeCamera:
    """The top camera over a table of synthetic cubes; ``cubes`` may be changed between frames."""

    def __init__(
        self,
        clock: FakeClock,
        cubes: Iterable[SyntheticCube] = (),
        intrinsics: CameraIntrinsics | None = None,
        pose_world: Pose | None = None,
        arm: FakeArm | None = None,
    ) -> None:
        self._clock = clock
        self.cubes = list(cubes)
        self._intrinsics = intrinsics or sim_intrinsics(CAMERA_WIDTH_PX, CAMERA_HEIGHT_PX)
        self.pose_world = pose_world or top_down_camera_pose()
        self._arm = arm
        #: (world time, arm joints or None) of every capture.
        self.captures: list[tuple[float, FloatArray | None]] = []
        #: The window of every capture (None: the full image), in the order of ``captures``.
        self.windows: list[PixelWindow | None] = []

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """Pinhole intrinsics of the rendered frames."""
        return self._intrinsics

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """Render the cubes as they are now (no depth): the full image, or only ``window``."""
        self.captures.append((self._clock.now(), None if self._arm is None else self._arm.joint_positions()))
        self.windows.append(window)
        intrinsics = self._intrinsics if window is None else self._intrinsics.windowed(window)
        frame = render_frame(self.cubes, intrinsics, self.pose_world, supersample=4)
        return CameraFrame(frame.rgb, None, frame.intrinsics, frame.camera_pose_world, self._clock.now())


def cube(colour: str, x_m: float, y_m: float, yaw_rad: float = 0.0) -> SyntheticCube:
    """A synthetic cube resting on the table."""
    return SyntheticCube(colour, x_m, y_m, yaw_rad)


def make_context(
    clock: FakeClock | None = None,
    *,
    cubes: Iterable[SyntheticCube] = (),
    q: Sequence[float] | FloatArray = DEFAULT_HOME_Q,
    gripper_width_m: float = GRIPPER_MAX_WIDTH_M,
    object_width_m: float | None = None,
    stuck_gripper: bool = False,
    settings: ManipulationSettings | None = None,
) -> Context:
    """A ``Context`` over fake devices, with the real planner (placo + ruckig) and detector."""
    clock = clock or FakeClock()
    kinematics = ArmKinematics()
    arm = FakeArm(clock, q, kinematics)
    gripper = FakeGripper(clock, gripper_width_m, object_width_m, stuck=stuck_gripper)
    camera = FakeCamera(clock, cubes, arm=arm)
    planner = MotionPlanner(kinematics, JointLimits(), CartesianLimits(), arm.control_period_s)
    return Context(
        robot=Robot(arm=arm, gripper=gripper, camera=camera, clock=clock),
        planner=planner,
        detector=PartDetector(),
        settings=settings or ManipulationSettings(),
    )


def fake_arm(context: Context) -> FakeArm:
    """The context's arm, as the fake it is."""
    assert isinstance(context.robot.arm, FakeArm)
    return context.robot.arm


def fake_gripper(context: Context) -> FakeGripper:
    """The context's gripper, as the fake it is."""
    assert isinstance(context.robot.gripper, FakeGripper)
    return context.robot.gripper


def fake_camera(context: Context) -> FakeCamera:
    """The context's camera, as the fake it is."""
    assert isinstance(context.robot.camera, FakeCamera)
    return context.robot.camera


def fake_clock(context: Context) -> FakeClock:
    """The context's clock, as the fake it is."""
    assert isinstance(context.robot.clock, FakeClock)
    return context.robot.clock


@dataclass(frozen=True)
class Tick:
    """What one tick did: the status and feedback after it, and the arm commands the behaviour sent."""

    time_s: float
    status: Status
    feedback: str
    arm_commands: int


@dataclass
class Run:
    """The ticks of one run of a behaviour."""

    ticks: list[Tick] = field(default_factory=list)

    @property
    def status(self) -> Status:
        """The status after the last tick."""
        return self.ticks[-1].status if self.ticks else Status.INVALID

    @property
    def feedback(self) -> str:
        """The feedback after the last tick."""
        return self.ticks[-1].feedback if self.ticks else ""

    @property
    def running(self) -> list[Tick]:
        """The ticks that ended RUNNING."""
        return [t for t in self.ticks if t.status == Status.RUNNING]


def tick_until_done(
    behaviour: py_trees.behaviour.Behaviour,
    context: Context,
    max_ticks: int = 5000,
    *,
    until: Callable[[Tick], bool] | None = None,
) -> Run:
    """Tick like the runner does (tick, brake step, one control period) until not RUNNING.

    ``until`` stops earlier, after the first tick it accepts (to interrupt a behaviour mid-run).
    Raises ``AssertionError`` if the behaviour still runs after ``max_ticks``.
    """
    arm, clock = fake_arm(context), fake_clock(context)
    run = Run()
    for _ in range(max_ticks):
        before = len(arm.commands)
        behaviour.tick_once()
        tick = Tick(clock.now(), behaviour.status, behaviour.feedback_message, len(arm.commands) - before)
        run.ticks.append(tick)
        context.brake.step()
        clock.advance(arm.control_period_s)
        if until is not None and until(tick):
            return run
        if behaviour.status != Status.RUNNING:
            # As the runner does: a motion the behaviour handed on at speed runs to its end.
            while context.brake.busy:
                context.brake.step()
                clock.advance(arm.control_period_s)
            return run
    raise AssertionError(f"{behaviour.name} still RUNNING after {max_ticks} ticks: {behaviour.feedback_message}")


def brake_until_idle(context: Context, max_steps: int = 2000) -> list[ArmCommand]:
    """Step the brake (one control period each) until the arm is at rest; the brake's commands."""
    arm, clock = fake_arm(context), fake_clock(context)
    before = len(arm.commands)
    for _ in range(max_steps):
        if not context.brake.active:
            return arm.commands[before:]
        context.brake.step()
        clock.advance(arm.control_period_s)
    raise AssertionError(f"the brake still moves the arm after {max_steps} steps")
