"""A hand-composed tree: three cubes in a row, the middle one first, all corrected at the end.

The worked example of docs/trees.md: it uses the subtree builders of ``bt_arrange.trees``
(``set_target``, ``transfer``, ``correction``) and py_trees composites directly.

    bt-arrange run trees/row_of_three.py
"""

import py_trees

from bt_arrange import backends
from bt_arrange.behaviours import Inspect, MoveHome
from bt_arrange.objects import ObjectStart
from bt_arrange.trees import Arrangement, Target, correction, set_target, transfer, validate_targets

ROW = [Target("green", 0.50, 0.10), Target("red", 0.50, 0.0), Target("blue", 0.50, -0.10)]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 8) -> Arrangement:
    """Place the middle cube, then its neighbours; then correct each one, middle first."""
    plan = validate_targets(ROW)  # one clear PlanError before anything moves
    middle_first = [plan[1], plan[0], plan[2]]
    place = py_trees.composites.Sequence(
        name="place the row",
        memory=True,
        children=[
            py_trees.composites.Sequence(
                name=f"place {t.obj}",
                memory=True,
                children=[
                    set_target(t),
                    transfer(t),
                    Inspect(f"inspect {t.obj} after placing", t.obj, after_placing=True),
                ],
            )
            for t in middle_first
        ],
    )
    correct = py_trees.composites.Sequence(
        name="correct the row",
        memory=True,
        children=[
            py_trees.composites.Sequence(
                name=f"check {t.obj}",
                memory=True,
                children=[Inspect(f"look at {t.obj}", t.obj), correction(t, threshold_mm, max_pushes)],
            )
            for t in middle_first
        ],
    )
    return Arrangement("row of three", [place, correct, MoveHome("park the arm")], plan, threshold_mm)


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start in the simulator."""
    return (backend or backends.load()).scatter([t.colour for t in ROW], seed, avoid=ROW)
