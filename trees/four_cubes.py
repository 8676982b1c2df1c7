"""The paper's four-colour pattern (a 2 x 2 square, 10 cm apart), corrected cube by cube.

bt-arrange run trees/four_cubes.py
"""

from bt_arrange.trees import Arrangement, Target, arrangement
from bt_arrange_sim.scenes import CubeStart, scatter

TARGETS = [
    Target("red", x_m=0.45, y_m=0.05),
    Target("green", x_m=0.45, y_m=-0.05),
    Target("blue", x_m=0.55, y_m=0.05),
    Target("yellow", x_m=0.55, y_m=-0.05),
]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: each cube picked, placed and corrected before the next one."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes, correct="each")


def create_scene(seed: int = 0) -> list[CubeStart]:
    """Where the cubes start in the simulator: scattered, clear of each other and of the pattern."""
    return scatter([t.colour for t in TARGETS], seed, avoid=TARGETS)
