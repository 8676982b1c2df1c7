"""The four-colour pattern placed first and corrected afterwards, as in the paper's Fig. 5.

bt-arrange run trees/four_cubes_after_all.py --record runs/fig5
"""

from four_cubes import TARGETS  # the same pattern  # noqa: I001

from bt_arrange import backends
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, arrangement


def create_root(threshold_mm: float = 1.0, max_pushes: int = 10) -> Arrangement:
    """The tree: place all four cubes, then correct each."""
    return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=max_pushes, correct="after_all")


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start in the simulator."""
    return (backend or backends.load()).scatter([t.colour for t in TARGETS], seed, avoid=TARGETS)
