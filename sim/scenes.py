"""Where parts start in the cell: scattered at random, clear of each other and of the targets."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from bt_arrange.checks import whole_number
from bt_arrange.deprecation import renamed_attributes
from bt_arrange.errors import PlanError
from bt_arrange.objects import CUBE, ObjectStart, ObjectType, object_type_of
from bt_arrange.plan.camera_view import CameraView

#: A part's starting pose on the table (``bt_arrange.objects.ObjectStart``: colour, x, y, yaw, name, type).
PartStart = ObjectStart

if TYPE_CHECKING:
    CubeStart = PartStart
else:
    # ``CubeStart`` said cube for any part: a deprecated alias, warned once, for one release.
    __getattr__ = renamed_attributes(__name__, {"CubeStart": "PartStart"})


#: Cubes start inside the UR5's comfortable reach, and inside the top camera's view with the plan
#: check's margin at any yaw (``CameraView.sees_face_at_any_yaw``, which trims these ranges' corners).
X_RANGE_M = (0.30, 0.68)
Y_RANGE_M = (-0.38, 0.38)
MAX_RADIUS_M = 0.74
#: Centre distance kept from other cubes and from targets: the open gripper (75 mm plus two
#: 8 mm pads) must come down beside a cube without touching a neighbour.
CLEARANCE_M = 0.12
#: Beyond two parts' half diagonals, the room kept between them (the cubes' 120 mm less two 35 mm).
CLEARANCE_GAP_M = CLEARANCE_M - 2 * CUBE.shape.sweep_radius_m


def clearance_m(first: ObjectType, second: ObjectType) -> float:
    """Centre distance kept between two parts (120 mm for cubes)."""
    return max(CLEARANCE_M, first.shape.sweep_radius_m + second.shape.sweep_radius_m + CLEARANCE_GAP_M)


def scatter(
    colours: Sequence[str],
    seed: int,
    avoid: Iterable[object] = (),
    max_tries: int = 10_000,
    view: CameraView | None = None,
    object_types: Sequence[ObjectType] | None = None,
    names: Sequence[str | None] | None = None,
) -> list[PartStart]:
    """Random starting poses for parts of ``colours``, reproducible from ``seed`` (a whole number, 0 or more).

    ``avoid`` holds things with ``x_m`` and ``y_m`` (targets) that the parts keep clear of; ``view``
    is the camera's view every part must be seen in (default: the default cell's camera).
    ``object_types`` and ``names`` (one per colour) give each part its type (default the cube)
    and name (default its colour).
    """
    whole_number("seed", seed, style="unit")
    if view is None:
        from bt_arrange_sim.config import CameraConfig

        view = CameraConfig().view()
    rng = np.random.default_rng(seed)
    kinds = list(object_types) if object_types is not None else [CUBE] * len(colours)
    labels = list(names) if names is not None else [None] * len(colours)
    if len(kinds) != len(colours) or len(labels) != len(colours):
        raise PlanError(f"scatter: {len(colours)} colours, {len(kinds)} object types and {len(labels)} names")
    taken = [(float(a.x_m), float(a.y_m), object_type_of(a)) for a in avoid]  # type: ignore[attr-defined]
    starts: list[PartStart] = []
    for colour, kind, label in zip(colours, kinds, labels, strict=True):
        # The top face grown by the view's margin, at any yaw (1 mm spare for the rim's sampling).
        x_m, y_m = kind.shape.extent_m
        radius_m = 0.5 * math.hypot(x_m + 2 * view.margin_m, y_m + 2 * view.margin_m) + 0.001
        for _ in range(max_tries):
            x, y = rng.uniform(*X_RANGE_M), rng.uniform(*Y_RANGE_M)
            if (
                math.hypot(x, y) <= MAX_RADIUS_M
                and all(math.hypot(x - u, y - v) >= clearance_m(kind, other) for u, v, other in taken)
                and view.sees_disc(x, y, radius_m, kind.shape.height_m)
            ):
                break
        else:
            what = kind.name
            raise PlanError(f"no room left on the table for a {colour} {what} after {max_tries} tries")
        taken.append((x, y, kind))
        starts.append(PartStart(colour, x, y, float(rng.uniform(-math.pi, math.pi)), label, kind))
    return starts
