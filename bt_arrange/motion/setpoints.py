"""What a motion hands the arm each control period, and the control periods a motion accepts."""

from __future__ import annotations

import math
from dataclasses import dataclass

from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray

#: Longest control period accepted (s): beyond 10 Hz a setpoint stream is no longer a trajectory.
MAX_CONTROL_PERIOD_S = 0.1


@dataclass(frozen=True)
class JointSetpoint:
    """What the arm should follow during the next control period: joint positions and velocities."""

    positions_rad: FloatArray
    velocities_rad_s: FloatArray


def check_control_period(control_period_s: float) -> float:
    """Return the control period, or raise ``OutOfRangeError`` if it is not in ``(0, 0.1]`` s."""
    value = float(control_period_s)
    if not math.isfinite(value) or not 0.0 < value <= MAX_CONTROL_PERIOD_S:
        raise OutOfRangeError(f"control period {value:g} s must lie in (0, {MAX_CONTROL_PERIOD_S:g}] s")
    return value


__all__ = ["MAX_CONTROL_PERIOD_S", "JointSetpoint", "check_control_period"]
