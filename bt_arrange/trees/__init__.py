"""Builders of arrangement trees: the paper's Algorithm 1 as py_trees subtrees.

``targets`` holds a plan's targets and their checks, ``steps`` the subtrees of one part (find,
transfer, inspect, correct), ``arrangement`` the tree of one part (``arrange_one``) and of a whole
plan (``arrangement``, ``Arrangement``). See ``bt_arrange.trees.arrangement`` for the tree's shape.
"""

from bt_arrange.trees.arrangement import TARGETS, Arrangement, arrange_one, arrangement
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
from bt_arrange.trees.targets import (
    CORRECT_MODES,
    DEFAULT_YAW_THRESHOLD_DEG,
    Target,
    check_threshold,
    footprint_m,
    kinds,
    parts_of,
    plan_steps,
    validate_targets,
)

__all__ = [
    "CORRECT_MODES",
    "DEFAULT_YAW_THRESHOLD_DEG",
    "TARGETS",
    "Arrangement",
    "Locate",
    "Target",
    "arrange_one",
    "arrangement",
    "by_camera",
    "by_depth",
    "check_strategy",
    "check_threshold",
    "correction",
    "footprint_m",
    "inspect",
    "kinds",
    "parts_of",
    "plan_steps",
    "set_target",
    "transfer",
    "validate_targets",
]
