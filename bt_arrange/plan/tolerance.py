"""How close a part must end to its target: the one "within" rule of a plan.

A part is within when its measured offset plus the camera's own error (``margin_mm``: what a
measurement may miss by, ``bt_arrange.uncertainty``) is under ``threshold_mm``, and its yaw error
under ``yaw_threshold_deg`` (None: position only; an unmeasured yaw does not count against it).
The correction loop (``RepeatUntilWithin``), the run's report and a campaign's summary all ask a
``Tolerance``, so the rule is written once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bt_arrange.checks import positive_number


@dataclass(frozen=True)
class Tolerance:
    """A plan's thresholds: ``threshold_mm`` on the planar offset (``inf``: yaw only), ``yaw_threshold_deg`` on yaw."""

    threshold_mm: float
    yaw_threshold_deg: float | None = None

    def __post_init__(self) -> None:
        positive_number("threshold", self.threshold_mm, "mm", style="unit", finite=False)
        if self.yaw_threshold_deg is not None:
            positive_number("yaw threshold", self.yaw_threshold_deg, "deg", style="unit", finite=False)
        object.__setattr__(self, "threshold_mm", float(self.threshold_mm))
        if self.yaw_threshold_deg is not None:
            object.__setattr__(self, "yaw_threshold_deg", float(self.yaw_threshold_deg))

    @property
    def yaw_only(self) -> bool:
        """True when the offset is not judged (an infinite ``threshold_mm``): the yaw alone decides."""
        return math.isinf(self.threshold_mm)

    def offset_within(self, offset_mm: float, margin_mm: float = 0.0) -> bool:
        """True when the offset with the camera's margin lies under the threshold."""
        return offset_mm + margin_mm < self.threshold_mm

    def yaw_within(self, yaw_error_deg: float | None) -> bool:
        """True when the yaw error is under its threshold, or is not judged (no threshold, or not measured)."""
        return self.yaw_threshold_deg is None or yaw_error_deg is None or abs(yaw_error_deg) < self.yaw_threshold_deg

    def within(self, offset_mm: float, yaw_error_deg: float | None = None, margin_mm: float = 0.0) -> bool:
        """The rule: the offset with the margin under the threshold, and the yaw error within."""
        return self.offset_within(offset_mm, margin_mm) and self.yaw_within(yaw_error_deg)
