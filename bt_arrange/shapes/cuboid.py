"""The cuboid: a box of ``size_m = (x, y, z)`` standing on its z face (the paper's 5 cm cube is one)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_arrange.geometry import FloatArray, fold_yaw
from bt_arrange.shapes.base import MAX_HEIGHT_M, MIN_EDGE_M, Grasp, PushedFace
from bt_arrange.shapes.gripper import Gripper

#: Two edges closer than this (metres) make a square top.
SQUARE_TOLERANCE_M = 0.0005


@dataclass(frozen=True)
class Cuboid:
    """A box: ``x`` and ``y`` across its top face, ``z`` its height on the table (metres).

    Its frame is the box's centre, axes along its edges. The pads close across the narrower side
    of the top face (either side of a square top), through the centre of mass where the pads
    allow; a push meets the face square to its heading.
    """

    size_m: tuple[float, float, float]

    @property
    def height_m(self) -> float:
        """The top face's height above the table."""
        return self.size_m[2]

    @property
    def extent_m(self) -> tuple[float, float]:
        """The top face's edges (x, y)."""
        return self.size_m[0], self.size_m[1]

    @property
    def outline_m(self) -> FloatArray:
        """The top face's four corners, counter-clockwise from (-x/2, -y/2)."""
        hx, hy = self.size_m[0] / 2, self.size_m[1] / 2
        return np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])

    @property
    def square_top(self) -> bool:
        """True when the top face is a square (within 0.5 mm)."""
        return abs(self.size_m[0] - self.size_m[1]) < SQUARE_TOLERANCE_M

    @property
    def is_cube(self) -> bool:
        """True for a cube: a square top as tall as it is wide (within 0.5 mm)."""
        return self.square_top and abs(self.size_m[0] - self.size_m[2]) < SQUARE_TOLERANCE_M

    @property
    def symmetry_rad(self) -> float:
        """90 degrees for a square top, 180 otherwise."""
        return math.pi / 2 if self.square_top else math.pi

    @property
    def sweep_radius_m(self) -> float:
        """Half the top face's diagonal."""
        return 0.5 * math.hypot(self.size_m[0], self.size_m[1])

    def support_m(self, direction: FloatArray) -> float:
        """How far the box reaches from its centre along a unit ``direction`` of its own frame (3-vector)."""
        half = [v / 2 for v in self.size_m]
        along = np.abs(np.asarray(direction, dtype=float))
        if half[0] == half[1] == half[2]:
            # A cube's in one product, the arithmetic the injectors were measured with.
            return half[0] * float(np.sum(along))
        return float(along @ np.array(half))

    def grasps(self, gripper: Gripper) -> tuple[Grasp, ...]:
        """Across the narrower side (``x`` first when they are equal), and across the other too on a square top.

        None when the narrower side is wider than the gripper closes across.
        """
        x_m, y_m, z_m = self.size_m
        height_m = max(z_m / 2, gripper.lowest_tcp_m)
        across_x = Grasp("x", 0.0, x_m, height_m)
        across_y = Grasp("y", math.pi / 2, y_m, height_m)
        preferred, other = (across_x, across_y) if x_m <= y_m else (across_y, across_x)
        if preferred.width_m > gripper.max_grasp_width_m:
            return ()
        return (preferred, other) if self.square_top else (preferred,)

    def pushed_face(self, heading_rad: float, yaw_rad: float) -> PushedFace:
        """The face square to the push, and its leading width at the part's turn from square."""
        relative = fold_yaw(heading_rad - yaw_rad, math.pi)
        along_x = abs(math.cos(relative)) >= abs(math.sin(relative))
        # Pushing along the part's x axis meets the face that spans its y edge.
        width_m, depth_m = (self.size_m[1], self.size_m[0]) if along_x else (self.size_m[0], self.size_m[1])
        turn_rad = abs(fold_yaw(heading_rad - yaw_rad, math.pi / 2))
        return PushedFace(width_m, depth_m, width_m * math.cos(turn_rad) - depth_m * math.sin(turn_rad))

    def problems(self, gripper: Gripper) -> list[str]:
        """An edge not positive or under 15 mm, taller than 100 mm, no side the gripper spans."""
        size = self.describe()
        if min(self.size_m) <= 0:
            return [f"size {size} has an edge that is not positive"]
        found = []
        if min(self.size_m) < MIN_EDGE_M:
            found.append(
                f"size {size} has an edge under {MIN_EDGE_M * 1000:.0f} mm, too thin for the pads and the camera"
            )
        if self.size_m[2] > MAX_HEIGHT_M:
            found.append(f"{self.size_m[2] * 1000:g} mm tall, taller than {MAX_HEIGHT_M * 1000:.0f} mm")
        if not self.grasps(gripper):
            found.append(
                f"size {size} has no horizontal side the gripper can span (the {gripper.name.split()[-1]} closes "
                f"across at most {gripper.max_grasp_width_m * 1000:.0f} mm: its {gripper.stroke_m * 1000:.0f} mm "
                f"stroke less {gripper.grasp_clearance_m * 1000:.0f} mm of clearance)"
            )
        return found

    def describe(self) -> str:
        """The size in millimetres, e.g. ``80 x 40 x 40 mm``."""
        return " x ".join(f"{v * 1000:g}" for v in self.size_m) + " mm"
