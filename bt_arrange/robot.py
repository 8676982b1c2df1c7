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

from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.shapes.gripper import ROBOTIQ_2F85

#: Robotiq 2F-85 stroke: the opening between the finger pads, in metres (``ROBOTIQ_2F85``).
GRIPPER_MAX_WIDTH_M = ROBOTIQ_2F85.stroke_m
#: Robotiq 2F-85 grip force range, in newtons.
GRIPPER_FORCE_RANGE_N = ROBOTIQ_2F85.force_range_n
#: Robotiq 2F-85 closing speed range, in metres per second.
GRIPPER_SPEED_RANGE_M_S = ROBOTIQ_2F85.speed_range_m_s


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

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Move the fingers to an opening of ``width_m`` at ``speed_m_s`` (None: the device's own); returns at once."""
        ...

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Close at ``speed_m_s`` (None: the device's own) until the fingers squeeze with at most ``force_n``.

        Returns at once.
        """
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

    def windowed(self, window: PixelWindow) -> CameraIntrinsics:
        """The intrinsics of a window of this image, read out with ``window.binning`` (area binning).

        A window moves the principal point by its offset; binning ``b`` averages ``b x b`` pixels,
        so focal lengths shrink by ``b`` and a pixel centre ``u`` becomes ``(u + 0.5) / b - 0.5``.
        Distortion coefficients are kept; they are defined in normalised coordinates.
        """
        window.check_inside(self)
        b = window.binning
        return CameraIntrinsics(
            window.out_width_px,
            window.out_height_px,
            self.fx_px / b,
            self.fy_px / b,
            (self.cx_px + 0.5 - window.x_px) / b - 0.5,
            (self.cy_px + 0.5 - window.y_px) / b - 0.5,
            self.distortion,
        )


@dataclass(frozen=True)
class PixelWindow:
    """A rectangle of a camera's full image, in full-resolution pixels: a region of interest.

    Columns ``x_px`` to ``x_px + width_px - 1`` and rows ``y_px`` to ``y_px + height_px - 1``,
    read out at one pixel per ``binning x binning`` block (1: full resolution), so the frame is
    ``width_px / binning`` by ``height_px / binning`` pixels. A real camera would read out a
    sensor window (and bin it); the simulated one renders only that part of the scene.
    """

    x_px: int
    y_px: int
    width_px: int
    height_px: int
    binning: int = 1

    def __post_init__(self) -> None:
        if self.x_px < 0 or self.y_px < 0:
            raise OutOfRangeError(f"pixel window starts at ({self.x_px}, {self.y_px}): outside the image")
        if self.binning < 1:
            raise OutOfRangeError(f"pixel window binning {self.binning} must be at least 1")
        if self.width_px < self.binning or self.height_px < self.binning:
            raise OutOfRangeError(
                f"pixel window {self.width_px}x{self.height_px} px is smaller than one "
                f"{self.binning}x{self.binning} bin"
            )
        if self.width_px % self.binning or self.height_px % self.binning:
            raise OutOfRangeError(
                f"pixel window {self.width_px}x{self.height_px} px is not a whole number of "
                f"{self.binning}x{self.binning} bins"
            )

    @property
    def out_width_px(self) -> int:
        """Width of the frame read out, in its own pixels."""
        return self.width_px // self.binning

    @property
    def out_height_px(self) -> int:
        """Height of the frame read out, in its own pixels."""
        return self.height_px // self.binning

    @classmethod
    def full(cls, intrinsics: CameraIntrinsics, binning: int = 1) -> PixelWindow:
        """The whole image (its size rounded down to whole bins)."""
        return cls(
            0,
            0,
            intrinsics.width_px // binning * binning,
            intrinsics.height_px // binning * binning,
            binning,
        )

    @classmethod
    def covering(
        cls, intrinsics: CameraIntrinsics, u_min_px: float, v_min_px: float, u_max_px: float, v_max_px: float
    ) -> PixelWindow | None:
        """The smallest full-resolution window holding the pixels of a box, cut to the image; None if outside."""
        x0 = max(0, int(np.floor(u_min_px)))
        y0 = max(0, int(np.floor(v_min_px)))
        x1 = min(intrinsics.width_px, int(np.ceil(u_max_px)) + 1)
        y1 = min(intrinsics.height_px, int(np.ceil(v_max_px)) + 1)
        if x1 <= x0 or y1 <= y0:
            return None
        return cls(x0, y0, x1 - x0, y1 - y0)

    def is_full(self, intrinsics: CameraIntrinsics) -> bool:
        """True when this is the whole image at full resolution."""
        return self == PixelWindow(0, 0, intrinsics.width_px, intrinsics.height_px)

    def check_inside(self, intrinsics: CameraIntrinsics) -> None:
        """Raise ``OutOfRangeError`` unless the window lies inside an image of ``intrinsics``."""
        if self.x_px + self.width_px > intrinsics.width_px or self.y_px + self.height_px > intrinsics.height_px:
            raise OutOfRangeError(
                f"pixel window {self.width_px}x{self.height_px} px at ({self.x_px}, {self.y_px}) leaves the "
                f"{intrinsics.width_px}x{intrinsics.height_px} px image"
            )


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
        """The intrinsics of the camera's full image."""
        ...

    @property
    def pose_world(self) -> Pose:
        """``T_W_C``, the calibrated pose of the optical frame (x right, y down, z forward)."""
        ...

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """Take one frame; depth only when asked, because rendering is the slow part.

        With a ``window``, only that part of the image, at its binning: the frame's intrinsics
        are those of the window (principal point moved by its offset), so perception needs no
        special case. Without one, the full image.
        """
        ...


@dataclass(frozen=True)
class Robot:
    """What a behaviour receives in ``setup()``: the four interfaces of one work cell."""

    arm: Arm
    gripper: Gripper
    camera: Camera
    clock: Clock
