"""The plan's floor: what a plan is and what is checked of it, below the behaviours and the trees.

``targets`` holds ``Target`` (one part's goal) and the checks of a list of them; ``layout`` (with
``layout_part``, ``layout_judged`` and ``footprints``) finds an order and where the pads go among
neighbours; ``stacking`` the supports of a plan in layers; ``puzzle_targets`` the targets a puzzle's
solve gives; ``camera_view`` what the top camera sees; ``check`` the plan check run before anything
moves. Nothing here imports a behaviour, a tree builder or the session.
"""

from bt_arrange.plan.camera_view import CameraView
from bt_arrange.plan.check import PlanSource, check_plan, check_scene
from bt_arrange.plan.targets import (
    DEFAULT_YAW_THRESHOLD_DEG,
    Target,
    check_threshold,
    parts_of,
)
from bt_arrange.plan.validate import plan_steps, validate_targets

__all__ = [
    "DEFAULT_YAW_THRESHOLD_DEG",
    "CameraView",
    "PlanSource",
    "Target",
    "check_plan",
    "check_scene",
    "check_threshold",
    "parts_of",
    "plan_steps",
    "validate_targets",
]
