"""Forward and inverse kinematics of the UR5 + 2F-85 TCP, with placo.

World conventions: z = 0 is the table top unless told otherwise, the robot's ``base_link`` sits at
``base_pose_world`` (the world origin by default), and a pose target is the pose of the URDF frame
``tcp`` (between the finger pads, at mid-pad height) in the world. Joint vectors hold the six arm
joints in URDF order (``ARM_JOINT_NAMES``), in radians; the finger joints are never moved.

Every grasp and push points the gripper straight down, so this module also builds that
orientation (``gripper_down_rotation``) and picks, among the yaws that are equivalent for a cube
or for the two-finger gripper, the one nearest the wrist's current yaw (``nearest_symmetric_yaw``).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from bt_arrange.errors import GeometryError, OutOfRangeError, UnreachableError
from bt_arrange.geometry import FloatArray, Pose, wrap_angle
from bt_arrange.motion import placo_models
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, TCP_FRAME, default_urdf_path
from bt_arrange.shapes.gripper import ROBOTIQ_2F85

# UR5 (CB3) DH parameters, which the bundled URDF's joint origins reproduce (tests/test_kinematics.py
# checks it). They give the cheap reach checks below their exact shape.
UR5_D1_M = 0.089159
UR5_A2_M = -0.425
UR5_A3_M = -0.39225
UR5_D4_M = 0.10915
UR5_D5_M = 0.09465
UR5_D6_M = 0.0823

#: The finger pads are 37.5 mm tall and the TCP sits at mid-pad height: the pad bottoms hang this far below it.
PAD_HALF_HEIGHT_M = ROBOTIQ_2F85.pad_half_height_m
#: Default gap kept between the pad bottoms and the table: pybullet's 1 mm collision margin plus
#: about 1 mm of tracking error, plus 1 mm to spare, so a grasp never scrapes the table.
DEFAULT_TABLE_CLEARANCE_M = 0.003
#: Inverse kinematics succeeds when the TCP lies this close to the target...
POSITION_TOLERANCE_M = 1e-6
#: ...and is turned this little from it.
ORIENTATION_TOLERANCE_RAD = 1e-5
#: A cube looks the same every quarter turn about its vertical axis.
CUBE_SYMMETRY_RAD = math.pi / 2
#: The two-finger gripper grasps the same way after a half turn.
GRIPPER_SYMMETRY_RAD = math.pi

#: The home configuration: gripper pointing straight down at TCP (0.25, 0.0, 0.40) m, closing axis
#: along world -y (yaw -90 deg), elbow up and behind the base (at about (-0.20, 0.11, 0.45) m).
#: Chosen to keep out of a top camera at (0.5, 0, 0.7) m looking down with a 70 x 43 deg field of
#: view, whichever way the image is turned: every corner of the gripper body and pads stays at least
#: 15 mm outside the field (at TCP z = 0.35 m it would reach 2 cm into it), and the axes of the
#: forearm and wrist links at least 11 cm. With the closing axis along y, the gripper body (12 cm
#: along its closing axis) reaches only 2.5 cm towards the camera. Only the shoulder, which no joint
#: vector moves, sits near the field's edge when the 70 deg side lies along x.
#: wrist_2 is at -pi/2, and wrist_3 as near zero as this yaw allows.
DEFAULT_HOME_Q: FloatArray = np.array(
    [-0.451815968962, -2.126117167939, 1.682788359902, -1.127467518758, -1.570796326795, -0.451815968962]
)

# In-plane distance from the shoulder axis to the wrist_3 joint centre when the arm is stretched.
_PLANAR_REACH_M = abs(UR5_A2_M) + abs(UR5_A3_M) + UR5_D5_M
# The shoulder, elbow and wrist_1 axes are parallel, and the links between them lie in one vertical
# plane that passes UR5_D4_M from the base axis: the wrist_3 centre is always in that plane.
_WRIST_CENTRE_REACH_M = math.hypot(_PLANAR_REACH_M, UR5_D4_M)
# Full Gauss-Newton steps converge in a few iterations near the solution but can jump branches or
# pile into a joint limit from far away: a step is clamped to this many radians per joint.
_MAX_STEP_RAD = 0.5
# Iterate until the residual is at round-off level (one step past the tolerance, with quadratic
# convergence), so that consecutive solutions along a line are smooth enough to differentiate.
_POLISH_POSITION_M = 1e-10
_POLISH_ORIENTATION_RAD = 1e-9


def gripper_down_rotation(yaw_rad: float) -> FloatArray:
    """Rotation of a TCP pointing straight down whose closing axis (tcp x) lies at ``yaw_rad`` about world z.

    The tcp z axis (the approach direction, from the wrist to the fingertips) points along world -z;
    the tcp x axis is ``(cos yaw, sin yaw, 0)``. ``Pose.yaw_rad`` of the result gives back ``yaw_rad``.
    """
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


def gripper_down_pose(x_m: float, y_m: float, z_m: float, yaw_rad: float = 0.0) -> Pose:
    """A TCP pose at ``(x, y, z)`` with the gripper pointing straight down at ``yaw_rad``."""
    return Pose.from_rotation([x_m, y_m, z_m], gripper_down_rotation(yaw_rad))


def nearest_symmetric_yaw(yaw_rad: float, reference_yaw_rad: float, symmetry_rad: float = CUBE_SYMMETRY_RAD) -> float:
    """Among ``yaw + k * symmetry`` the one nearest ``reference_yaw_rad`` (e.g. the wrist's current yaw).

    Use ``CUBE_SYMMETRY_RAD`` to grasp or push a cube (any of its four faces will do) and
    ``GRIPPER_SYMMETRY_RAD`` when only the gripper's own half-turn symmetry applies (placing a
    held cube at a target yaw). The result lies within ``symmetry / 2`` of the reference, unwrapped,
    so the wrist turns by the least amount.
    """
    if symmetry_rad <= 0.0:
        raise GeometryError(
            f"symmetry {symmetry_rad:g} rad must be positive",
            field="symmetry_rad",
            value=symmetry_rad,
            limit=0.0,
            unit="rad",
        )
    offset = (yaw_rad - reference_yaw_rad + symmetry_rad / 2) % symmetry_rad - symmetry_rad / 2
    return reference_yaw_rad + offset


def rotation_angle_rad(rotation_a: ArrayLike, rotation_b: ArrayLike) -> float:
    """Angle of the rotation that takes ``rotation_a`` to ``rotation_b``, in ``[0, pi]``.

    Computed with ``atan2`` rather than ``arccos``, which loses precision below about 1e-8 rad.
    """
    r = np.asarray(rotation_a, dtype=float).T @ np.asarray(rotation_b, dtype=float)
    sine = 0.5 * math.sqrt((r[2, 1] - r[1, 2]) ** 2 + (r[0, 2] - r[2, 0]) ** 2 + (r[1, 0] - r[0, 1]) ** 2)
    cosine = 0.5 * (r[0, 0] + r[1, 1] + r[2, 2] - 1.0)
    return math.atan2(sine, cosine)


class ArmKinematics:
    """Kinematics of the arm's TCP: ``forward(q)``, ``inverse(target, seed_q)``, ``check_reachable(target)``.

    ``inverse`` iterates placo's QP solver (a frame task on ``tcp``, joint limits on, the floating
    base and the finger joints masked) from the seed, with steps clamped to 0.5 rad per joint,
    until the TCP is within ``POSITION_TOLERANCE_M`` and ``ORIENTATION_TOLERANCE_RAD`` of the target.
    A solution therefore lies on the seed's branch (elbow, wrist) whenever the target allows it.

    Not thread-safe: the placo model holds the state of the last query.
    """

    def __init__(
        self,
        urdf_path: str | Path | None = None,
        *,
        base_pose_world: Pose | None = None,
        table_top_z_m: float = 0.0,
        table_clearance_m: float = DEFAULT_TABLE_CLEARANCE_M,
        max_iterations: int = 60,
    ) -> None:
        """Load the URDF (the bundled UR5 + 2F-85 by default) and set up the IK problem.

        ``base_pose_world`` is the pose of ``base_link`` in the world (identity by default).
        ``table_top_z_m`` and ``table_clearance_m`` set the lowest TCP target:
        ``table_top_z_m + table_clearance_m + PAD_HALF_HEIGHT_M``.
        ``max_iterations`` bounds one IK attempt (about 25 us per iteration).
        """
        path = Path(urdf_path) if urdf_path is not None else default_urdf_path()
        self.urdf_path = path
        self.base_pose_world = base_pose_world if base_pose_world is not None else Pose()
        self._base_is_identity = bool(np.allclose(self.base_pose_world.matrix, np.eye(4), atol=1e-15))
        self._world_to_base = self.base_pose_world.inverse()
        self.table_top_z_m = float(table_top_z_m)
        if table_clearance_m < 0.0:
            raise OutOfRangeError(
                f"table clearance {table_clearance_m:g} m must not be negative",
                field="table_clearance_m",
                value=table_clearance_m,
                limit=0.0,
                unit="m",
            )
        self.table_clearance_m = float(table_clearance_m)
        self.max_iterations = int(max_iterations)

        # One model of the URDF per live kinematics, kept for the process: placo leaks a dropped one.
        model, self._give_back = placo_models.borrow(self, str(path))
        self._robot = model.robot
        self._solver = model.solver
        self._task = model.task
        self._q_index = np.array([self._robot.get_joint_offset(n) for n in ARM_JOINT_NAMES])
        self._v_index = np.array([self._robot.get_joint_v_offset(n) for n in ARM_JOINT_NAMES])
        limits = np.array([self._robot.get_joint_limits(n) for n in ARM_JOINT_NAMES])
        self.lower_rad: FloatArray = limits[:, 0].copy()
        self.upper_rad: FloatArray = limits[:, 1].copy()

        # Where the wrist_3 joint centre sits in the tcp frame: the reach checks work on that point,
        # whose position follows from the target alone.
        self._set_q(np.zeros(6))
        t_tcp_wrist = np.linalg.inv(self._robot.get_T_world_frame(TCP_FRAME)) @ self._robot.get_T_world_frame(
            "wrist_3_link"
        )
        self._wrist_centre_in_tcp_m: FloatArray = t_tcp_wrist[:3, 3].copy()

    def release(self) -> None:
        """Give the placo model back now, for the next kinematics (a closed session's): this one is done with it.

        Without it the model goes back when this object is garbage, which for one held in a cycle (a
        tree's context) waits for the garbage collector while new runs build new models.
        """
        self._give_back()
        self._robot = self._solver = self._task = None

    # ----------------------------------------------------------------------------------------------
    # Properties

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The arm joints, in the order of every joint vector."""
        return ARM_JOINT_NAMES

    @property
    def min_tcp_z_m(self) -> float:
        """Lowest TCP height allowed for a target, in world z."""
        return self.table_top_z_m + self.table_clearance_m + PAD_HALF_HEIGHT_M

    @property
    def reach_m(self) -> float:
        """Largest distance between the shoulder and the wrist_3 joint centre (arm stretched)."""
        return _WRIST_CENTRE_REACH_M

    # ----------------------------------------------------------------------------------------------
    # Forward kinematics

    def forward(self, q: ArrayLike, frame: str = TCP_FRAME) -> Pose:
        """Pose of ``frame`` (the TCP by default) in the world for the joint vector ``q``."""
        self._set_q(self._as_q(q))
        return self._to_world(self._robot.get_T_world_frame(frame))

    def jacobian(self, q: ArrayLike) -> FloatArray:
        """6x6 TCP Jacobian in world-aligned axes: rows (vx, vy, vz, wx, wy, wz), columns the arm joints."""
        self._set_q(self._as_q(q))
        return self._current_jacobian()

    def wrist_yaw_rad(self, q: ArrayLike) -> float:
        """Yaw of the TCP's closing axis about world z: the reference for ``nearest_symmetric_yaw``."""
        return self.forward(q).yaw_rad

    # ----------------------------------------------------------------------------------------------
    # Reachability and inverse kinematics

    def check_reachable(self, target: Pose) -> None:
        """Cheap geometric checks of a TCP target, before any IK; raise ``UnreachableError`` if one fails.

        The checks: the pad bottoms stay ``table_clearance_m`` above the table; the wrist_3 joint
        centre (fixed by the target pose) lies within the arm's reach of the shoulder; and it lies
        at least the plane offset (d4) from the base axis, which no configuration can undercut.
        """
        self._check_reachable(target, self._to_base(target))

    def inverse(self, target: Pose, seed_q: ArrayLike, *, retry: bool = True) -> FloatArray:
        """Joint vector that puts the TCP at ``target`` (world frame), found from ``seed_q``.

        Raises ``UnreachableError`` when a geometric check fails (see ``check_reachable``) or when
        no attempt converges within the joint limits; the message names the residual. With
        ``retry`` (the default), a failed attempt from the seed is repeated from the seed with the
        base joint turned towards the target, then from ``DEFAULT_HOME_Q`` turned the same way;
        ``retry=False`` keeps strictly to the seed's branch (used along a line).
        """
        t_base = self._to_base(target)
        self._check_reachable(target, t_base)
        best: tuple[float, float] | None = None
        for seed in self._seeds(t_base, self._as_q(seed_q), retry):
            q, position_error_m, orientation_error_rad = self._solve(t_base, seed)
            if position_error_m < POSITION_TOLERANCE_M and orientation_error_rad < ORIENTATION_TOLERANCE_RAD:
                return q
            if best is None or position_error_m + orientation_error_rad < sum(best):
                best = (position_error_m, orientation_error_rad)
        assert best is not None
        raise UnreachableError(
            f"target {target!r} has no inverse kinematics solution within the joint limits: residual "
            f"{best[0] * 1e3:.3g} mm and {best[1]:.3g} rad, tolerance {POSITION_TOLERANCE_M * 1e3:g} mm "
            f"and {ORIENTATION_TOLERANCE_RAD:g} rad",
            pose=target,
        )

    # ----------------------------------------------------------------------------------------------
    # Internals

    def _as_q(self, q: ArrayLike) -> FloatArray:
        """Validate a joint vector's shape and values."""
        return joint_vector(q)

    def _set_q(self, q: FloatArray) -> None:
        """Put the arm joints of the placo model at ``q`` and update its frames."""
        state_q = self._robot.state.q
        state_q[self._q_index] = q
        self._robot.state.q = state_q
        self._robot.update_kinematics()

    def _get_q(self) -> FloatArray:
        """The arm joints of the placo model."""
        return np.asarray(self._robot.state.q[self._q_index], dtype=float).copy()

    def _current_jacobian(self) -> FloatArray:
        """TCP Jacobian of the current placo state, in world-aligned axes."""
        jacobian = np.asarray(self._robot.frame_jacobian(TCP_FRAME, "local_world_aligned"))[:, self._v_index]
        if not self._base_is_identity:
            rotation = self.base_pose_world.rotation
            jacobian = np.vstack([rotation @ jacobian[:3], rotation @ jacobian[3:]])
        return jacobian

    def _to_world(self, t_base_frame: ArrayLike) -> Pose:
        """A base-frame 4x4 transform as a world pose."""
        pose = Pose.from_matrix(t_base_frame)
        return pose if self._base_is_identity else self.base_pose_world @ pose

    def _to_base(self, target: Pose) -> FloatArray:
        """A world pose as a base-frame 4x4 transform."""
        return target.matrix if self._base_is_identity else (self._world_to_base @ target).matrix

    def _check_reachable(self, target: Pose, t_base: FloatArray) -> None:
        """``check_reachable`` with the target already expressed in the base frame."""
        z_m = target.z_m
        if z_m < self.min_tcp_z_m:
            raise UnreachableError(
                f"target {target!r} is below the table: TCP z {z_m:.5f} m < minimum {self.min_tcp_z_m:.5f} m "
                f"(pad bottoms {PAD_HALF_HEIGHT_M * 1e3:.2f} mm below the TCP, table top {self.table_top_z_m:.4f} m, "
                f"clearance {self.table_clearance_m * 1e3:.1f} mm)",
                pose=target,
            )
        wrist_centre = t_base[:3, :3] @ self._wrist_centre_in_tcp_m + t_base[:3, 3]
        distance_m = math.dist(wrist_centre, (0.0, 0.0, UR5_D1_M))
        if distance_m > _WRIST_CENTRE_REACH_M:
            raise UnreachableError(
                f"target {target!r} is out of reach: its wrist centre lies {distance_m:.3f} m from the shoulder, "
                f"the reach is {_WRIST_CENTRE_REACH_M:.3f} m",
                pose=target,
            )
        radial_m = math.hypot(wrist_centre[0], wrist_centre[1])
        if radial_m < UR5_D4_M:
            raise UnreachableError(
                f"target {target!r} is too close to the base axis: its wrist centre lies {radial_m:.3f} m from it, "
                f"the minimum is {UR5_D4_M:.3f} m",
                pose=target,
            )

    def _errors(self, t_target: FloatArray) -> tuple[float, float]:
        """Position (m) and orientation (rad) residuals of the current TCP against ``t_target``."""
        current = self._robot.get_T_world_frame(TCP_FRAME)
        position_error_m = math.dist(current[:3, 3], t_target[:3, 3])
        return position_error_m, rotation_angle_rad(current[:3, :3], t_target[:3, :3])

    def _clip(self, q: FloatArray) -> FloatArray:
        """A seed inside the joint limits: the QP has no feasible step from outside them."""
        return np.clip(q, self.lower_rad, self.upper_rad)

    def _seeds(self, t_target: FloatArray, seed_q: FloatArray, retry: bool) -> Iterator[FloatArray]:
        """The seeds to try, lazily: the caller's, then (``retry``) two with the base turned to the target."""
        yield self._clip(seed_q)
        if not retry:
            return
        target_wrist = t_target[:3, :3] @ self._wrist_centre_in_tcp_m + t_target[:3, 3]
        target_azimuth = math.atan2(target_wrist[1], target_wrist[0])
        for base_seed in (seed_q, DEFAULT_HOME_Q):
            self._set_q(self._clip(base_seed))
            wrist = self._robot.get_T_world_frame("wrist_3_link")[:3, 3]
            turned = base_seed.copy()
            turned[0] += wrap_angle(target_azimuth - math.atan2(wrist[1], wrist[0]))
            yield self._clip(turned)

    def _solve(self, t_target: FloatArray, seed: FloatArray) -> tuple[FloatArray, float, float]:
        """One IK attempt from ``seed``: returns the joints and the position and orientation residuals."""
        self._set_q(seed)
        self._task.T_world_frame = t_target
        position_error_m, orientation_error_rad = self._errors(t_target)
        for _ in range(self.max_iterations):
            if position_error_m < _POLISH_POSITION_M and orientation_error_rad < _POLISH_ORIENTATION_RAD:
                break
            step = np.asarray(self._solver.solve(False))[self._v_index]
            largest = float(np.max(np.abs(step)))
            if largest < 1e-14:
                break  # stuck against a joint limit: more iterations change nothing
            if largest > _MAX_STEP_RAD:
                step *= _MAX_STEP_RAD / largest
            # Scaling a step between two points inside the limits keeps it inside: the clip only
            # removes round-off.
            self._set_q(self._clip(self._get_q() + step))
            position_error_m, orientation_error_rad = self._errors(t_target)
        return self._get_q(), position_error_m, orientation_error_rad


def joint_vector(values: ArrayLike) -> FloatArray:
    """A copy of six joint values as a float array, checked for shape and finiteness."""
    q = np.array(values, dtype=float).reshape(-1)
    if q.shape != (6,) or not np.isfinite(q).all():
        raise GeometryError(f"a joint vector needs 6 finite values in radians, got {q}", field="q", value=q, unit="rad")
    return q
