"""MuJoCo implementations of the robot interfaces of ``bt_arrange.robot``: arm, gripper, camera, clock.

Like the pybullet devices, none of them steps the world; the cell's owner does, one control
period at a time (``MujocoCell.step``). Commands only set the actuators' controls.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.ranges import (
    checked_joint_setpoint,
    checked_render_offset,
)
from bt_arrange.robot import GRIPPER_MAX_WIDTH_M, CameraFrame, CameraIntrinsics, PixelWindow
from bt_arrange_sim.device_base import CellArm, CellCamera, CellClock, CellGripper
from bt_arrange_sim.mujoco.model import camera_quat_wxyz
from bt_arrange_sim.mujoco.rendering import OffscreenRenderer

#: The cell the devices belong to (``cell.MujocoCell``, which builds them): named by what they read of it,
#: so that the devices need not import the module that imports them.
MujocoCell = Any


def _xyzw(wxyz: np.ndarray) -> np.ndarray:
    w, x, y, z = wxyz
    return np.array([x, y, z, w])


class MujocoClock(CellClock):
    """World time of one MuJoCo cell: advances only when the cell is stepped."""


class MujocoArm(CellArm):
    """The UR5's six joints under MuJoCo position servos with velocity feed-forward, one setpoint per period.

    A ``general`` actuator's force is ``kp u - kp q - kv qd`` (``model.set_arm_gains``); with
    ``u = q_ref + (kv / kp) qd_ref`` that is ``kp (q_ref - q) + kv (qd_ref - qd)``. Within a
    control period the servo advances the setpoint along its velocity at every physics step
    (``interpolate``), as a joint controller between two setpoints does: holding the position for
    the whole period, the stiff servo braked every moving joint (measured: 220 N m on the shoulder,
    above the URDF's 150 N m, with the joint 8 mrad ahead of a held setpoint).
    """

    def __init__(self, cell: MujocoCell) -> None:
        self._cell = cell
        model = cell.model
        self._names = cell.ARM_JOINTS
        self._qpos = np.array([model.joint(n).qposadr[0] for n in self._names])
        self._dof = np.array([model.joint(n).dofadr[0] for n in self._names])
        self._actuators = np.array([model.actuator(f"{n}_servo").id for n in self._names])
        kp = model.actuator_gainprm[self._actuators, 0]
        kv = -model.actuator_biasprm[self._actuators, 2]
        self._lead_s = kv / kp
        self._q_ref = np.zeros(6)
        self._qd_ref = np.zeros(6)
        self._time_step_s = cell.config.physics.time_step_s

    def joint_positions(self) -> FloatArray:
        """Measured joint positions in radians."""
        return self._cell.data.qpos[self._qpos].copy()

    def joint_velocities(self) -> FloatArray:
        """Measured joint velocities in radians per second."""
        return self._cell.data.qvel[self._dof].copy()

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Track ``positions_rad`` (with a velocity feed-forward) until the next command."""
        checked_joint_setpoint(positions_rad, velocities_rad_s)
        self._q_ref = np.asarray(positions_rad, dtype=float).copy()
        self._qd_ref = np.zeros(6) if velocities_rad_s is None else np.asarray(velocities_rad_s, dtype=float).copy()
        self.interpolate(0)

    @property
    def setpoint(self) -> tuple[FloatArray, FloatArray]:
        """The last command: positions and velocities."""
        return self._q_ref.copy(), self._qd_ref.copy()

    def interpolate(self, substep: int) -> None:
        """The servo's setpoint at physics step ``substep`` of the control period (``MujocoCell.step``)."""
        ahead_s = substep * self._time_step_s + self._lead_s
        self._cell.data.ctrl[self._actuators] = self._q_ref + ahead_s * self._qd_ref

    def tcp_pose(self) -> Pose:
        """Measured pose of the TCP (between the finger pads) in the world."""
        self._cell.forward()
        body = self._cell.tcp_body
        return Pose(self._cell.data.xpos[body].copy(), _xyzw(self._cell.data.xquat[body]))

    def reset(self, positions_rad: FloatArray) -> None:
        """Put the arm at rest at ``positions_rad`` (set-up only, never during a task)."""
        data = self._cell.data
        data.qpos[self._qpos] = positions_rad
        data.qvel[self._dof] = 0.0
        self.command(np.asarray(positions_rad, dtype=float))
        self._cell.invalidate()


class MujocoGripper(CellGripper):
    """Two mirrored, force-limited prismatic fingers coupled by an equality constraint (the linkage).

    Each finger joint is the distance of its pad from the centre, so the opening is their sum.
    Each finger's servo is a velocity servo whose gain is ``force / (speed / 2)``: closing, it runs at
    ``-speed / 2`` and, blocked by the part, presses with the grip force (the pybullet cell's
    force-limited velocity motor); opening, a position loop (``finger_position_gain_1_s``) capped
    at ``speed / 2`` with the cell's opening force (the pybullet cell's position motor with
    ``maxVelocity``).
    """

    def __init__(self, cell: MujocoCell) -> None:
        self._cell = cell
        model = cell.model
        self._qpos = np.array([model.joint(n).qposadr[0] for n in cell.FINGER_JOINTS])
        self._dof = np.array([model.joint(n).dofadr[0] for n in cell.FINGER_JOINTS])
        self._actuators = np.array([model.actuator(f"{n}_servo").id for n in cell.FINGER_JOINTS])
        #: ("open", target per finger, speed per finger) or ("close", velocity per finger).
        self._mode: tuple[str, float, float] = ("open", GRIPPER_MAX_WIDTH_M / 2, 0.075)

    def _drive_open(self, width_m: float, speed_m_s: float) -> None:
        self._set_force(self._cell.config.physics.finger_open_force_n, speed_m_s / 2)
        self._mode = ("open", width_m / 2, speed_m_s / 2)
        self.update()

    def _drive_close(self, force_n: float, speed_m_s: float) -> None:
        self._set_force(force_n, speed_m_s / 2)
        self._mode = ("close", -speed_m_s / 2, 0.0)
        self.update()

    def update(self) -> None:
        """The fingers' velocity setpoints for the next control period (``MujocoCell.step`` calls it)."""
        kind, value, speed = self._mode
        data = self._cell.data
        if kind == "close":
            data.ctrl[self._actuators] = value
            return
        gain = self._cell.mujoco_physics.finger_position_gain_1_s
        error = value - data.qpos[self._qpos]
        data.ctrl[self._actuators] = np.clip(gain * error, -speed, speed)

    def _set_force(self, force_n: float, speed_m_s: float) -> None:
        """The servo's gain: at ``speed_m_s`` short of its setpoint (blocked) a finger presses with ``force_n``."""
        model = self._cell.model
        gain = force_n / speed_m_s
        model.actuator_gainprm[self._actuators, 0] = gain
        model.actuator_biasprm[self._actuators, 2] = -gain

    def width(self) -> float:
        """Measured opening between the pads in metres."""
        return float(np.sum(self._cell.data.qpos[self._qpos]))

    def is_moving(self) -> bool:
        """True while either finger moves faster than 1 mm/s."""
        return bool(np.any(np.abs(self._cell.data.qvel[self._dof]) > 1e-3))

    def reset(self, width_m: float) -> None:
        """Put the fingers at rest at an opening (set-up only)."""
        self._cell.data.qpos[self._qpos] = width_m / 2
        self._cell.data.qvel[self._dof] = 0.0
        self._cell.invalidate()
        self.open(width_m)


class MujocoCamera(CellCamera):
    """The top RGB-D camera, rendered by MuJoCo (OpenGL, offscreen): the pybullet cell's intrinsics and pose.

    The ideal cell's camera is its nominal pinhole (``CameraIntrinsics.from_fov``), which is what
    OpenGL renders (``rendering``); ``set_render_offset`` moves the rendering camera, as the
    pybullet camera's does, for the perception error injector.
    """

    def __init__(self, cell: MujocoCell) -> None:
        self._cell = cell
        config = cell.config.camera
        self._intrinsics = CameraIntrinsics.from_fov(config.width_px, config.height_px, config.horizontal_fov_deg)
        self._pose_world = config.pose_world()
        self.true_intrinsics = self._intrinsics
        self._full_window = PixelWindow.full(self._intrinsics)
        self._renderer: OffscreenRenderer | None = None  # made at the first frame: a cell rebuilt before has none
        self._camera_id = cell.model.camera("top").id
        self._render_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def true_pose_world(self) -> Pose:
        """The pose the camera renders from (evaluation only)."""
        return self._rendered_pose()

    def set_render_offset(self, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Error injection: render from a camera moved by (dx, dy) and turned by dyaw about the vertical.

        Frames still report the calibrated ``pose_world`` (``SimCamera.set_render_offset``).
        """
        self._render_offset = checked_render_offset(dx_m, dy_m, dyaw_rad)
        pose = self._rendered_pose()
        model = self._cell.model
        model.cam_pos[self._camera_id] = pose.position_m
        model.cam_quat[self._camera_id] = camera_quat_wxyz(pose)
        self._cell.invalidate()

    def _rendered_pose(self) -> Pose:
        dx, dy, dyaw = self._render_offset
        if (dx, dy, dyaw) == (0.0, 0.0, 0.0):
            return self._pose_world
        c, s = np.cos(dyaw), np.sin(dyaw)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return Pose.from_rotation(
            self._pose_world.position_m + np.array([dx, dy, 0.0]), turn @ self._pose_world.rotation
        )

    def window_intrinsics(self, window: PixelWindow) -> CameraIntrinsics:
        """Intrinsics of the frame rendered through ``window``: the full image's, windowed (area binning)."""
        return self._intrinsics.windowed(window)

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """Render one frame of the world as it is now: the full image, or only ``window``."""
        window = self._full_window if window is None else window
        intrinsics = self._intrinsics if window == self._full_window else self.window_intrinsics(window)
        self._cell.forward()
        if self._renderer is None:
            config = self._cell.config.camera
            self._renderer = OffscreenRenderer(self._cell.model, "top", self._intrinsics, config.near_m, config.far_m)
        rgb, depth = self._renderer.render(self._cell.data, window, with_depth)
        return self._frame(rgb, depth, intrinsics)

    def close(self) -> None:
        """Free the renderer."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
