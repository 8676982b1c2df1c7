"""What every step asks of a part's shape: the :class:`Shape` protocol and the values it answers with.

A shape is a part's geometry in its own frame (origin at the top face's area centroid, z up from
the table): the top-face outline, the height, the yaw symmetry, the grasps a gripper can take on
it, the face a push meets, and the footprint the layout and the plan check use. Perception, Pick,
Place, Push, the layout, the plan check, the injectors and the simulator's body builder ask it;
none of them knows which shape it is. ``docs/architecture.md`` says how a new shape is added.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import FloatArray, fold_yaw, rotation_z
from bt_arrange.shapes.gripper import Gripper

#: The thinnest part the camera and the pads handle (each edge), and the tallest (its height).
MIN_EDGE_M = 0.015
MAX_HEIGHT_M = 0.10


@dataclass(frozen=True)
class Grasp:
    """A grasp the pads can take: they close along ``axis`` of the part's frame.

    ``yaw_offset_rad`` is the gripper's yaw minus the part's (the closing axis lies along the
    gripper's yaw), ``width_m`` the part's width between the pads, ``height_m`` the TCP's (mid-pad)
    height above the table, ``centre_m`` where the pads' centre stands in the part's frame (the
    origin for a cuboid; off it where an irregular part's grasped edges are).
    """

    axis: str
    yaw_offset_rad: float
    width_m: float
    height_m: float
    centre_m: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class PushedFace:
    """The face a push along a heading meets (metres).

    ``width_m`` across the push and ``depth_m`` (the part along it) of the face square to the
    push; ``leading_width_m`` the width of the part's leading edge as the pads see it when the
    part is turned from square to the push (``width cos a - depth sin a``, the face's width when
    square): pads opened wider than that leave its leading corner in the gap between them.
    """

    width_m: float
    depth_m: float
    leading_width_m: float


#: The least opening of the fingers for pushing an irregular part, nearly closed: both pads land on
#: the edge a square push meets (``Prism.named_pushes`` opens them wider where the edge allows).
PRISM_PUSH_OPENING_M = 0.004


@dataclass(frozen=True)
class SquarePush:
    """A push that meets one edge squarely.

    Its ``heading_rad`` in the part's frame (the edge's inward normal), how far behind the centroid
    the edge lies (``back_m``), the edge's length and index, and the fingers' opening.
    """

    heading_rad: float
    back_m: float
    edge_m: float
    edge: int
    #: The fingers' opening for this push (``Prism.named_pushes``).
    opening_m: float = PRISM_PUSH_OPENING_M


class Shape(Protocol):
    """A rigid part standing on the table, as every step of an arrangement sees it (metres, radians)."""

    @property
    def height_m(self) -> float:
        """The top face's height above the table."""
        ...

    @property
    def outline_m(self) -> FloatArray:
        """The top face's outline in the part's frame (N x 2, counter-clockwise)."""
        ...

    @property
    def extent_m(self) -> tuple[float, float]:
        """The top face's size along the part's own x and y axes (its bounding box)."""
        ...

    @property
    def symmetry_rad(self) -> float:
        """The smallest turn that shows the same top face (2 pi for none)."""
        ...

    @property
    def sweep_radius_m(self) -> float:
        """The radius of the circle the top face sweeps as the part turns about its origin."""
        ...

    @property
    def size_m(self) -> tuple[float, float, float]:
        """The part's bounding box in its own frame: ``extent_m`` and the height (a box's edges)."""
        ...

    @property
    def area_m2(self) -> float:
        """The top face's area."""
        ...

    @property
    def rectangular(self) -> bool:
        """The trait of a box: the top face is a rectangle along the part's axes (the faster paths ask it)."""
        ...

    @property
    def square_top(self) -> bool:
        """The trait of a box with a square top face (within 0.5 mm)."""
        ...

    @property
    def is_cube(self) -> bool:
        """The trait of a cube: a square top as tall as it is wide."""
        ...

    def support_m(self, direction: FloatArray) -> float:
        """How far the part reaches from its mid-height centre along a unit ``direction`` of its frame (3-vector)."""
        ...

    def grasps(self, gripper: Gripper) -> tuple[Grasp, ...]:
        """The grasps ``gripper`` can take on the part, the preferred first (none: it cannot hold it)."""
        ...

    def named_pushes(self, gripper: Gripper) -> dict[str, SquarePush]:
        """The pushes that meet one edge squarely, by name (``"@-54.0"``), with the fingers' opening for each."""
        ...

    def back_within_m(self, heading_rad: float, yaw_rad: float, half_span_m: float) -> float:
        """How far back from the origin, along a push, the outline reaches within ``half_span_m`` of its line."""
        ...

    def push_contact_m(self, heading_rad: float, yaw_rad: float) -> tuple[float, float]:
        """The span (low, high) across a push, from the line through the origin, of what the pads meet."""
        ...

    def convex_pieces(self) -> list[FloatArray]:
        """The top face as convex polygons (counter-clockwise): the engines' bodies, the layout's footprints."""
        ...

    def pushed_face(self, heading_rad: float, yaw_rad: float) -> PushedFace:
        """The face a push along ``heading_rad`` meets on the part turned to ``yaw_rad``."""
        ...

    def problems(self, gripper: Gripper) -> list[str]:
        """What makes the part one the camera or ``gripper`` cannot handle (empty: none)."""
        ...

    def size_problems(self) -> list[str]:
        """The part's own problems, those that need no gripper (too thin, too tall, an edge too short)."""
        ...

    def describe(self) -> str:
        """The shape in a few words, in millimetres (``80 x 40 x 40 mm``)."""
        ...


def footprint_m(shape: Shape | _Outline, x_m: float, y_m: float, yaw_rad: float) -> FloatArray:
    """The top face's outline (N x 2) on the table with the part's origin at ``(x, y)`` turned by ``yaw_rad``."""
    outline = np.column_stack([shape.outline_m, np.zeros(len(shape.outline_m))])
    return (rotation_z(yaw_rad) @ outline.T).T[:, :2] + np.array([x_m, y_m])


def grown(shape: Shape, margin_m: float) -> _Outline:
    """The shape's top face grown by ``margin_m`` all round (each edge moved out along its normal)."""
    outline = np.asarray(shape.outline_m, dtype=float)
    before = outline - np.roll(outline, 1, axis=0)
    after = np.roll(outline, -1, axis=0) - outline
    # Outward normals of the edges into and out of each corner (counter-clockwise: right of travel).
    n_in = np.column_stack([before[:, 1], -before[:, 0]]) / np.linalg.norm(before, axis=1)[:, None]
    n_out = np.column_stack([after[:, 1], -after[:, 0]]) / np.linalg.norm(after, axis=1)[:, None]
    miter = (n_in + n_out) / (1.0 + np.sum(n_in * n_out, axis=1))[:, None]
    return _Outline(outline + margin_m * miter, shape.height_m)


@dataclass(frozen=True)
class _Outline:
    """A bare top face at a height: what ``grown`` returns, enough for ``footprint_m``."""

    outline_m: FloatArray
    height_m: float


def folded_yaw(shape: Shape, yaw_rad: float) -> float:
    """A yaw folded to the shape's symmetry: ``[-45, 45)`` degrees for a square top, ``[-90, 90)`` for a rectangle."""
    return fold_yaw(yaw_rad, shape.symmetry_rad)


def yaw_error_rad(shape: Shape, measured_yaw_rad: float, target_yaw_rad: float) -> float:
    """Measured minus target yaw, folded to the shape's symmetry (signed)."""
    return fold_yaw(measured_yaw_rad - target_yaw_rad, shape.symmetry_rad)


def preferred_grasp(shape: Shape, gripper: Gripper) -> Grasp:
    """The shape's first grasp; a shape without one never passes the plan check, so this is a bug."""
    grasps = shape.grasps(gripper)
    if not grasps:
        raise BtArrangeError(f"no grasp for {shape.describe()}: the plan check should have refused it")
    return grasps[0]


def min_centre_distance_m(first: Shape, second: Shape) -> float:
    """Centres of two parts closer than this may overlap at some yaw (the sum of their sweep radii)."""
    return first.sweep_radius_m + second.sweep_radius_m


__all__ = [
    "MAX_HEIGHT_M",
    "MIN_EDGE_M",
    "Grasp",
    "PRISM_PUSH_OPENING_M",
    "PushedFace",
    "SquarePush",
    "Shape",
    "folded_yaw",
    "footprint_m",
    "min_centre_distance_m",
    "preferred_grasp",
    "yaw_error_rad",
]
