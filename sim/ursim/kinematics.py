"""The controller's own kinematics, in Universal Robots' conventions, on top of the project's placo model.

A UR controller reports and takes poses as ``[x, y, z, rx, ry, rz]`` (metres, and a rotation
vector in radians) of the TCP in its ``base`` frame. ``base`` is the ROS description's
``base_link`` turned half a turn about z (ur_description's ``base_link-base_fixed_joint``), the
flange is ``tool0``, and the TCP is the flange moved by the TCP offset (``set_tcp``, zero until
set). The joint angles are the description's.

The controller computes with the nominal description (the bundled URDF), as a real controller
computes with its own kinematic model: in a real cell (``--cell real``) the simulated arm is the
perturbed one, so its TCP is where the nominal model says only up to the arm's error.

Not thread-safe (placo's model keeps the last query's state): the physics thread alone uses it.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from bt_arrange.geometry import Pose
from bt_arrange.motion import TCP_FRAME, ArmKinematics

#: ``base_link`` to UR's ``base``: half a turn about z.
BASE_LINK_TO_BASE = np.diag([-1.0, -1.0, 1.0, 1.0])
FLANGE_FRAME = "tool0"


def pose_to_matrix(pose: list[float] | np.ndarray) -> np.ndarray:
    """A UR pose vector ``[x, y, z, rx, ry, rz]`` as a 4x4 transform."""
    values = np.asarray(pose, dtype=float)
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_rotvec(values[3:6]).as_matrix()
    matrix[:3, 3] = values[:3]
    return matrix


def matrix_to_pose(matrix: np.ndarray) -> list[float]:
    """A 4x4 transform as a UR pose vector ``[x, y, z, rx, ry, rz]``."""
    rotation_vector = Rotation.from_matrix(matrix[:3, :3]).as_rotvec()
    return [*(float(v) for v in matrix[:3, 3]), *(float(v) for v in rotation_vector)]


class UrKinematics:
    """Forward and inverse kinematics of the flange and TCP in UR's ``base`` frame."""

    def __init__(self) -> None:
        self._model = ArmKinematics()
        self.lower_rad = self._model.lower_rad
        self.upper_rad = self._model.upper_rad
        zero = np.zeros(6)
        #: The URDF's ``tcp`` (between the finger pads, mid-pad) seen from the flange: ``set_tcp`` this
        #: (``matrix_to_pose``) and the controller's TCP is the simulated backend's.
        self.flange_to_pads_tcp = (
            np.linalg.inv(self._model.forward(zero, FLANGE_FRAME).matrix) @ self._model.forward(zero, TCP_FRAME).matrix
        )

    def flange_matrix(self, q: np.ndarray) -> np.ndarray:
        """``T_base_flange`` at the joint vector ``q``."""
        return BASE_LINK_TO_BASE.T @ self._model.forward(q, FLANGE_FRAME).matrix

    def tcp_pose(self, q: np.ndarray, tcp_offset: list[float]) -> list[float]:
        """The TCP pose vector at ``q`` with the TCP offset ``tcp_offset`` (a pose vector of the flange)."""
        return matrix_to_pose(self.flange_matrix(q) @ pose_to_matrix(tcp_offset))

    def elbow_position_m(self, q: np.ndarray) -> list[float]:
        """Where the elbow joint sits in ``base`` (the RTDE field ``elbow_position``)."""
        matrix = BASE_LINK_TO_BASE.T @ self._model.forward(q, "forearm_link").matrix
        return [float(v) for v in matrix[:3, 3]]

    def inverse(self, tcp_pose: list[float], tcp_offset: list[float], seed_q: np.ndarray) -> np.ndarray:
        """A joint vector on ``seed_q``'s branch that puts the TCP at ``tcp_pose``; raises when there is none."""
        flange = pose_to_matrix(tcp_pose) @ np.linalg.inv(pose_to_matrix(tcp_offset))
        urdf_tcp = BASE_LINK_TO_BASE @ flange @ self.flange_to_pads_tcp
        return self._model.inverse(Pose.from_matrix(urdf_tcp), seed_q)

    def within_limits(self, q: np.ndarray) -> bool:
        """True when every joint of ``q`` is a finite number within the description's limits."""
        q = np.asarray(q, dtype=float)
        return bool(
            q.shape == (6,)
            and np.all(np.isfinite(q))
            and np.all(q >= self.lower_rad - 1e-9)
            and np.all(q <= self.upper_rad + 1e-9)
        )
