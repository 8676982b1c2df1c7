"""Where cubes start in the cell: scattered at random, clear of each other and of the targets."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from bt_arrange.checks import whole_number
from bt_arrange.errors import PlanError
from bt_arrange.plancheck import CameraView
from bt_arrange.settings import CUBE_EDGE_M


@dataclass(frozen=True)
class CubeStart:
    """A cube's starting pose on the table."""

    colour: str
    x_m: float
    y_m: float
    yaw_rad: float
    name: str | None = None


#: Cubes start inside the UR5's comfortable reach, and inside the top camera's view with the plan
#: check's margin at any yaw (``CameraView.sees_face_at_any_yaw``, which trims these ranges' corners).
X_RANGE_M = (0.30, 0.68)
Y_RANGE_M = (-0.38, 0.38)
MAX_RADIUS_M = 0.74
#: Centre distance kept from other cubes and from targets: the open gripper (75 mm plus two
#: 8 mm pads) must come down beside a cube without touching a neighbour.
CLEARANCE_M = 0.12


def scatter(
    colours: Sequence[str],
    seed: int,
    avoid: Iterable[object] = (),
    max_tries: int = 10_000,
    view: CameraView | None = None,
) -> list[CubeStart]:
    """Random starting poses for cubes of ``colours``, reproducible from ``seed`` (a whole number, 0 or more).

    ``avoid`` holds things with ``x_m`` and ``y_m`` (targets) that the cubes keep clear of; ``view``
    is the camera's view every cube must be seen in (default: the default cell's camera).
    """
    whole_number("seed", seed, style="unit")
    if view is None:
        from bt_arrange_sim.cell import CameraConfig

        view = CameraConfig().view()
    rng = np.random.default_rng(seed)
    taken = [(float(a.x_m), float(a.y_m)) for a in avoid]  # type: ignore[attr-defined]
    starts: list[CubeStart] = []
    for colour in colours:
        for _ in range(max_tries):
            x, y = rng.uniform(*X_RANGE_M), rng.uniform(*Y_RANGE_M)
            if (
                math.hypot(x, y) <= MAX_RADIUS_M
                and all(math.hypot(x - u, y - v) >= CLEARANCE_M for u, v in taken)
                and view.sees_face_at_any_yaw(x, y, CUBE_EDGE_M)
            ):
                break
        else:
            raise PlanError(f"no room left on the table for a {colour} cube after {max_tries} tries")
        taken.append((x, y))
        starts.append(CubeStart(colour, x, y, float(rng.uniform(-math.pi, math.pi))))
    return starts
