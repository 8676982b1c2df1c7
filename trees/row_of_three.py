"""A hand-composed tree: three cubes in a row, the middle one first, all corrected at the end.

The worked example of docs/trees.md: the plan is compiled once (its threshold stated there), and
the tree is composed from its steps with the subtree builders of ``bt_arrange.trees``
(``set_target``, ``transfer``, ``correction``) and py_trees composites.

    bt-arrange run trees/row_of_three.py
"""

import py_trees

from bt_arrange import backends
from bt_arrange.behaviours import Inspect, MoveHome
from bt_arrange.objects import ObjectStart
from bt_arrange.plan import Target, Tolerance, compile_plan
from bt_arrange.trees import Arrangement, correction, set_target, transfer

ROW = [Target("green", 0.50, 0.10), Target("red", 0.50, 0.0), Target("blue", 0.50, -0.10)]


def create_root(threshold_mm: float = 1.0, max_pushes: int = 8) -> Arrangement:
    """Place the middle cube, then its neighbours; then correct each one, middle first."""
    # One clear PlanError before anything moves; the steps come in the order asked for.
    plan = compile_plan(
        ROW, Tolerance(threshold_mm, yaw_threshold_deg=1.0), max_pushes=max_pushes, order=["red", "green", "blue"]
    )
    place = py_trees.composites.Sequence(
        name="place the row",
        memory=True,
        children=[
            py_trees.composites.Sequence(
                name=f"place {step.target.obj}",
                memory=True,
                children=[
                    set_target(step.target),
                    transfer(step, plan),
                    Inspect(f"inspect {step.target.obj} after placing", step.target.obj, after_placing=True),
                ],
            )
            for step in plan.steps
        ],
    )
    correct = py_trees.composites.Sequence(
        name="correct the row",
        memory=True,
        children=[
            py_trees.composites.Sequence(
                name=f"check {step.target.obj}",
                memory=True,
                children=[Inspect(f"look at {step.target.obj}", step.target.obj), correction(step, plan)],
            )
            for step in plan.steps
        ],
    )
    return Arrangement("row of three", [place, correct, MoveHome("park the arm")], plan=plan)


def create_scene(seed: int = 0, backend: backends.Backend | None = None) -> list[ObjectStart]:
    """Where the cubes start in the simulator."""
    return (backend or backends.load()).scatter([t.colour for t in ROW], seed, avoid=ROW)
