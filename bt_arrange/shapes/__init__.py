"""The home of part geometry and of the gripper's figures.

A :class:`Shape` answers what every step asks of a part (outline, height, symmetry, grasps,
pushed face, footprint); :class:`Cuboid` is the one shape today. A :class:`Gripper` holds the
stroke, the pads and the clearances (:data:`ROBOTIQ_2F85`, the paper's).
"""

from bt_arrange.shapes.base import (
    MAX_HEIGHT_M,
    MIN_EDGE_M,
    Grasp,
    PushedFace,
    Shape,
    folded_yaw,
    footprint_m,
    grown,
    min_centre_distance_m,
    preferred_grasp,
    yaw_error_rad,
)
from bt_arrange.shapes.cuboid import Cuboid
from bt_arrange.shapes.gripper import ROBOTIQ_2F85, Gripper
from bt_arrange.shapes.prism import Prism, outline_problem, told_apart

__all__ = [
    "MAX_HEIGHT_M",
    "MIN_EDGE_M",
    "ROBOTIQ_2F85",
    "Cuboid",
    "Grasp",
    "Gripper",
    "Prism",
    "PushedFace",
    "Shape",
    "folded_yaw",
    "footprint_m",
    "grown",
    "min_centre_distance_m",
    "outline_problem",
    "told_apart",
    "preferred_grasp",
    "yaw_error_rad",
]
