"""A part as the layout sees it: its target, its shape and the gripper holding it, asked what the pads need.

Planar, in metres and radians, in the part's own frame. ``bt_arrange.plan.layout`` plans with it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from bt_arrange.plan.footprints import Footprint, Outline, Rect
from bt_arrange.shapes.base import Shape, SquarePush
from bt_arrange.shapes.gripper import ROBOTIQ_2F85, Gripper

#: Directions a part can be pushed towards, in its target's frame.
DIRECTIONS: dict[str, tuple[float, float]] = {"+x": (1.0, 0.0), "-x": (-1.0, 0.0), "+y": (0.0, 1.0), "-y": (0.0, -1.0)}


def pushed_from(towards: str) -> str | None:
    """The side the pads stand on for a push ``towards`` (``"+y"`` -> ``"-y"``); None for a square push."""
    if towards not in DIRECTIONS:
        return None
    return ("-" if towards[0] == "+" else "+") + towards[1]


@dataclass(frozen=True)
class Part:
    """One part at its target: ``name``, target ``(x_m, y_m, yaw_rad)``, its ``shape`` and the ``gripper`` holding it.

    Everything the layout needs it asks the shape (``bt_arrange.shapes.Shape``). A box, and a part
    no grasp holds across its own x or y axis, is modelled by its rectangle (``extent_m``) and
    pushed towards its target frame's four directions; any other part by its outline's convex
    pieces, its preferred grasp and its square pushes (``Shape.named_pushes``), by name.
    """

    name: str
    x_m: float
    y_m: float
    yaw_rad: float
    shape: Shape
    gripper: Gripper = ROBOTIQ_2F85

    @property
    def size_x_m(self) -> float:
        """Its footprint's size along its own x axis."""
        return float(self.shape.extent_m[0])

    @property
    def size_y_m(self) -> float:
        """Its footprint's size along its own y axis."""
        return float(self.shape.extent_m[1])

    @functools.cached_property
    def by_outline(self) -> bool:
        """True when it is modelled by its outline: no box, and its preferred grasp closes across its x or y axis.

        The layout models the pads beside a part's x or y faces only; a part held otherwise keeps
        its rectangle (and is arranged only with room around it: ``arrange_one`` refuses it among
        neighbours).
        """
        if self.shape.rectangular:
            return False
        grasps = self.shape.grasps(self.gripper)
        return bool(grasps) and grasps[0].axis in ("x", "y")

    @functools.cached_property
    def grasp_axes(self) -> tuple[str, ...]:
        """The axes of its frame the pads may close across (a bar only across the side the stroke spans).

        A part modelled by its outline is released across its preferred grasp only: it is picked
        by it. A part with no grasp along x or y is given both, which serve its spacing checks.
        """
        grasps = self.shape.grasps(self.gripper)
        if self.by_outline:
            return (grasps[0].axis,)
        return tuple(grasp.axis for grasp in grasps if grasp.axis in ("x", "y")) or ("x", "y")

    @functools.cached_property
    def _square_pushes(self) -> dict[str, SquarePush]:
        return self.shape.named_pushes(self.gripper) if self.by_outline else {}

    @functools.cached_property
    def footprint(self) -> Footprint:
        """The part at its target (kept: the layout search asks for it at every step it tries)."""
        if self.by_outline:
            pieces = tuple(tuple((float(x), float(y)) for x, y in piece) for piece in self.shape.convex_pieces())
            return Outline(self.x_m, self.y_m, self.yaw_rad, pieces)
        return Rect(self.x_m, self.y_m, self.yaw_rad, self.size_x_m / 2, self.size_y_m / 2)

    def half(self, axis: str) -> float:
        """Half its size along its own ``axis``."""
        return (self.size_x_m if axis == "x" else self.size_y_m) / 2

    def grasp_half(self, axis: str) -> float:
        """Half the width between the pads closed across ``axis``."""
        return self.shape.grasps(self.gripper)[0].width_m / 2 if self.by_outline else self.half(axis)

    def grasp_centre(self, axis: str) -> tuple[float, float]:
        """Where the pads' centre stands, closed across ``axis`` (own frame; the origin for a box)."""
        return self.shape.grasps(self.gripper)[0].centre_m if self.by_outline else (0.0, 0.0)

    @property
    def push_directions(self) -> tuple[str, ...]:
        """The directions it may be pushed towards: its target frame's four, or its square pushes."""
        return tuple(self._square_pushes) if self.by_outline else tuple(DIRECTIONS)

    def push_vector(self, towards: str) -> tuple[float, float]:
        """The unit vector (own frame) of a push ``towards``."""
        if not self.by_outline:
            return DIRECTIONS[towards]
        heading_rad = self._square_pushes[towards].heading_rad
        return math.cos(heading_rad), math.sin(heading_rad)

    def back(self, towards: str) -> float:
        """How far behind its origin the pads pushing it ``towards`` meet it (half its size for a box)."""
        return self._square_pushes[towards].back_m if self.by_outline else self.half(towards[1])

    def push_heading_rad(self, towards: str) -> float:
        """The heading (own frame) of the square push ``towards``."""
        return self._square_pushes[towards].heading_rad

    def push_opening(self, towards: str) -> float:
        """The fingers' opening for the square push ``towards``."""
        return self._square_pushes[towards].opening_m

    @property
    def push_opening_m(self) -> float:
        """The narrowest opening of its square pushes (what a push that has no name of its own uses)."""
        return min((push.opening_m for push in self._square_pushes.values()), default=0.0)
