"""Moved to ``bt_arrange.plan.stacking``: this path warns once and goes in the next release."""

from bt_arrange.deprecation import moved_module

moved_module(__name__, "bt_arrange.plan.stacking")
