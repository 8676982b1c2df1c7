"""The interfaces behaviours use to reach the world: an Arm, a Gripper, a Camera and a Clock.

``bt_arrange`` never imports a simulator. The pybullet work cell (``bt_arrange_sim``)
implements these protocols, tests implement them with fakes, and a real UR5 backend
could implement them later without touching a behaviour.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from bt_arrange.geometry import FloatArray, Pose

#: Robotiq 2F-85 stroke: the opening between the finger pads, in metres.
GRIPPER_MAX_WIDTH_M = 0.085
#: Robotiq 2F-85 grip force range, in newtons.
GRIPPER_FORCE_RANGE_N = (20.0, 235.0)
#: Robotiq 2F-85 closing speed range, in metres per second.
GRIPPER_SPEED_RANGE_M_S = (0.020, 0.150)


@runtime_checkable
class Clock(Protocol):
    """World time. In simulation it advances only when the world is stepped."""

    def now(self) -> float:
        """Seconds of world time since the world started."""
        ...


@runtime_checkable
class Arm(Protocol):
    """A position-controlled arm that follows one joint setpoint per control period."""

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the arm joints, in the order of every joint vector."""
        ...

    @property
    def control_period_s(self) -> float:
        """Seconds between two setpoints."""
        ...

    def joint_positions(self) -> FloatArray:
        """Measured joint positions in radians."""
        ...

    def joint_velocities(self) -> FloatArray:
        """Measured joint velocities in radians per second."""
        ...

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Set the setpoint to track until the next command (velocities are a feed-forward)."""
        ...

    def tcp_pose(self) -> Pose:
        """Measured pose of the tool centre point (between the fingertips) in the world frame."""
        ...


@runtime_checkable
class Gripper(Protocol):
    """A parallel gripper; widths are the opening between the pads in metres."""

    @property
    def max_width_m(self) -> float:
        """Widest opening in metres."""
        ...

    def open(self, width_m: float) -> None:
        """Move the fingers to an opening of ``width_m``; returns at once."""
        ...

    def close(self, force_n: float) -> None:
        """Close until the fingers squeeze with at most ``force_n``; returns at once."""
        ...

    def width(self) -> float:
        """Measured opening between the pads in metres."""
        ...

    def is_moving(self) -> bool:
        """True while the fingers still move."""
        ...


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics in pixels (OpenCV convention, no distortion unless given)."""

    width_px: int
    height_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def matrix(self) -> FloatArray:
        """The 3x3 camera matrix K."""
        return np.array([[self.fx_px, 0.0, self.cx_px], [0.0, self.fy_px, self.cy_px], [0.0, 0.0, 1.0]])

    @classmethod
    def from_fov(cls, width_px: int, height_px: int, horizontal_fov_deg: float) -> CameraIntrinsics:
        """Square pixels, principal point at the image centre, from the horizontal field of view."""
        fx = (width_px / 2.0) / np.tan(np.radians(horizontal_fov_deg) / 2.0)
        return cls(width_px, height_px, float(fx), float(fx), (width_px - 1) / 2.0, (height_px - 1) / 2.0)


@dataclass(frozen=True)
class CameraFrame:
    """One camera frame: what a detection needs, and nothing from the simulator's ground truth.

    ``camera_pose_world`` is ``T_W_C`` with the OpenCV optical frame: x right, y down, z forward.
    """

    rgb: NDArray[np.uint8]
    depth_m: NDArray[np.float32] | None
    intrinsics: CameraIntrinsics
    camera_pose_world: Pose
    time_s: float


@runtime_checkable
class Camera(Protocol):
    """A calibrated camera fixed in the world."""

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """The camera's intrinsics."""
        ...

    def capture(self, with_depth: bool = False) -> CameraFrame:
        """Take one frame; depth only when asked, because rendering is the slow part."""
        ...


@dataclass(frozen=True)
class Robot:
    """What a behaviour receives in ``setup()``: the four interfaces of one work cell."""

    arm: Arm
    gripper: Gripper
    camera: Camera
    clock: Clock
