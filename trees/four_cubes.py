"""The paper's four-colour pattern (a 2 x 2 square, 10 cm apart), corrected cube by cube.

bt-arrange run trees/four_cubes.py
"""

from bt_arrange import backends
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, Target, arrangement

TARGETS = [
    Target("red", x_m=0.45, y_m=0.05),
    Target("green", x_m=0.45, y_m=-0.05),
    Target("blue", x_m=0.55, y_m=0.05),
    Target("yellow", x_m=0.55, y_m=-0.05),
]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: each cube picked, placed and corrected before the next one."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes, correct="each")


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start: scattered by the run's backend, clear of each other and of the pattern."""
    return (backend or backends.load()).scatter([t.colour for t in TARGETS], seed, avoid=TARGETS)
