"""A dense row: four cubes of distinct colours with 2 mm gaps along x.

bt-arrange run trees/dense_row.py

Each cube after the first is released at its target with the pads across its free y faces (a
pad never enters a 2 mm gap), pushed only from free sides, and the cube before it is looked at
again once it is down. The same row of five identical cubes: trees/dense_row_identical.py.
"""

from bt_arrange import backends
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, Target, arrangement

#: Gap between neighbouring faces, metres.
GAP_M = 0.002
PITCH_M = 0.05 + GAP_M

TARGETS = [
    Target(colour, x_m=0.42 + i * PITCH_M, y_m=0.0) for i, colour in enumerate(("red", "green", "blue", "yellow"))
]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: cube by cube along the row, each neighbour checked after the next is down."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes, correct="each")


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start: scattered, clear of each other and of the row."""
    return (backend or backends.load()).scatter([t.colour for t in TARGETS], seed, avoid=TARGETS)
