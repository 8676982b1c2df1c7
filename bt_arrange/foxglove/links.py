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


def _axis_angle(axis: FloatArray, angle_rad: float) -> FloatArray:
    x, y, z = axis
    c, s, t = math.cos(angle_rad), math.sin(angle_rad), 1.0 - math.cos(angle_rad)
    return np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    )


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
        # A fixed joint's transform never changes: worked out once.
        self._fixed = {j.name: _as_transform(j.origin) for j in self.joints if j.kind == "fixed"}

    def transforms(self, positions: dict[str, float]) -> list[tuple[str, str, FloatArray, FloatArray]]:
        """``(parent, child, translation_m, quaternion_xyzw)`` per joint; a joint not in ``positions`` is at 0."""
        out = []
        for joint in self.joints:
            fixed = self._fixed.get(joint.name)
            if fixed is not None:
                out.append((joint.parent, joint.child, *fixed))
                continue
            value = positions.get(joint.name, 0.0)
            motion = np.eye(4)
            if joint.kind == "prismatic":
                motion[:3, 3] = joint.axis * value
            else:  # revolute or continuous
                motion[:3, :3] = _axis_angle(joint.axis, value)
            out.append((joint.parent, joint.child, *_as_transform(joint.origin @ motion)))
        return out


def _as_transform(matrix: FloatArray) -> tuple[FloatArray, FloatArray]:
    return matrix[:3, 3].copy(), matrix_to_quaternion(matrix[:3, :3])
