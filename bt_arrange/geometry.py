"""Pose value classes: a full SE(3) pose, and the planar (x, y, yaw) a table-top user thinks in.

Conventions: metres and radians; quaternions are ``(x, y, z, w)`` like pybullet and scipy;
a ``Pose`` called ``T_a_b`` is the pose of frame ``b`` expressed in frame ``a``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bt_arrange.errors import GeometryError

FloatArray = NDArray[np.float64]


def wrap_angle(angle_rad: float) -> float:
    """Wrap an angle to ``[-pi, pi)``."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def fold_yaw(yaw_rad: float, symmetry_rad: float = math.pi / 2) -> float:
    """Fold a yaw into ``[-symmetry/2, symmetry/2)``: a cube looks the same every 90 degrees."""
    return (yaw_rad + symmetry_rad / 2) % symmetry_rad - symmetry_rad / 2


def quaternion_to_matrix(quaternion_xyzw: ArrayLike) -> FloatArray:
    """Rotation matrix of a unit quaternion ``(x, y, z, w)``."""
    x, y, z, w = np.asarray(quaternion_xyzw, dtype=float) / np.linalg.norm(quaternion_xyzw)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quaternion(rotation: ArrayLike) -> FloatArray:
    """Unit quaternion ``(x, y, z, w)`` of a rotation matrix, with ``w >= 0``."""
    r = np.asarray(rotation, dtype=float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s]
    quaternion = np.asarray(q) / np.linalg.norm(q)
    return quaternion if quaternion[3] >= 0 else -quaternion


def rotation_z(angle_rad: float) -> FloatArray:
    """Rotation matrix about z."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class PlanarPose:
    """A pose on the table: ``x_m``, ``y_m`` in metres, ``yaw_rad`` about the world z axis."""

    x_m: float
    y_m: float
    yaw_rad: float = 0.0

    def distance_to(self, other: PlanarPose) -> float:
        """Planar Euclidean distance in metres (the paper's offset metric, Δd_xy)."""
        return math.hypot(self.x_m - other.x_m, self.y_m - other.y_m)


@dataclass(frozen=True)
class Pose:
    """A rigid transform in SE(3): ``position_m`` (3,) and ``quaternion_xyzw`` (4,)."""

    position_m: FloatArray = field(default_factory=lambda: np.zeros(3))
    quaternion_xyzw: FloatArray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 1.0]))

    def __post_init__(self) -> None:
        position = np.asarray(self.position_m, dtype=float).reshape(3)
        quaternion = np.asarray(self.quaternion_xyzw, dtype=float).reshape(4)
        norm = np.linalg.norm(quaternion)
        if not np.isfinite(position).all() or not np.isfinite(norm) or norm < 1e-9:
            raise GeometryError(
                f"invalid pose: position {position}, quaternion {quaternion}",
                field="pose",
                value=(position, quaternion),
            )
        object.__setattr__(self, "position_m", position)
        object.__setattr__(self, "quaternion_xyzw", quaternion / norm)

    @classmethod
    def from_matrix(cls, matrix: ArrayLike) -> Pose:
        """Pose of a 4x4 homogeneous transform."""
        m = np.asarray(matrix, dtype=float)
        return cls(m[:3, 3].copy(), matrix_to_quaternion(m[:3, :3]))

    @classmethod
    def from_rotation(cls, position_m: ArrayLike, rotation: ArrayLike) -> Pose:
        """Pose of a position and a 3x3 rotation matrix."""
        return cls(np.asarray(position_m, dtype=float), matrix_to_quaternion(rotation))

    @classmethod
    def from_planar(cls, x_m: float, y_m: float, yaw_rad: float = 0.0, z_m: float = 0.0) -> Pose:
        """Pose at height ``z_m`` turned by ``yaw_rad`` about the world z axis."""
        return cls.from_rotation([x_m, y_m, z_m], rotation_z(yaw_rad))

    @property
    def rotation(self) -> FloatArray:
        """3x3 rotation matrix."""
        return quaternion_to_matrix(self.quaternion_xyzw)

    @property
    def matrix(self) -> FloatArray:
        """4x4 homogeneous transform."""
        m = np.eye(4)
        m[:3, :3] = self.rotation
        m[:3, 3] = self.position_m
        return m

    @property
    def x_m(self) -> float:
        """Position along world x in metres."""
        return float(self.position_m[0])

    @property
    def y_m(self) -> float:
        """Position along world y in metres."""
        return float(self.position_m[1])

    @property
    def z_m(self) -> float:
        """Position along world z in metres."""
        return float(self.position_m[2])

    @property
    def yaw_rad(self) -> float:
        """Heading of the frame's x axis projected on the table, about world z."""
        r = self.rotation
        return math.atan2(r[1, 0], r[0, 0])

    def planar(self) -> PlanarPose:
        """The table-top view of this pose: x, y and yaw."""
        return PlanarPose(self.x_m, self.y_m, self.yaw_rad)

    def __matmul__(self, other: Pose) -> Pose:
        """Compose: ``T_a_c = T_a_b @ T_b_c``."""
        return Pose.from_matrix(self.matrix @ other.matrix)

    def inverse(self) -> Pose:
        """The inverse transform."""
        r = self.rotation
        return Pose.from_rotation(-r.T @ self.position_m, r.T)

    def transform_point(self, point: ArrayLike) -> FloatArray:
        """Map a point from this pose's frame into its parent frame."""
        return self.rotation @ np.asarray(point, dtype=float) + self.position_m

    def __repr__(self) -> str:
        x, y, z = self.position_m
        return f"Pose(x={x:.4f} m, y={y:.4f} m, z={z:.4f} m, yaw={math.degrees(self.yaw_rad):.2f} deg)"
