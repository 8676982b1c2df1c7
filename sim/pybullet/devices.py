"""pybullet implementations of the robot interfaces of ``bt_arrange.robot``.

Each device talks to one world's ``BulletClient``; none of them steps the simulation:
the world's owner (the runner, a benchmark) does, one control period at a time.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.ranges import (
    checked_joint_setpoint,
    checked_joint_setpoint_lists,
    checked_render_offset,
)
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow
from bt_arrange_sim.device_base import CellArm, CellCamera, CellClock, CellGripper
from bt_arrange_sim.pybullet.table_top import TableTopFill, frustum, straight_down

#: The cell the devices belong to (``cell.WorkCell``, which builds them): named by what they read of it,
#: so that the devices need not import the module that imports them.
WorkCell = Any


def _pybullet() -> Any:
    """The pybullet module (imported when a device is built: importing this module needs no pybullet)."""
    import pybullet

    return pybullet


class SimClock(CellClock):
    """World time of one pybullet cell: advances only when the cell is stepped."""


class SimArm(CellArm):
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
        # The client's bound call and the fixed arguments, looked up once: the arm is commanded
        # every control period.
        self._set_motors = cell.client.setJointMotorControlArray
        # ``BulletClient`` builds a fresh partial at every attribute access (an ``inspect`` call and
        # a ``functools.partial``): the joint states are read several times a period, so bound once.
        self._joint_states = cell.client.getJointStates
        self._position_control = _pybullet().POSITION_CONTROL
        physics = cell.config.physics
        self._position_gains = [physics.arm_position_gain] * 6
        self._velocity_gains = [physics.arm_velocity_gain] * 6
        self._zero_velocities = [0.0] * 6

    def joint_positions(self) -> FloatArray:
        """Measured joint positions in radians."""
        measured = np.array([s[0] for s in self._joint_states(self._body, self._indices)])
        return measured - self._joint_error if self._joint_sigma_rad else measured

    def joint_velocities(self) -> FloatArray:
        """Measured joint velocities in radians per second."""
        return np.array([s[1] for s in self._joint_states(self._body, self._indices)])

    def command(self, positions_rad: FloatArray, velocities_rad_s: FloatArray | None = None) -> None:
        """Track ``positions_rad`` (with a velocity feed-forward) until the next command."""
        # Called every control period: the setpoint is checked and sent as the lists pybullet takes,
        # converted once (``checked_joint_setpoint_lists``), not as arrays checked then converted again.
        if self._joint_sigma_rad:
            checked_joint_setpoint(positions_rad, velocities_rad_s)
            positions = np.asarray(positions_rad, dtype=float)
            velocities = np.zeros(6) if velocities_rad_s is None else np.asarray(velocities_rad_s, dtype=float)
            resting = not np.any(velocities)
            if resting and (self._rest_q is None or not np.array_equal(positions, self._rest_q)):
                self._rest_q = positions.copy()
                self._joint_error = self._joint_rng.normal(0.0, self._joint_sigma_rad, 6)
            positions = positions + self._joint_error
            target_positions = positions.tolist()
            target_velocities = (
                self._zero_velocities
                if velocities_rad_s is None
                else np.asarray(velocities_rad_s, dtype=float).tolist()
            )
        else:
            target_positions, target_velocities = checked_joint_setpoint_lists(positions_rad, velocities_rad_s)
            if target_velocities is None:
                target_velocities = self._zero_velocities
        self._set_motors(
            self._body,
            self._indices,
            self._position_control,
            targetPositions=target_positions,
            targetVelocities=target_velocities,
            forces=self._efforts_n_m,
            positionGains=self._position_gains,
            velocityGains=self._velocity_gains,
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


class SimGripper(CellGripper):
    """Two mirrored, force-limited prismatic fingers kept centred by a gear constraint.

    Each finger joint is the distance of its pad from the centre, so the opening is their sum.
    """

    #: Polls further apart than this (s) are not compared for ringing (the control period is 8 ms).
    RING_POLL_S = 0.05

    def __init__(self, cell: WorkCell) -> None:
        self._cell = cell
        self._client = cell.client
        self._body = cell.robot_id
        self._fingers = list(cell.finger_joint_indices)
        # Bound once (see ``SimArm``): a guard reads the fingers' width every tick.
        self._joint_states = cell.client.getJointStates
        #: The world times and finger positions of the last two ``is_moving`` polls of different times.
        self._polls: tuple[tuple[float, list[float]], ...] = ((-1.0, []), (-1.0, []))
        #: Whether the pads' contacts have friction anchors now (the cell sets them as ``pad_contact`` says).
        self._pads_anchored = cell.config.physics.pad_contact.friction_anchor
        #: The last opening sent (width, speed), while the fingers hold it; None after a close.
        self._opening: tuple[float, float] | None = None

    def _drive_open(self, width_m: float, speed_m_s: float) -> None:
        physics = self._cell.config.physics
        held = self._unanchored_contacts()
        # The pads' friction anchors pin a held prism; opening, they pinned a stale contact point of its
        # hull too, whose normal no longer faced the pad, and held the fingers shut at 40 N (a kite wedged
        # at 40.2 mm of 85). A prism is let go without them; a box's release is as it was.
        self._anchor_pads(physics.pad_contact.friction_anchor and not held)
        if physics.fresh_prism_release_contacts:
            self._refresh_contacts(held)
        self._drive_fingers(width_m, speed_m_s)

    def _drive_fingers(self, width_m: float, speed_m_s: float) -> None:
        """Send each finger where the cell puts it for an opening of ``width_m`` (``finger_targets_m``)."""
        import pybullet

        physics = self._cell.config.physics
        self._opening = (width_m, speed_m_s)
        for finger, target_m in zip(self._fingers, self._cell.finger_targets_m(width_m), strict=True):
            self._client.setJointMotorControl2(
                self._body,
                finger,
                pybullet.POSITION_CONTROL,
                targetPosition=target_m,
                maxVelocity=speed_m_s / 2,
                force=physics.finger_open_force_n,
                positionGain=physics.finger_position_gain,
            )

    def retarget(self) -> None:
        """Send the fingers of the last opening again where the cell now puts them (re-centred)."""
        if self._opening is not None:
            self._drive_fingers(*self._opening)

    def _drive_close(self, force_n: float, speed_m_s: float) -> None:
        import pybullet

        self._opening = None
        self._anchor_pads(self._cell.config.physics.pad_contact.friction_anchor)
        for finger in self._fingers:
            self._client.setJointMotorControl2(
                self._body, finger, pybullet.VELOCITY_CONTROL, targetVelocity=-speed_m_s / 2, force=force_n
            )

    def _anchor_pads(self, anchored: bool) -> None:
        """Give the pads' contacts friction anchors, or take them away (only when that changes)."""
        if anchored == self._pads_anchored:
            return
        for finger in self._fingers:
            self._client.changeDynamics(self._body, finger, frictionAnchor=int(anchored))
        self._pads_anchored = anchored

    def width(self) -> float:
        """Measured opening between the pads in metres."""
        return float(sum(s[0] for s in self._joint_states(self._body, self._fingers)))

    def is_moving(self) -> bool:
        """True while either finger moves faster than 1 mm/s.

        On a part without friction anchors (a prism, ``PhysicsConfig.prism_contact``) the pads can
        ring in place, the fingers swinging a few micrometres together at the control rate (a
        trapezoid under the close: +2.7 to -2.1 mm/s, 8 um peak to peak, every 8 ms): there a
        finger also has to have travelled 1 mm/s's worth since the last poll (if within ``RING_POLL_S``)
        to count as moving.
        """
        states = self._joint_states(self._body, self._fingers)
        now_s, positions = self._cell.sim_time_s, [s[0] for s in states]
        if now_s != self._polls[-1][0]:
            self._polls = (self._polls[-1], (now_s, positions))
        last_s, last = self._polls[0]
        fast = [abs(s[1]) > 1e-3 for s in states]
        # A poll from before this command (a stage ago: the first polls of a command are not made)
        # says nothing of ringing: measured against one, fingers opening at 75 mm/s had travelled
        # less than 1 mm/s's worth of the seconds since and counted as still (a release "stalled").
        if not any(fast) or not last or now_s - last_s > self.RING_POLL_S or not self._on_unanchored_part():
            return any(fast)
        travelled = [abs(q - q0) > 1e-3 * (now_s - last_s) for q, q0 in zip(positions, last, strict=True)]
        return any(f and t for f, t in zip(fast, travelled, strict=True))

    def _on_unanchored_part(self) -> bool:
        """Whether a pad touches a part whose contacts have no friction anchors."""
        return bool(self._unanchored_contacts())

    def _unanchored_contacts(self) -> list[tuple[int, int]]:
        """(part body, finger link) of each pad touching a part whose contacts have no friction anchors (a prism)."""
        cell = self._cell
        if cell.config.physics.prism_contact.friction_anchor:
            return []
        unanchored = [cell.parts[n] for n, t in cell.object_types.items() if not t.shape.rectangular]
        return [
            (body, finger)
            for body in unanchored
            for finger in self._fingers
            if self._client.getContactPoints(self._body, body, linkIndexA=finger)
        ]

    def _refresh_contacts(self, pairs: list[tuple[int, int]]) -> None:
        """Make Bullet forget the contact points it keeps between these pads and parts; the next step finds them anew.

        Bullet keeps a pair's contact points from step to step, each with the normal it had when
        found, until the bodies drift 20 mm apart there (its breaking threshold). A prism's hull
        squeezed by a pad can keep a point whose normal faces the wrong way; opening, that pad
        pulled the part with it (a triangle dragged 8 mm and lifted on the retreat, a fragment
        turned 1.5 deg). The pair's collision is switched off for one collision pass, which drops
        its points, and on again: nothing moves, and the next step's contacts are the geometry's.
        """
        client = self._client
        for body, finger in pairs:
            client.setCollisionFilterPair(self._body, body, finger, -1, 0)
        if pairs:
            client.performCollisionDetection()
        for body, finger in pairs:
            client.setCollisionFilterPair(self._body, body, finger, -1, 1)

    def reset(self, width_m: float) -> None:
        """Put the fingers at rest at an opening (set-up only)."""
        for finger in self._fingers:
            self._client.resetJointState(self._body, finger, width_m / 2, 0.0)
        self.open(width_m)


class SimCamera(CellCamera):
    """The top RGB-D camera, rendered with pybullet's TinyRenderer (CPU, no display needed).

    The ideal cell's camera is its nominal pinhole, and its frames say so (``calibrated_intrinsics``,
    which holds TinyRenderer's half-pixel shift). A real cell's (``realcell.CameraCalibrationError``)
    is the *true* camera: the true pinhole seen from the true pose, warped by the true lens
    distortion; its frames report the *nominal* camera (datasheet field of view, centred principal
    point, no distortion, the drawing's pose), which only a calibration corrects.
    """

    def __init__(self, cell: WorkCell) -> None:
        self._cell = cell
        config = cell.config.camera
        self._intrinsics = config.calibrated_intrinsics()
        self._pose_world = config.pose_world()
        errors = cell.config.errors
        self._true = errors.camera_draw() if errors.camera.enabled else None
        self._imaging = errors.imaging if errors.imaging.enabled else None
        self._light_rng = errors.rng("imaging", per_run=True)
        self._warp_maps: dict[tuple, tuple[tuple[float, float], PixelWindow, np.ndarray, np.ndarray]] = {}
        #: The table top's colour and z-buffer value by view, light and table colour (``_table_top``).
        self._table_fill = TableTopFill(cell, self._rgba)
        # Uncalibrated pinhole: windows shift it by the renderer's half pixel in their own pixels.
        self._nominal = CameraIntrinsics.from_fov(config.width_px, config.height_px, config.horizontal_fov_deg)
        self._true_pose_world = self._pose_world
        #: The true camera's intrinsics and lens (pixel-centre convention): evaluation only.
        self.true_intrinsics = self._intrinsics
        if self._true is not None:
            t = self._true
            turn = _small_rotation(t["rx"], t["ry"], t["rz"])
            self._true_pose_world = Pose.from_rotation(
                self._pose_world.position_m + np.array([t["dx"], t["dy"], t["dz"]]), self._pose_world.rotation @ turn
            )
            n = self._nominal
            self.true_intrinsics = CameraIntrinsics(
                n.width_px, n.height_px, n.fx_px * (1.0 + t["dfx"]), n.fy_px * (1.0 + t["dfy"]),
                n.cx_px + t["dcx"], n.cy_px + t["dcy"], (t["k1"], t["k2"], t["p1"], t["p2"], 0.0),
            )  # fmt: skip
            # A new cell's software knows only the datasheet camera: that is what frames report.
            self._intrinsics = self._nominal
        # OpenGL looks down its -z with y up; the OpenCV optical frame looks down +z with y down.
        flip = np.diag([1.0, -1.0, -1.0, 1.0])
        self._view_matrix = list(np.linalg.inv(self._true_pose_world.matrix @ flip).flatten(order="F"))
        # Error injection only (``set_render_offset``): the view actually rendered, normally the calibrated one.
        self._render_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self._render_view_matrix = self._view_matrix
        self._full_window = PixelWindow.full(self._intrinsics)
        vertical_fov_deg = math.degrees(2.0 * math.atan((config.height_px / 2.0) / self._intrinsics.fy_px))
        self._projection_matrix = cell.client.computeProjectionMatrixFOV(
            vertical_fov_deg, config.width_px / config.height_px, config.near_m, config.far_m
        )

    @property
    def true_pose_world(self) -> Pose:
        """The true camera pose ``T_W_C`` (evaluation only: never hand it to the robot's software)."""
        return self._true_pose_world

    def set_render_offset(self, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Error injection: render from a camera displaced as if its mount had been bumped.

        The rendering camera is moved by (dx_m, dy_m) along world x and y and turned by ``dyaw_rad``
        about the vertical through its centre. Frames still report the calibrated ``pose_world``, so
        poses measured from them are off: a cube appears shifted by -(dx, dy) and turned by -dyaw
        about the point below the camera. Off by default; call with no arguments (all zeros) to
        render from the calibrated pose again.
        """
        offset = checked_render_offset(dx_m, dy_m, dyaw_rad)
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

    def projection_matrix(self, window: PixelWindow) -> list[float]:
        """OpenGL projection (column-major, as pybullet takes it) of the nominal frustum through ``window``.

        The full image's frustum is symmetric about the optical axis; a window's is the part of
        it through the window's pixels (an off-axis frustum, like ``glFrustum``), so each pixel
        of the window sees what that pixel of the full image sees. Binning only changes how
        many pixels the frustum is rendered into.
        """
        config = self._cell.config.camera
        near = config.near_m
        width, height = config.width_px, config.height_px
        # Half extents of the full frustum on the near plane (the nominal pinhole is centred).
        half_w = near * (width / 2.0) / self._nominal.fx_px
        half_h = near * (height / 2.0) / self._nominal.fy_px
        # Pixel edges u = 0 .. width map to x = -half_w .. +half_w; rows run down from +half_h.
        left = half_w * (2.0 * window.x_px / width - 1.0)
        right = half_w * (2.0 * (window.x_px + window.width_px) / width - 1.0)
        top = half_h * (1.0 - 2.0 * window.y_px / height)
        bottom = half_h * (1.0 - 2.0 * (window.y_px + window.height_px) / height)
        return frustum(left, right, bottom, top, near, config.far_m)

    def _warp(self, window: PixelWindow) -> tuple[tuple[float, float], PixelWindow, np.ndarray, np.ndarray]:
        """The true pinhole's pixels to render for ``window`` and the maps that warp them by the lens.

        Each output pixel's centre (full-resolution coordinates of the distorted image) is taken
        through the inverse of the true distortion (``cv2.undistortPoints``) to the true pinhole's
        pixel that sees the same ray; the render covers those pixels (a frustum that may reach past
        the image, binned as the window is), and the maps say where in it each output pixel lies,
        TinyRenderer's half-pixel shift of its own output taken out. Returns the region's first
        pixel edges (u, v; full-resolution), its size, and the maps.
        """
        key = (window.x_px, window.y_px, window.width_px, window.height_px, window.binning)
        if key not in self._warp_maps:
            import cv2

            k, b = self.true_intrinsics, window.binning
            i = np.arange(window.out_width_px, dtype=np.float64)
            j = np.arange(window.out_height_px, dtype=np.float64)
            u = window.x_px + (i + 0.5) * b - 0.5
            v = window.y_px + (j + 0.5) * b - 0.5
            grid = np.stack(np.meshgrid(u, v), axis=-1).reshape(-1, 1, 2)
            pinhole = cv2.undistortPoints(grid, k.matrix, np.asarray(k.distortion), P=k.matrix).reshape(
                window.out_height_px, window.out_width_px, 2
            )
            # Pixel edges (centre + 0.5) of the region to render, with room for the bilinear samples.
            e0 = np.floor(pinhole.reshape(-1, 2).min(axis=0) + 0.5) - 2 * b
            e1 = np.ceil(pinhole.reshape(-1, 2).max(axis=0) + 0.5) + 2 * b
            size = np.ceil((e1 - e0) / b).astype(int) * b
            region = PixelWindow(0, 0, int(size[0]), int(size[1]), b)  # its offset is e0 (may be negative)
            map_u = ((pinhole[..., 0] + 0.5 - e0[0]) / b).astype(np.float32)
            map_v = ((pinhole[..., 1] + 0.5 - e0[1]) / b - 1.0).astype(np.float32)
            if len(self._warp_maps) >= 64:  # windows move with the parts: keep the latest few
                self._warp_maps.pop(next(iter(self._warp_maps)))
            self._warp_maps[key] = ((float(e0[0]), float(e0[1])), region, map_u, map_v)
        return self._warp_maps[key]

    def _true_frustum(self, e0: tuple[float, float], region: PixelWindow) -> list[float]:
        """The true pinhole's frustum through the pixel edges ``e0`` to ``e0 + region size``."""
        config = self._cell.config.camera
        near, k = config.near_m, self.true_intrinsics
        left = near * (e0[0] - (k.cx_px + 0.5)) / k.fx_px
        right = near * (e0[0] + region.width_px - (k.cx_px + 0.5)) / k.fx_px
        top = near * ((k.cy_px + 0.5) - e0[1]) / k.fy_px
        bottom = near * ((k.cy_px + 0.5) - (e0[1] + region.height_px)) / k.fy_px
        return frustum(left, right, bottom, top, near, config.far_m)

    def _light_direction(self) -> list[float]:
        """The light's direction, turned by up to ``light_jitter_deg`` per frame in a real cell."""
        direction = np.asarray(self._cell.config.camera.light_direction, dtype=float)
        if self._imaging is None or self._imaging.light_jitter_deg <= 0:
            return list(direction)
        limit = math.radians(self._imaging.light_jitter_deg)
        turn = _small_rotation(*self._light_rng.uniform(-limit, limit, 3))
        return [float(v) for v in turn @ direction]

    def window_intrinsics(self, window: PixelWindow) -> CameraIntrinsics:
        """Intrinsics the camera reports for the frame rendered through ``window``.

        The ideal cell's calibration above (TinyRenderer samples a pixel at its corner) is half a
        pixel of the *rendered* image, so a binned render is not the area-binned full frame: its
        principal point is the nominal one of the window's frustum, moved by half a rendered
        pixel. A real cell reports its nominal camera, windowed.
        """
        nominal = self._nominal.windowed(window)
        if self._true is not None:
            return nominal
        return dataclasses.replace(nominal, cx_px=nominal.cx_px + 0.5, cy_px=nominal.cy_px - 0.5)

    def _render(
        self, width: int, height: int, projection: list[float], with_depth: bool
    ) -> tuple[np.ndarray, np.ndarray | None]:
        light = self._light_direction()
        image = self._over_table(width, height, projection, light)
        if image is None:
            image = self._image(width, height, projection, light)
        rgb, z = image
        depth = None
        if with_depth:
            config = self._cell.config.camera
            near, far = config.near_m, config.far_m
            depth = (far * near / (far - (far - near) * z.astype(np.float64))).astype(np.float32)
        return rgb, depth

    def _image(
        self, width: int, height: int, projection: list[float], light: list[float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """TinyRenderer's colour (rows, columns, 3) and z-buffer of everything in the world."""
        rgba, z = self._rgba(width, height, projection, light)
        return rgba[:, :, :3].copy(), z

    def _rgba(
        self, width: int, height: int, projection: list[float], light: list[float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """TinyRenderer's RGBA (rows, columns, 4) and z-buffer of everything in the world."""
        import pybullet

        _, _, rgba, zbuffer, _ = self._cell.client.getCameraImage(
            width,
            height,
            viewMatrix=self._render_view_matrix,
            projectionMatrix=projection,
            renderer=pybullet.ER_TINY_RENDERER,
            shadow=0,
            lightDirection=light,
            flags=pybullet.ER_NO_SEGMENTATION_MASK,
        )
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
        return rgba, np.asarray(zbuffer, dtype=np.float32).reshape(height, width)

    def _over_table(
        self, width: int, height: int, projection: list[float], light: list[float]
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The same image, the table's top filled in instead of shaded pixel by pixel (``table_top``); None: cannot."""
        return self._table_fill.render(self._render_view_matrix, width, height, projection, light)

    def _straight_down(self) -> bool:
        """True when the rendering camera's optical axis is the world's vertical (the table's top at one depth)."""
        return straight_down(self._render_view_matrix)

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """Render one frame of the world as it is now: the full image, or only ``window``."""
        config = self._cell.config.camera
        full = window is None or window == self._full_window
        if self._true is not None:
            window = self._full_window if window is None else window
            intrinsics = self._intrinsics if full else self.window_intrinsics(window)
            origin, region, map_u, map_v = self._warp(window)
            projection = self._true_frustum(origin, region)
            pinhole, pinhole_depth = self._render(region.out_width_px, region.out_height_px, projection, with_depth)
            import cv2

            rgb = cv2.remap(pinhole, map_u, map_v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            depth = (
                None
                if pinhole_depth is None
                else cv2.remap(pinhole_depth, map_u, map_v, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)
            )
        else:
            if full:
                projection, intrinsics = self._projection_matrix, self._intrinsics
                width, height = config.width_px, config.height_px
            else:
                assert window is not None
                intrinsics = self.window_intrinsics(window)
                projection = self.projection_matrix(window)
                width, height = window.out_width_px, window.out_height_px
            rgb, depth = self._render(width, height, projection, with_depth)
        return self._frame(rgb, depth, intrinsics)


def _small_rotation(rx_rad: float, ry_rad: float, rz_rad: float) -> np.ndarray:
    """The rotation of a small turn about x, then y, then z (a calibration residual, a light's wobble)."""
    cx, sx, cy, sy, cz, sz = (math.cos(rx_rad), math.sin(rx_rad), math.cos(ry_rad), math.sin(ry_rad),
                              math.cos(rz_rad), math.sin(rz_rad))  # fmt: skip
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx
