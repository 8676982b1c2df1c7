"""The raised rows' trials (``rows.RAISED_ROWS``): the trial's cube placed on top of another.

The trial's target is drawn as every row's (``trial._run_trial``); ``raised_plan`` puts a support
of the same type under it, turned from it, and lifts the target onto the support's top face. The
arrangement places the support first (corrected as any part on the table), then the raised cube,
which is set down and picked centred before it goes up, placed at its height and corrected there
(``bt_arrange.trees.layers``). The row's figures are the raised cube's; ``SupportWatch`` adds how
far the support ended from its target and how far it moved while the raised cube was handled.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from bt_arrange.plan.targets import Target
    from bt_arrange.report import SessionReport
    from bt_arrange.runner import Transition

#: The support's colour (the trial's cube is red).
SUPPORT_COLOUR = "green"
#: The support is turned from the raised target by up to this (deg) either way: a tower's turn.
SUPPORT_TURN_DEG = 45.0


def raised_plan(target: Target, rng: np.random.Generator) -> list[Target]:
    """The support at ``target``'s place, turned by a draw of ``rng``, and ``target`` on its top face."""
    from bt_arrange.trees import Target

    turn_rad = math.radians(float(rng.uniform(-SUPPORT_TURN_DEG, SUPPORT_TURN_DEG)))
    support = Target(SUPPORT_COLOUR, target.x_m, target.y_m, target.yaw_rad + turn_rad, object_type=target.object_type)
    return [support, dataclasses.replace(target, z_m=target.object_type.shape.height_m)]


class SupportWatch:
    """Ground truth (evaluation only) of the support while the raised part is placed and corrected."""

    def __init__(self, run: Any, support: Target, raised: Target) -> None:
        self.run, self.support, self.raised = run, support.obj, raised.obj
        self.target_z_m = raised.z_m
        self.start_m: np.ndarray | None = None
        self.moved_mm: float | None = None
        run.transition_hooks.append(self)

    def _position_m(self) -> np.ndarray:
        return np.array(self.run.cell.part_pose_truth(self.support).position_m, dtype=float)

    def __call__(self, transition: Transition) -> None:
        """A snapshot when the raised part's subtree starts, the distance when it ends."""
        if transition.behaviour != f"arrange {self.raised}":
            return
        if transition.new == "RUNNING" and self.start_m is None:
            self.start_m = self._position_m()
        elif transition.new in ("SUCCESS", "FAILURE") and self.start_m is not None and self.moved_mm is None:
            self.moved_mm = round(float(np.linalg.norm(self._position_m() - self.start_m)) * 1000, 4)

    def fields(self, report: SessionReport) -> dict[str, Any]:
        """The record's support fields: its final offset (camera, truth) and how far it moved (truth, 3-D)."""
        outcome = next(o for o in report.objects if o.name == self.support)
        return {
            "target_z_mm": round(self.target_z_m * 1000, 3),
            "support": self.support,
            "support_pushed_mm": outcome.final_offset_mm,
            "support_pushed_truth_mm": outcome.final_offset_truth_mm,
            "support_moved_truth_mm": self.moved_mm,
        }
