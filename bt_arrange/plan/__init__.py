"""The plan's floor: what a plan is and what is checked of it, below the behaviours and the trees.

``targets`` holds ``Target`` (one part's goal); ``validate`` the checks of a list of them and the
layout's steps; ``layout`` (with ``layout_part``, ``layout_judged`` and ``footprints``) finds an
order and where the pads go among neighbours; ``stacking`` the supports of a plan in layers;
``puzzle_targets`` the targets a puzzle's solve gives; ``camera_view`` what the top camera sees;
``check`` the plan check run before anything moves; ``tolerance`` the one "within" rule;
``choices`` the enums a plan chooses among; ``compiled`` turns all of it into one frozen
``ArrangementPlan``, a step per part, that the tree builders render. Nothing here imports a
behaviour, a tree builder or the session.
"""

from bt_arrange.plan.camera_view import CameraView
from bt_arrange.plan.check import PlanSource, check_plan, check_scene
from bt_arrange.plan.choices import CorrectMode, PushStrategy
from bt_arrange.plan.compiled import ArrangementPlan, NeighbourCheck, PartStep, compile_plan
from bt_arrange.plan.targets import DEFAULT_YAW_THRESHOLD_DEG, Target, check_threshold, parts_of
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.plan.validate import plan_steps, validate_targets

__all__ = [
    "DEFAULT_YAW_THRESHOLD_DEG",
    "ArrangementPlan",
    "CameraView",
    "CorrectMode",
    "NeighbourCheck",
    "PartStep",
    "PlanSource",
    "PushStrategy",
    "Target",
    "Tolerance",
    "check_plan",
    "check_scene",
    "check_threshold",
    "compile_plan",
    "parts_of",
    "plan_steps",
    "validate_targets",
]
