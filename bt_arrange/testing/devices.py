"""The fake devices of the testing kit: a clock, an arm, a gripper and a camera, each recording what it was told.

Each implements its protocol of :mod:`bt_arrange.robot`:

- :class:`FakeClock`: world time that moves only when told to (``advance(dt_s)``).
- :class:`FakeArm`: tracks every setpoint perfectly (the measured joints are the last command) and
  records each command with the clock's time in ``commands``; its TCP pose comes from the real
  kinematics.
- :class:`FakeGripper`: the fingers move at a fixed speed as the clock advances; a close stops at
  ``object_width_m`` (a part between the pads) or at 0 (nothing); ``slip()`` lets the part go,
  ``stuck=True`` makes the fingers never report standing still, ``wedge()`` holds the next openings.
- :class:`FakeCamera`: the top camera's frames, rendered by :mod:`bt_arrange.perception.synthetic`
  for its list of ``parts`` at a reduced resolution (960 x 540, about 20 ms per frame and
  detection); a window renders only its pixels, through the window's intrinsics.

:func:`bt_arrange.testing.make_context` puts them together with the real planner and detector.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion import ARM_JOINT_NAMES, DEFAULT_HOME_Q, ArmKinematics
from bt_arrange.perception.synthetic import (
    SyntheticCube,
    SyntheticPrism,
    render_frame,
    sim_intrinsics,
    top_down_camera_pose,
)
from bt_arrange.robot import (
    GRIPPER_FORCE_RANGE_N,
    GRIPPER_MAX_WIDTH_M,
    CameraFrame,
    CameraIntrinsics,
    PixelWindow,
)

#: A part the fake camera renders: a cube or a flat prism of :mod:`bt_arrange.perception.synthetic`.
SyntheticPart: TypeAlias = SyntheticCube | SyntheticPrism

#: The UR CB3's 125 Hz, as in the simulated cell.
CONTROL_PERIOD_S = 0.008
#: Fingers of the fake gripper move at this speed (within the 2F-85's 20 to 150 mm/s).
GRIPPER_SPEED_M_S = 0.05
#: The fake camera's image, smaller than the cell's 1920 x 1080: four times fewer pixels, still about
#: 1 mm per pixel.
CAMERA_WIDTH_PX = 960
CAMERA_HEIGHT_PX = 540


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

    A close stops at ``object_width_m`` (a part between the pads) or at 0 when it is ``None``.
    ``slip()`` takes the part away: closed fingers go on closing towards 0. With ``stuck=True``
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
        """The part slips out: no object between the pads any more; closed fingers close on."""
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
    """The top camera over a table of synthetic parts; ``parts`` may be changed between frames."""

    def __init__(
        self,
        clock: FakeClock,
        parts: Iterable[SyntheticPart] = (),
        intrinsics: CameraIntrinsics | None = None,
        pose_world: Pose | None = None,
        arm: FakeArm | None = None,
    ) -> None:
        self._clock = clock
        #: What the camera sees: changed by a test between frames (a part moved, taken away, added).
        self.parts: list[SyntheticPart] = list(parts)
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
        """Render the parts as they are now (no depth): the full image, or only ``window``."""
        self.captures.append((self._clock.now(), None if self._arm is None else self._arm.joint_positions()))
        self.windows.append(window)
        intrinsics = self._intrinsics if window is None else self._intrinsics.windowed(window)
        frame = render_frame(self.parts, intrinsics, self.pose_world, supersample=4)
        return CameraFrame(frame.rgb, None, frame.intrinsics, frame.camera_pose_world, self._clock.now())
