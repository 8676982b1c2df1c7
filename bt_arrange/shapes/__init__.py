"""The home of part geometry and of the gripper's figures.

A :class:`Shape` answers what every step asks of a part (outline, height, symmetry, grasps,
pushes, pushed face, convex pieces, footprint). The polygonal :class:`Prism` is the one shape:
a box (the paper's cube) is the prism :class:`Cuboid`, made by :meth:`Prism.box`, which declares
the trait ``rectangular`` for the steps that keep a faster path for boxes. A :class:`Gripper` holds the
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
from bt_arrange.shapes.gripper import ROBOTIQ_2F85, Gripper
from bt_arrange.shapes.polygon import outline_problem
from bt_arrange.shapes.prism import Cuboid, Prism, SquarePush, told_apart

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
    "SquarePush",
    "folded_yaw",
    "footprint_m",
    "grown",
    "min_centre_distance_m",
    "outline_problem",
    "told_apart",
    "preferred_grasp",
    "yaw_error_rad",
]
