"""Builders of arrangement trees: the paper's Algorithm 1 as py_trees subtrees, rendered from a compiled plan.

``steps`` holds the subtrees of one part (find, transfer, inspect, correct); ``arrangement`` renders
a compiled plan (``render``, ``render_part``) under its root ``Arrangement``; ``puzzle`` a puzzle's
subtree; ``builder.arrangement`` is the public builder (compile, then render). What a plan is and
what is checked of it lives on the floor below, ``bt_arrange.plan``; its names are handed on here.
"""

from bt_arrange.plan.choices import CorrectMode, PushStrategy
from bt_arrange.plan.compiled import ArrangementPlan, PartStep, compile_plan
from bt_arrange.plan.targets import (
    CORRECT_MODES,
    DEFAULT_YAW_THRESHOLD_DEG,
    Target,
    check_threshold,
    footprint_m,
    kinds,
    parts_of,
)
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.plan.validate import plan_steps, validate_targets
from bt_arrange.trees.arrangement import TARGETS, Arrangement, arrange_one, plan_of, render, render_part
from bt_arrange.trees.builder import arrangement
from bt_arrange.trees.steps import (
    Locate,
    by_camera,
    by_depth,
    check_strategy,
    correction,
    inspect,
    set_target,
    transfer,
)

__all__ = [
    "CORRECT_MODES",
    "DEFAULT_YAW_THRESHOLD_DEG",
    "TARGETS",
    "Arrangement",
    "ArrangementPlan",
    "CorrectMode",
    "PartStep",
    "PushStrategy",
    "Tolerance",
    "Locate",
    "Target",
    "arrange_one",
    "arrangement",
    "by_camera",
    "by_depth",
    "check_strategy",
    "check_threshold",
    "compile_plan",
    "correction",
    "footprint_m",
    "inspect",
    "kinds",
    "parts_of",
    "plan_of",
    "plan_steps",
    "render",
    "render_part",
    "set_target",
    "transfer",
    "validate_targets",
]
