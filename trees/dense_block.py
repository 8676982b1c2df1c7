"""A dense 2 x 2 block: four cubes with 3 mm gaps, placed among their neighbours.

bt-arrange run trees/dense_block.py

The layout (``bt_arrange.plan.layout``) chooses where the pads go: the second and third cubes are
released at their targets with the pads across their free faces, the last one, boxed in on two
sides, is released 10 mm away where the pads fit and pushed home from a free side. After each cube
its placed neighbours are looked at again and corrected if it moved them beyond the threshold.
"""

from bt_arrange import backends
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, Target, arrangement

#: Gap between neighbouring faces, metres.
GAP_M = 0.003
PITCH_M = 0.05 + GAP_M

TARGETS = [
    Target("red", x_m=0.45, y_m=0.0),
    Target("green", x_m=0.45 + PITCH_M, y_m=0.0),
    Target("blue", x_m=0.45, y_m=PITCH_M),
    Target("yellow", x_m=0.45 + PITCH_M, y_m=PITCH_M),
]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: each cube placed among the ones before it, then its neighbours checked."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes, correct="each")


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start: scattered, clear of each other and of the block."""
    return (backend or backends.load()).scatter([t.colour for t in TARGETS], seed, avoid=TARGETS)
