"""What every engine's devices share: the clock, the gripper's commands checked and defaulted, the camera's frames.

An engine's devices subclass these and say only how they drive their world (``_drive_open``,
``_drive_close``, the renderer); the ranges are ``bt_arrange_sim.ranges``'.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bt_arrange.geometry import Pose
from bt_arrange.ranges import checked_grip_force_n, checked_gripper_speed_m_s, checked_gripper_width_m
from bt_arrange.robot import GRIPPER_MAX_WIDTH_M, CameraFrame, CameraIntrinsics


class CellClock:
    """World time of one cell: advances only when the cell is stepped."""

    def __init__(self, cell: Any) -> None:
        self._cell = cell

    def now(self) -> float:
        """Seconds of simulated time since the cell was built."""
        return self._cell.sim_time_s


class CellGripper:
    """The 2F-85's ``open`` and ``close``: ranges checked, speeds defaulted from the cell, the grasp told to the cell.

    ``_cell`` is the engine's cell (its ``config.physics``, ``begin_grasp`` and ``end_grasp``).
    """

    _cell: Any

    @property
    def max_width_m(self) -> float:
        """The 2F-85 stroke in metres."""
        return GRIPPER_MAX_WIDTH_M

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Move to an opening of ``width_m`` at ``speed_m_s`` (defaults to the cell's opening speed)."""
        checked_gripper_width_m(width_m)
        physics = self._cell.config.physics
        speed = checked_gripper_speed_m_s(physics.gripper_open_speed_m_s if speed_m_s is None else speed_m_s)
        self._cell.end_grasp(width_m)
        self._drive_open(width_m, speed)

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Close at ``speed_m_s`` until each pad presses with at most ``force_n``."""
        checked_grip_force_n(force_n)
        physics = self._cell.config.physics
        speed = checked_gripper_speed_m_s(physics.gripper_speed_m_s if speed_m_s is None else speed_m_s)
        self._cell.begin_grasp()
        self._drive_close(force_n, speed)

    def _drive_open(self, width_m: float, speed_m_s: float) -> None:
        """Command the fingers to an opening of ``width_m`` at ``speed_m_s`` (checked)."""
        raise NotImplementedError

    def _drive_close(self, force_n: float, speed_m_s: float) -> None:
        """Command the fingers to close at ``speed_m_s`` pressing with at most ``force_n`` (checked)."""
        raise NotImplementedError


class CellCamera:
    """The top camera's reported intrinsics and pose, its render offset, and a frame from a rendered image.

    ``_cell`` is the engine's cell (its ``camera_noise`` and ``sim_time_s``).
    """

    _cell: Any
    _intrinsics: CameraIntrinsics
    _pose_world: Pose
    _render_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """Pinhole intrinsics the camera reports (a real cell's: the nominal ones)."""
        return self._intrinsics

    @property
    def pose_world(self) -> Pose:
        """``T_W_C``, optical frame (x right, y down, z forward), as the camera reports it."""
        return self._pose_world

    @property
    def render_offset(self) -> tuple[float, float, float]:
        """The physical displacement rendered from: (dx_m, dy_m, dyaw_rad); zeros when calibrated (the default)."""
        return self._render_offset

    def _frame(self, rgb: np.ndarray, depth: np.ndarray | None, intrinsics: CameraIntrinsics) -> CameraFrame:
        """The frame of a rendered image: the cell's camera noise on it, the reported pose, the world time."""
        rgb = self._cell.camera_noise.apply(rgb)
        return CameraFrame(rgb, depth, intrinsics, self._pose_world, self._cell.sim_time_s)


class CellArm:
    """The UR5's joint names and control period, read off the engine's cell (``_cell``, ``_names``)."""

    _cell: Any
    _names: tuple[str, ...]

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The six arm joints, base to wrist."""
        return self._names

    @property
    def control_period_s(self) -> float:
        """Seconds between two setpoints."""
        return self._cell.config.physics.control_period_s
