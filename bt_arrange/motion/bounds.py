"""Lower bounds on motion times: what a jerk-limited trajectory needs at the hardware's limits.

``benchmarks/throughput.py`` sets a run's world time beside these bounds, for the same waypoints:

- a joint move: ruckig's time-optimal rest-to-rest trajectory between the same joint vectors, at
  the UR5's joint speeds (the URDF's) and the highest acceleration and jerk the project allows
  (``ManipulationSettings.free_joint_limits``);
- a straight TCP line: the longer of that joint-space bound between its ends and the path's own
  rest-to-rest time at the UR5's typical TCP speed (1 m/s) and the project's fastest line limits;
- the fingers: their travel at the 2F-85's datasheet speed (150 mm/s).

Each is a lower bound of the motion it stands for: any trajectory between the same rest states
under the same limits takes at least as long (ruckig's is time-optimal), and a line is one such
trajectory with a path constraint on top.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from ruckig import InputParameter, Result, Ruckig, Trajectory

from bt_arrange.errors import MotionError
from bt_arrange.motion.limits import MAX_TCP_SPEED_M_S, CartesianLimits, JointLimits


def rest_to_rest_s(
    start: ArrayLike, target: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike, jerk: ArrayLike
) -> float:
    """Time-optimal jerk-limited rest-to-rest duration (s) from ``start`` to ``target``, per-axis limits."""
    start = np.atleast_1d(np.asarray(start, dtype=float))
    target = np.atleast_1d(np.asarray(target, dtype=float))
    dofs = len(start)
    if float(np.max(np.abs(target - start), initial=0.0)) < 1e-12:
        return 0.0
    inp = InputParameter(dofs)
    inp.current_position = start.tolist()
    inp.target_position = target.tolist()
    zeros = [0.0] * dofs
    inp.current_velocity = inp.current_acceleration = zeros
    inp.target_velocity = inp.target_acceleration = zeros
    inp.max_velocity = np.broadcast_to(np.asarray(velocity, dtype=float), (dofs,)).tolist()
    inp.max_acceleration = np.broadcast_to(np.asarray(acceleration, dtype=float), (dofs,)).tolist()
    inp.max_jerk = np.broadcast_to(np.asarray(jerk, dtype=float), (dofs,)).tolist()
    trajectory = Trajectory(dofs)
    result = Ruckig(dofs).calculate(inp, trajectory)
    if result not in (Result.Working, Result.Finished):
        raise MotionError(f"no rest-to-rest trajectory from {start} to {target}: ruckig {result}")
    return float(trajectory.duration)


def joint_move_bound_s(start_q: ArrayLike, target_q: ArrayLike, limits: JointLimits) -> float:
    """A joint move's lower bound: rest to rest at the hardware joint speeds, ``limits``' acceleration and jerk."""
    return rest_to_rest_s(
        start_q, target_q, limits.hardware_velocity_rad_s, limits.acceleration_rad_s2, limits.jerk_rad_s3
    )


def line_bound_s(
    start_q: ArrayLike, target_q: ArrayLike, length_m: float, joint_limits: JointLimits, line_limits: CartesianLimits
) -> float:
    """A straight line's lower bound: its ends' joint-space bound, or its path at 1 m/s, whichever is longer."""
    path_s = rest_to_rest_s([0.0], [length_m], MAX_TCP_SPEED_M_S, line_limits.acceleration_m_s2, line_limits.jerk_m_s3)
    return max(joint_move_bound_s(start_q, target_q, joint_limits), path_s)


def finger_bound_s(travel_m: float, max_speed_m_s: float) -> float:
    """The fingers' lower bound: their travel (change of opening, m) at the gripper's top speed."""
    return abs(travel_m) / max_speed_m_s
