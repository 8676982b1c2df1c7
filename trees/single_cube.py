"""One red cube: detect, pick, place, inspect, push until within the threshold (Algorithm 1).

bt-arrange run trees/single_cube.py
"""

from bt_arrange import backends
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, Target, arrangement

TARGETS = [Target("red", x_m=0.50, y_m=0.0, yaw_rad=0.0)]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: one cube to its target, corrected to ``threshold_mm``."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes)


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cube starts in the simulator: a random pose clear of the target."""
    return (backend or backends.load()).scatter([t.colour for t in TARGETS], seed, avoid=TARGETS)
