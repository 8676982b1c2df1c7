"""The devices' range checks, once for every backend: what a command may ask of the gripper, the arm and the camera.

A real UR5 and 2F-85 refuse a command outside their ranges; every backend's devices (the simulated
engines' and the real cell's, ``bt_arrange.ur``) call these before they touch their world, so a tree
that runs on one backend is refused on another for the same reasons, with the same words
(``OutOfRangeError``). ``bt_arrange_sim.ranges`` re-exports them for the engines.
"""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.errors import OutOfRangeError
from bt_arrange.geometry import FloatArray
from bt_arrange.robot import GRIPPER_FORCE_RANGE_N, GRIPPER_MAX_WIDTH_M, GRIPPER_SPEED_RANGE_M_S

#: The UR5's joints: a setpoint names each of them.
ARM_JOINT_COUNT = 6


def checked_gripper_width_m(width_m: float) -> float:
    """``width_m`` when the 2F-85's stroke can open to it."""
    if not 0.0 <= width_m <= GRIPPER_MAX_WIDTH_M:
        raise OutOfRangeError(
            f"gripper width {width_m * 1000:.1f} mm is outside 0 to {GRIPPER_MAX_WIDTH_M * 1000:.0f} mm"
        )
    return width_m


def checked_grip_force_n(force_n: float) -> float:
    """``force_n`` when the gripper can press with it."""
    low, high = GRIPPER_FORCE_RANGE_N
    if not low <= force_n <= high:
        raise OutOfRangeError(f"grip force {force_n:.1f} N is outside {low:.0f} to {high:.0f} N")
    return force_n


def checked_gripper_speed_m_s(speed_m_s: float) -> float:
    """``speed_m_s`` when the fingers can move at it."""
    low, high = GRIPPER_SPEED_RANGE_M_S
    if not low <= speed_m_s <= high:
        raise OutOfRangeError(
            f"gripper speed {speed_m_s * 1000:.0f} mm/s is outside {low * 1000:.0f} to {high * 1000:.0f} mm/s"
        )
    return speed_m_s


def checked_joint_setpoint(positions_rad: FloatArray, velocities_rad_s: FloatArray | None) -> None:
    """A setpoint names every arm joint with a finite position (and velocity, when given)."""
    for what, values in (("positions", positions_rad), ("velocities", velocities_rad_s)):
        if values is None:
            continue
        array = np.asarray(values, dtype=float)
        if array.shape != (ARM_JOINT_COUNT,) or not np.all(np.isfinite(array)):
            raise OutOfRangeError(f"arm setpoint {what} {array.tolist()} are not {ARM_JOINT_COUNT} finite numbers")


def checked_joint_setpoint_lists(
    positions_rad: FloatArray, velocities_rad_s: FloatArray | None
) -> tuple[list[float], list[float] | None]:
    """``checked_joint_setpoint``, returning the setpoint as lists of floats (what a simulator's call takes).

    The same checks and the same refusal, for a setpoint sent every control period: converted to
    floats once and checked element by element, instead of through NumPy's reductions on six numbers.
    """
    lists: list[list[float] | None] = []
    for values in (positions_rad, velocities_rad_s):
        if values is None:
            lists.append(None)
            continue
        array = np.asarray(values, dtype=float)
        listed = array.tolist()
        if array.shape != (ARM_JOINT_COUNT,) or not all(map(math.isfinite, listed)):
            checked_joint_setpoint(positions_rad, velocities_rad_s)  # raises with the words of every engine
        lists.append(listed)
    positions, velocities = lists
    assert positions is not None
    return positions, velocities


def checked_render_offset(dx_m: float, dy_m: float, dyaw_rad: float) -> tuple[float, float, float]:
    """A camera displacement (error injection) of finite numbers, as floats."""
    offset = (float(dx_m), float(dy_m), float(dyaw_rad))
    if not all(math.isfinite(v) for v in offset):
        raise OutOfRangeError(f"camera render offset {offset} is not finite")
    return offset
