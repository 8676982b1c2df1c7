"""pybullet implementations of the robot interfaces of ``bt_arrange.robot``.

Each device talks to one world's ``BulletClient``; none of them steps the simulation:
the world's owner (the runner, a benchmark) does, one control period at a time.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.robot import (
    GRIPPER_FORCE_RANGE_N,
    GRIPPER_MAX_WIDTH_M,
    GRIPPER_SPEED_RANGE_M_S,
    CameraFrame,
    CameraIntrinsics,
    PixelWindow,
)

if TYPE_CHECKING:
    from bt_arrange_sim.cell import WorkCell


class SimClock:
    """World time of one cell: advances only when the cell is stepped."""

    def __init__(self, cell: WorkCell) -> None:
        self._cell = cell

    def now(self) -> float:
        """Seconds of simulated time since the cell was built."""
        return self._cell.sim_time_s


class SimArm:
    """The UR5's six joints under pybullet position control, fed one setpoint per control period."""

    def __init__(self, cell: WorkCell) -> None:
        self._cell = cell
        self._client = cell.client
        self._body = cell.robot_id
        self._indices = list(cell.arm_joint_indices)
        self._efforts_n_m = list(cell.arm_joint_efforts_n_m)
        self._names = tuple(cell.joint_name(i) for i in self._indices)
        # A real cell's joint repeatability: the arm rests a little off each new setpoint, the
        # encoders read the setpoint (realcell.JointRepeatability). Zeros in the ideal cell.
        repeatability = cell.config.errors.joints
        self._joint_sigma_rad = repeatability.joint_sigma_mrad / 1000 if repeatability.enabled else 0.0
        self._joint_rng = cell.config.errors.rng("joints", per_run=True)
        self._joint_error = np.zeros(6)
        self._rest_q: FloatArray | None = None

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The six arm joints, base to wrist."""
        return self._names

    @property
    def control_period_s(self) -> float:
        """Seconds between two setpoints."""
        return self._cell.config.physics.control_period_s

    def joint_positions(self) -> FloatArray:
        """Measured joint positions in radians."""
        measured = np.array([s[0] for s in self._client.getJointStates(self._body, self._indices)])
        return measured - self._joint_error if self._joint_sigma_rad else measured

    def joint_velocities(self) -> FloatArray:
        """Measured joint velocities in radians per second."""
        return np.array([s[1] for s in self._client.getJointStates(self._body, self._indices)])

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Track ``positions_rad`` (with a velocity feed-forward) until the next command."""
        import pybullet

        velocities = np.zeros(6) if velocities_rad_s is None else np.asarray(velocities_rad_s, dtype=float)
        physics = self._cell.config.physics
        positions = np.asarray(positions_rad, dtype=float)
        if self._joint_sigma_rad:
            resting = not np.any(velocities)
            if resting and (self._rest_q is None or not np.array_equal(positions, self._rest_q)):
                self._rest_q = positions.copy()
                self._joint_error = self._joint_rng.normal(0.0, self._joint_sigma_rad, 6)
            positions = positions + self._joint_error
        self._client.setJointMotorControlArray(
            self._body,
            self._indices,
            pybullet.POSITION_CONTROL,
            targetPositions=list(positions),
            targetVelocities=list(velocities),
            forces=self._efforts_n_m,
            positionGains=[physics.arm_position_gain] * 6,
            velocityGains=[physics.arm_velocity_gain] * 6,
        )

    def tcp_pose(self) -> Pose:
        """Measured pose of the TCP (between the finger pads) in the world."""
        state = self._client.getLinkState(self._body, self._cell.tcp_link_index, computeForwardKinematics=True)
        return Pose(np.array(state[4]), np.array(state[5]))

    def reset(self, positions_rad: FloatArray) -> None:
        """Put the arm at rest at ``positions_rad`` (set-up only, never during a task)."""
        for index, q in zip(self._indices, positions_rad, strict=True):
            self._client.resetJointState(self._body, index, float(q), 0.0)
        self.command(np.asarray(positions_rad, dtype=float))


class SimGripper:
    """Two mirrored, force-limited prismatic fingers kept centred by a gear constraint.

    Each finger joint is the distance of its pad from the centre, so the opening is their sum.
    """

    def __init__(self, cell: WorkCell) -> None:
        self._cell = cell
        self._client = cell.client
        self._body = cell.robot_id
        self._fingers = list(cell.finger_joint_indices)

    @property
    def max_width_m(self) -> float:
        """The 2F-85 stroke in metres."""
        return GRIPPER_MAX_WIDTH_M

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Move to an opening of ``width_m`` at ``speed_m_s`` (defaults to the cell's opening speed)."""
        import pybullet

        if not 0.0 <= width_m <= GRIPPER_MAX_WIDTH_M:
            raise OutOfRangeError(
                f"gripper width {width_m * 1000:.1f} mm is outside 0 to {GRIPPER_MAX_WIDTH_M * 1000:.0f} mm"
            )
        physics = self._cell.config.physics
        speed = self._checked_speed(physics.gripper_open_speed_m_s if speed_m_s is None else speed_m_s)
        for finger in self._fingers:
            self._client.setJointMotorControl2(
                self._body,
                finger,
                pybullet.POSITION_CONTROL,
                targetPosition=width_m / 2,
                maxVelocity=speed / 2,
                force=physics.finger_open_force_n,
                positionGain=physics.finger_position_gain,
            )

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Close at ``speed_m_s`` until each pad presses with at most ``force_n``."""
        import pybullet

        low, high = GRIPPER_FORCE_RANGE_N
        if not low <= force_n <= high:
            raise OutOfRangeError(f"grip force {force_n:.1f} N is outside {low:.0f} to {high:.0f} N")
        speed = self._checked_speed(speed_m_s)
        for finger in self._fingers:
            self._client.setJointMotorControl2(
                self._body, finger, pybullet.VELOCITY_CONTROL, targetVelocity=-speed / 2, force=force_n
            )

    def width(self) -> float:
        """Measured opening between the pads in metres."""
        return float(sum(s[0] for s in self._client.getJointStates(self._body, self._fingers)))

    def is_moving(self) -> bool:
        """True while either finger moves faster than 1 mm/s."""
        return any(abs(s[1]) > 1e-3 for s in self._client.getJointStates(self._body, self._fingers))

    def reset(self, width_m: float) -> None:
        """Put the fingers at rest at an opening (set-up only)."""
        for finger in self._fingers:
            self._client.resetJointState(self._body, finger, width_m / 2, 0.0)
        self.open(width_m)

    def _checked_speed(self, speed_m_s: float | None) -> float:
        speed = self._cell.config.physics.gripper_speed_m_s if speed_m_s is None else speed_m_s
        low, high = GRIPPER_SPEED_RANGE_M_S
        if not low <= speed <= high:
            raise OutOfRangeError(
                f"gripper speed {speed * 1000:.0f} mm/s is outside {low * 1000:.0f} to {high * 1000:.0f} mm/s"
            )
        return speed


class SimCamera:
    """The top RGB-D camera, rendered with pybullet's TinyRenderer (CPU, no display needed)."""

    def __init__(self, cell: WorkCell) -> None:
        self._cell = cell
        config = cell.config.camera
        self._intrinsics = config.calibrated_intrinsics()
        self._pose_world = config.pose_world()
        # A real cell's camera (realcell.CameraCalibrationError): images come from the true camera,
        # frames report the calibrated one. In the ideal cell the two are the same.
        errors = cell.config.errors
        self._true = errors.camera_draw() if errors.camera.enabled else None
        self._imaging = errors.imaging if errors.imaging.enabled else None
        self._light_rng = errors.rng("imaging", per_run=True)
        self._distortion_maps: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._true_pose_world = self._pose_world
        if self._true is not None:
            t = self._true
            turn = _small_rotation(t["rx"], t["ry"], t["rz"])
            self._true_pose_world = Pose.from_rotation(
                self._pose_world.position_m + np.array([t["dx"], t["dy"], t["dz"]]), self._pose_world.rotation @ turn
            )
        # OpenGL looks down its -z with y up; the OpenCV optical frame looks down +z with y down.
        flip = np.diag([1.0, -1.0, -1.0, 1.0])
        self._view_matrix = list(np.linalg.inv(self._true_pose_world.matrix @ flip).flatten(order="F"))
        # Error injection only (``set_render_offset``): the view actually rendered, normally the calibrated one.
        self._render_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self._render_view_matrix = self._view_matrix
        # Uncalibrated pinhole: windows shift it by the renderer's half pixel in their own pixels.
        self._nominal = CameraIntrinsics.from_fov(config.width_px, config.height_px, config.horizontal_fov_deg)
        self._full_window = PixelWindow.full(self._intrinsics)
        vertical_fov_deg = math.degrees(2.0 * math.atan((config.height_px / 2.0) / self._intrinsics.fy_px))
        self._projection_matrix = cell.client.computeProjectionMatrixFOV(
            vertical_fov_deg, config.width_px / config.height_px, config.near_m, config.far_m
        )

    @property
    def render_offset(self) -> tuple[float, float, float]:
        """The physical displacement rendered from: (dx_m, dy_m, dyaw_rad); zeros when calibrated (the default)."""
        return self._render_offset

    def set_render_offset(self, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Error injection: render from a camera displaced as if its mount had been bumped.

        The rendering camera is moved by (dx_m, dy_m) along world x and y and turned by ``dyaw_rad``
        about the vertical through its centre. Frames still report the calibrated ``pose_world``, so
        poses measured from them are off: a cube appears shifted by -(dx, dy) and turned by -dyaw
        about the point below the camera. Off by default; call with no arguments (all zeros) to
        render from the calibrated pose again.
        """
        offset = (float(dx_m), float(dy_m), float(dyaw_rad))
        if not all(math.isfinite(v) for v in offset):
            raise OutOfRangeError(f"camera render offset {offset} is not finite")
        self._render_offset = offset
        if offset == (0.0, 0.0, 0.0):
            self._render_view_matrix = self._view_matrix
            return
        c, s = math.cos(offset[2]), math.sin(offset[2])
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        moved = Pose.from_rotation(
            self._true_pose_world.position_m + np.array([offset[0], offset[1], 0.0]),
            turn @ self._true_pose_world.rotation,
        )
        flip = np.diag([1.0, -1.0, -1.0, 1.0])  # as in __init__: OpenGL view from the OpenCV optical frame
        self._render_view_matrix = list(np.linalg.inv(moved.matrix @ flip).flatten(order="F"))

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """Pinhole intrinsics of the rendered image."""
        return self._intrinsics

    @property
    def pose_world(self) -> Pose:
        """``T_W_C``, optical frame (x right, y down, z forward)."""
        return self._pose_world

    def projection_matrix(self, window: PixelWindow) -> list[float]:
        """OpenGL projection (column-major, as pybullet takes it) of the frustum through ``window``.

        The full image's frustum is symmetric about the optical axis; a window's is the part of
        it through the window's pixels (an off-axis frustum, like ``glFrustum``), so each pixel
        of the window sees what that pixel of the full image sees. Binning only changes how
        many pixels the frustum is rendered into.
        """
        config = self._cell.config.camera
        near, far = config.near_m, config.far_m
        width, height = config.width_px, config.height_px
        if self._true is not None:
            return self._true_projection_matrix(window)
        # Half extents of the full frustum on the near plane (the nominal pinhole is centred).
        half_w = near * (width / 2.0) / self._nominal.fx_px
        half_h = near * (height / 2.0) / self._nominal.fy_px
        # Pixel edges u = 0 .. width map to x = -half_w .. +half_w; rows run down from +half_h.
        left = half_w * (2.0 * window.x_px / width - 1.0)
        right = half_w * (2.0 * (window.x_px + window.width_px) / width - 1.0)
        top = half_h * (1.0 - 2.0 * window.y_px / height)
        bottom = half_h * (1.0 - 2.0 * (window.y_px + window.height_px) / height)
        matrix = np.array(
            [
                [2 * near / (right - left), 0.0, (right + left) / (right - left), 0.0],
                [0.0, 2 * near / (top - bottom), (top + bottom) / (top - bottom), 0.0],
                [0.0, 0.0, -(far + near) / (far - near), -2 * far * near / (far - near)],
                [0.0, 0.0, -1.0, 0.0],
            ]
        )
        return [float(v) for v in matrix.flatten(order="F")]

    def _true_projection_matrix(self, window: PixelWindow) -> list[float]:
        """The frustum through ``window`` of the true pinhole (a real cell's intrinsics error)."""
        assert self._true is not None
        config = self._cell.config.camera
        near, far = config.near_m, config.far_m
        fx = self._nominal.fx_px * (1.0 + self._true["dfx"])
        fy = self._nominal.fy_px * (1.0 + self._true["dfy"])
        cx = self._nominal.cx_px + self._true["dcx"]
        cy = self._nominal.cy_px + self._true["dcy"]
        left = near * (window.x_px - cx) / fx
        right = near * (window.x_px + window.width_px - cx) / fx
        top = near * (cy - window.y_px) / fy
        bottom = near * (cy - (window.y_px + window.height_px)) / fy
        matrix = np.array(
            [
                [2 * near / (right - left), 0.0, (right + left) / (right - left), 0.0],
                [0.0, 2 * near / (top - bottom), (top + bottom) / (top - bottom), 0.0],
                [0.0, 0.0, -(far + near) / (far - near), -2 * far * near / (far - near)],
                [0.0, 0.0, -1.0, 0.0],
            ]
        )
        return [float(v) for v in matrix.flatten(order="F")]

    def _distort(self, rgb: np.ndarray, intrinsics: CameraIntrinsics) -> np.ndarray:
        """Resample a pinhole render as the true lens (radial ``k1`` left by the calibration) sees it."""
        assert self._true is not None
        k1 = self._true["k1"]
        if k1 == 0.0:
            return rgb
        import cv2

        height, width = rgb.shape[:2]
        # Normalised coordinates relative to the full image's optical axis, in this frame's pixels.
        key = (width, height, intrinsics.fx_px, intrinsics.fy_px, intrinsics.cx_px, intrinsics.cy_px)
        if key not in self._distortion_maps:
            u, v = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
            xd = (u - intrinsics.cx_px) / intrinsics.fx_px
            yd = (v - intrinsics.cy_px) / intrinsics.fy_px
            # Each distorted pixel shows the pinhole ray at x_u = x_d / (1 + k1 r^2) (first order).
            scale = 1.0 / (1.0 + k1 * (xd * xd + yd * yd))
            map_u = (xd * scale * intrinsics.fx_px + intrinsics.cx_px).astype(np.float32)
            map_v = (yd * scale * intrinsics.fy_px + intrinsics.cy_px).astype(np.float32)
            self._distortion_maps[key] = (map_u, map_v)
        map_u, map_v = self._distortion_maps[key]
        return cv2.remap(rgb, map_u, map_v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)

    def _light_direction(self) -> list[float]:
        """The light's direction, turned by up to ``light_jitter_deg`` per frame in a real cell."""
        direction = np.asarray(self._cell.config.camera.light_direction, dtype=float)
        if self._imaging is None or self._imaging.light_jitter_deg <= 0:
            return list(direction)
        limit = math.radians(self._imaging.light_jitter_deg)
        turn = _small_rotation(*self._light_rng.uniform(-limit, limit, 3))
        return [float(v) for v in turn @ direction]

    def window_intrinsics(self, window: PixelWindow) -> CameraIntrinsics:
        """Intrinsics of the frame rendered through ``window``.

        The calibration above (TinyRenderer samples a pixel at its corner) is half a pixel of the
        *rendered* image, so a binned render is not the area-binned full frame: its principal
        point is the nominal one of the window's frustum, moved by half a rendered pixel.
        """
        nominal = self._nominal.windowed(window)
        return dataclasses.replace(nominal, cx_px=nominal.cx_px + 0.5, cy_px=nominal.cy_px - 0.5)

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """Render one frame of the world as it is now: the full image, or only ``window``."""
        import pybullet

        config = self._cell.config.camera
        client = self._cell.client
        if (window is None or window == self._full_window) and self._true is None:
            projection, intrinsics = self._projection_matrix, self._intrinsics
            width, height = config.width_px, config.height_px
        elif window is None or window == self._full_window:
            projection, intrinsics = self.projection_matrix(self._full_window), self._intrinsics
            width, height = config.width_px, config.height_px
        else:
            intrinsics = self.window_intrinsics(window)
            projection = self.projection_matrix(window)
            width, height = window.out_width_px, window.out_height_px
        _, _, rgba, zbuffer, _ = client.getCameraImage(
            width,
            height,
            viewMatrix=self._render_view_matrix,
            projectionMatrix=projection,
            renderer=pybullet.ER_TINY_RENDERER,
            shadow=0,
            lightDirection=self._light_direction(),
            flags=pybullet.ER_NO_SEGMENTATION_MASK,
        )
        rgb = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()
        depth = None
        if with_depth:
            z = np.asarray(zbuffer, dtype=np.float64).reshape(height, width)
            near, far = config.near_m, config.far_m
            depth = (far * near / (far - (far - near) * z)).astype(np.float32)
        if self._true is not None:
            rgb = self._distort(rgb, intrinsics)
        rgb = self._cell.camera_noise.apply(rgb)
        return CameraFrame(rgb, depth, intrinsics, self._pose_world, self._cell.sim_time_s)


def _small_rotation(rx_rad: float, ry_rad: float, rz_rad: float) -> np.ndarray:
    """The rotation of a small turn about x, then y, then z (a calibration residual, a light's wobble)."""
    cx, sx, cy, sy, cz, sz = (math.cos(rx_rad), math.sin(rx_rad), math.cos(ry_rad), math.sin(ry_rad),
                              math.cos(rz_rad), math.sin(rz_rad))  # fmt: skip
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx
