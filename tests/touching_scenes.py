"""Scenes whose parts start touching: plans with their starts set against each other.

Each scene is a plan file's text whose ``[[scene.starts]]`` put parts side by side; ``touching``
slides a start along the line to another until their footprints are a tenth of a millimetre apart
(below the camera's half-millimetre pixel: one blob in its mask). Shared by the integration test
(``integration/test_touching_cell.py``) and ``benchmarks/touching.py``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from bt_arrange import treefile
from bt_arrange.objects import ObjectStart
from bt_arrange.plan import stacking
from bt_arrange.plan.footprints import gap_m
from bt_arrange.plan.targets import Target
from bt_arrange.settings import ManipulationSettings

#: The gap (m) left between two starts set touching: sub-pixel, so the camera sees one blob.
TOUCHING_GAP_M = 0.0001

TWO_CUBES = """
threshold_mm = 1.0
[[targets]]
colour = "red"
x_mm = 450
y_mm = 150
[[targets]]
colour = "red"
x_mm = 450
y_mm = 250
[[targets]]
colour = "blue"
x_mm = 560
y_mm = 150
[[scene.starts]]
colour = "red"
x_mm = 450
y_mm = -150
[[scene.starts]]
colour = "red"
x_mm = 500
y_mm = -150
[[scene.starts]]
colour = "blue"
x_mm = 560
y_mm = -150
"""

THREE_CUBES_IN_A_ROW = """
threshold_mm = 1.0
[[targets]]
colour = "red"
x_mm = 400
y_mm = 150
[[targets]]
colour = "red"
x_mm = 500
y_mm = 150
[[targets]]
colour = "red"
x_mm = 600
y_mm = 150
[[scene.starts]]
colour = "red"
x_mm = 420
y_mm = -170
yaw_deg = 20
[[scene.starts]]
colour = "red"
x_mm = 467
y_mm = -153
yaw_deg = 20
[[scene.starts]]
colour = "red"
x_mm = 514
y_mm = -136
yaw_deg = 20
"""

TWO_BARS = """
threshold_mm = 1.0
[objects.bar]
size_mm = [80, 40, 40]
[colours.orange]
rgb = [1.0, 0.5, 0.0]
[[targets]]
object = "bar"
colour = "orange"
x_mm = 450
y_mm = 150
[[targets]]
object = "bar"
colour = "orange"
x_mm = 450
y_mm = 250
[[scene.starts]]
object = "bar"
colour = "orange"
x_mm = 500
y_mm = -150
yaw_deg = 90
[[scene.starts]]
object = "bar"
colour = "orange"
x_mm = 540
y_mm = -150
yaw_deg = 90
"""

RED_AND_BLUE = """
threshold_mm = 1.0
[[targets]]
colour = "red"
x_mm = 450
y_mm = 150
[[targets]]
colour = "blue"
x_mm = 550
y_mm = 150
[[scene.starts]]
colour = "red"
x_mm = 450
y_mm = -150
[[scene.starts]]
colour = "blue"
x_mm = 500
y_mm = -150
"""

OUTLINES = """
threshold_mm = 1.0
yaw_threshold_deg = 1.0
[objects.trapezoid]
outline_mm = [[0, 0], [70, 0], [50, 35], [15, 35]]
height_mm = 20
[objects.triangle]
outline_mm = [[0, 0], [60, 0], [15, 45]]
height_mm = 20
[[targets]]
object = "trapezoid"
colour = "green"
x_mm = 560
y_mm = 120
name = "trapezoid"
[[targets]]
object = "triangle"
colour = "green"
x_mm = 450
y_mm = 160
name = "triangle"
[[scene.starts]]
object = "trapezoid"
colour = "green"
x_mm = 500
y_mm = -200
yaw_deg = -30
name = "trapezoid"
[[scene.starts]]
object = "triangle"
colour = "green"
x_mm = 590
y_mm = -170
yaw_deg = 60
name = "triangle"
"""

TWO_ELLS = """
threshold_mm = 1.0
yaw_threshold_deg = 1.0
[objects.ell]
outline_mm = [[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]]
height_mm = 20
[[targets]]
object = "ell"
colour = "green"
x_mm = 430
y_mm = 120
[[targets]]
object = "ell"
colour = "green"
x_mm = 560
y_mm = 120
[[scene.starts]]
object = "ell"
colour = "green"
x_mm = 420
y_mm = -200
yaw_deg = 10
[[scene.starts]]
object = "ell"
colour = "green"
x_mm = 500
y_mm = -200
yaw_deg = -30
"""

FRESCO = """
threshold_mm = 1.0
yaw_threshold_deg = 1.0
[colours.ochre]
rgb = [0.8, 0.55, 0.2]
[fresco.tile]
size_mm = [{size}]
pieces = {pieces}
gap_mm = 2
seed = 0
colour = "ochre"
x_mm = 500
y_mm = 0
yaw_deg = 0
"""

#: Each scene: its plan text, the scatter seed, and the starts (by name) slid against another's.
SCENES: dict[str, tuple[str, int, tuple[tuple[str, str], ...]]] = {
    "two red cubes": (TWO_CUBES, 0, ()),
    "three red cubes in a row": (THREE_CUBES_IN_A_ROW, 0, (("red 2", "red 1"), ("red 3", "red 2"))),
    "two orange bars": (TWO_BARS, 0, ()),
    "red and blue cubes": (RED_AND_BLUE, 0, ()),
    "a trapezoid and a triangle of one colour": (OUTLINES, 0, (("triangle", "trapezoid"),)),
    "two identical ells": (TWO_ELLS, 0, (("green 2", "green 1"),)),
    "fresco of 3, two touching": (FRESCO.format(size="120, 80, 20", pieces=3), 0, (("tile 2", "tile 1"),)),
    "fresco of 8, three pairs touching": (
        FRESCO.format(size="200, 120, 20", pieces=8),
        0,
        (("tile 6", "tile 5"), ("tile 1", "tile 3"), ("tile 7", "tile 2")),
    ),
}


def touching(moving: ObjectStart, fixed: ObjectStart, gap: float = TOUCHING_GAP_M) -> ObjectStart:
    """``moving`` slid along the line to ``fixed`` until their footprints are ``gap`` (m) apart (bisection)."""
    settings = ManipulationSettings()

    def footprint(start: ObjectStart) -> Any:
        as_target = Target(start.colour, start.x_m, start.y_m, start.yaw_rad, object_type=start.object_type)
        return stacking.footprint_of(as_target, settings)

    origin = np.array([moving.x_m, moving.y_m])
    towards = np.array([fixed.x_m, fixed.y_m]) - origin
    fixed_print = footprint(fixed)

    def at(t: float) -> ObjectStart:
        x, y = origin + towards * t
        return replace(moving, x_m=float(x), y_m=float(y))

    low, high = 0.0, 1.0
    for _ in range(50):
        middle = (low + high) / 2
        low, high = (middle, high) if gap_m(footprint(at(middle)), fixed_print) > gap else (low, middle)
    return at(low)


def scene(name: str, folder: Path) -> tuple[Any, list[ObjectStart]]:
    """The scene's tree root and starts (the plan written to ``folder``)."""
    text, seed, pairs = SCENES[name]
    path = folder / f"{name.replace(' ', '_').replace(',', '')}.toml"
    path.write_text(text)
    module = treefile.load(path)
    root = treefile.build_root(module)
    starts = list(treefile.scene(module, seed))
    names = [s.name or s.colour for s in starts]
    for moving, fixed in pairs:
        i, j = names.index(moving), names.index(fixed)
        starts[i] = touching(starts[i], starts[j])
    return root, starts
