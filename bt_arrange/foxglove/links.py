"""The robot's links as frame transforms, parent to child, from a URDF and the measured joint positions.

Foxglove's 3-D panel chains the transforms itself and draws each link of the URDF on
``/robot_description`` in its frame, so one transform per joint is all it needs. The URDF is read
with the standard library: the recording observes the run and never loads a kinematic model.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bt_arrange.geometry import FloatArray, matrix_to_quaternion

#: A quaternion (x, y, z, w) as plain floats: cheaper than an array for one product per joint and tick.
Quaternion = tuple[float, ...]


@dataclass(frozen=True)
class Joint:
    """One URDF joint: its frames, its fixed origin and, for a moving one, its axis and type."""

    name: str
    parent: str
    child: str
    kind: str
    origin: FloatArray
    axis: FloatArray


def _origin_matrix(element: ElementTree.Element | None) -> FloatArray:
    matrix = np.eye(4)
    if element is None:
        return matrix
    x, y, z = (float(v) for v in element.get("xyz", "0 0 0").split())
    roll, pitch, yaw = (float(v) for v in element.get("rpy", "0 0 0").split())
    matrix[:3, :3] = _rz(yaw) @ _ry(pitch) @ _rx(roll)  # URDF: fixed-axis roll, then pitch, then yaw
    matrix[:3, 3] = (x, y, z)
    return matrix


def _rx(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class RobotLinks:
    """The joints of a URDF; ``transforms(positions)`` gives each joint's parent-to-child transform."""

    def __init__(self, urdf_path: Path) -> None:
        root = ElementTree.parse(urdf_path).getroot()
        self.joints: list[Joint] = []
        for element in root.iter("joint"):
            parent, child = element.find("parent"), element.find("child")
            if parent is None or child is None:
                continue
            axis_element = element.find("axis")
            axis = np.array(
                [float(v) for v in (axis_element.get("xyz", "1 0 0") if axis_element is not None else "1 0 0").split()]
            )
            norm = float(np.linalg.norm(axis))
            self.joints.append(
                Joint(
                    name=element.get("name", ""),
                    parent=parent.get("link", ""),
                    child=child.get("link", ""),
                    kind=element.get("type", "fixed"),
                    origin=_origin_matrix(element.find("origin")),
                    axis=axis / norm if norm > 0 else np.array([1.0, 0.0, 0.0]),
                )
            )
        children = {joint.child for joint in self.joints}
        parents = [joint.parent for joint in self.joints if joint.parent not in children]
        #: The link no joint moves: the robot's base, placed in the world by the world-to-base transform.
        self.base_link = parents[0] if parents else "base_link"
        # Worked out once: a joint's child frame is its origin, then a turn about (or a slide along) its axis, so
        # each tick needs one quaternion product (or one rotated axis), no matrices.
        self._origins = [
            (t, tuple(float(v) for v in q)) for t, q in map(_as_transform, (j.origin for j in self.joints))
        ]
        self._slides = [joint.origin[:3, :3] @ joint.axis for joint in self.joints]

    def transforms(self, positions: dict[str, float]) -> list[tuple[str, str, FloatArray, Quaternion]]:
        """``(parent, child, translation_m, quaternion_xyzw)`` per joint; a joint not in ``positions`` is at 0."""
        out: list[tuple[str, str, FloatArray, Quaternion]] = []
        for joint, (translation, rotation), slide in zip(self.joints, self._origins, self._slides, strict=True):
            value = positions.get(joint.name, 0.0) if joint.kind != "fixed" else 0.0
            if joint.kind == "fixed" or value == 0.0:
                out.append((joint.parent, joint.child, translation, rotation))
            elif joint.kind == "prismatic":
                out.append((joint.parent, joint.child, translation + slide * value, rotation))
            else:  # revolute or continuous
                half = value / 2
                sin_half = math.sin(half)
                turn = (joint.axis[0] * sin_half, joint.axis[1] * sin_half, joint.axis[2] * sin_half, math.cos(half))
                out.append((joint.parent, joint.child, translation, _multiply(rotation, turn)))
        return out


def _multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """The quaternion product ``a b`` (x, y, z, w): ``b``'s turn in ``a``'s frame."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _as_transform(matrix: FloatArray) -> tuple[FloatArray, FloatArray]:
    return matrix[:3, 3].copy(), matrix_to_quaternion(matrix[:3, :3])
