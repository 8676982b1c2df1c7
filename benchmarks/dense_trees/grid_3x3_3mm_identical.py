"""A 3 x 3 grid of nine identical green cubes with 3 mm gaps (the grid target).

python benchmarks/dense.py benchmarks/dense_trees/grid_3x3_3mm_identical.py --seeds 0

The camera tells the nine apart by where they lie (Detect picks one not at a target of its kind,
Inspect follows the one nearest its target); the layout chooses the order and where the pads go.
"""

from bt_arrange import backends
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, Target, arrangement

#: No XML twin: the XML node models do not hold where the pads go among neighbours yet.
XML_TWIN = False

GAP_M = 0.003
PITCH_M = 0.05 + GAP_M

TARGETS = [
    Target("green", x_m=0.42 + i * PITCH_M, y_m=(j - 1) * PITCH_M, name=f"green {3 * j + i + 1}")
    for j in range(3)
    for i in range(3)
]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: the layout's order, each cube's neighbours checked after it is down."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes, correct="each")


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start: scattered, clear of each other and of the grid."""
    return (backend or backends.load()).scatter(
        [t.colour for t in TARGETS], seed, avoid=TARGETS, names=[t.obj for t in TARGETS]
    )
