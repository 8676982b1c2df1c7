"""``MotionPlanner``: one object that holds the kinematics, the limits and the control period.

A behaviour receives a planner and asks it for motions; it never builds ruckig inputs itself.
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from bt_arrange.geometry import Pose
from bt_arrange.motion.kinematics import ArmKinematics
from bt_arrange.motion.limits import CartesianLimits, JointLimits
from bt_arrange.motion.trajectory import (
    DEFAULT_LINE_ORIENTATION_TOLERANCE_RAD,
    JointMotion,
    LinearMotion,
    check_control_period,
)


class MotionPlanner:
    """Plans the three kinds of motion a pick, place or push needs.

    - ``move_joints(start_q, target_q)``: joint-space motion to a joint vector (e.g. home).
    - ``move_to_pose(start_q, target_pose)``: joint-space motion to the IK solution of a TCP pose,
      seeded from ``start_q`` (fast transfers, where the TCP path does not matter).
    - ``move_line(start_q, target_pose)``: straight TCP line at constant orientation (approach,
      descend, lift, push).

    Every method plans completely and raises before returning when the motion is impossible.
    ``start_q`` is the measured joint vector; the start is taken to be at rest unless
    ``start_velocities_rad_s`` is given to ``move_joints``.
    """

    def __init__(
        self,
        kinematics: ArmKinematics,
        joint_limits: JointLimits,
        cartesian_limits: CartesianLimits,
        control_period_s: float,
    ) -> None:
        """Hold the kinematics, the limits of both kinds of motion and the arm's control period."""
        self.kinematics = kinematics
        self.joint_limits = joint_limits
        self.cartesian_limits = cartesian_limits
        self.control_period_s = check_control_period(control_period_s)

    def move_joints(
        self,
        start_q: ArrayLike,
        target_q: ArrayLike,
        start_velocities_rad_s: ArrayLike | None = None,
        *,
        start_accelerations_rad_s2: ArrayLike | None = None,
        joint_limits: JointLimits | None = None,
    ) -> JointMotion:
        """Joint-space motion from ``start_q`` (at rest, or moving at the given rates) to ``target_q``.

        ``joint_limits`` replaces the planner's for this motion (e.g. the faster free-space ones).
        """
        return JointMotion(
            start_q,
            target_q,
            joint_limits or self.joint_limits,
            self.control_period_s,
            start_velocities_rad_s=start_velocities_rad_s,
            start_accelerations_rad_s2=start_accelerations_rad_s2,
        )

    def move_to_pose(
        self,
        start_q: ArrayLike,
        target_pose: Pose,
        *,
        start_velocities_rad_s: ArrayLike | None = None,
        start_accelerations_rad_s2: ArrayLike | None = None,
        joint_limits: JointLimits | None = None,
    ) -> JointMotion:
        """Joint-space motion to the IK solution of ``target_pose`` nearest ``start_q``'s branch."""
        target_q = self.kinematics.inverse(target_pose, start_q)
        return self.move_joints(
            start_q,
            target_q,
            start_velocities_rad_s,
            start_accelerations_rad_s2=start_accelerations_rad_s2,
            joint_limits=joint_limits,
        )

    def move_line(
        self,
        start_q: ArrayLike,
        target_pose: Pose,
        orientation_tolerance_rad: float = DEFAULT_LINE_ORIENTATION_TOLERANCE_RAD,
        cartesian_limits: CartesianLimits | None = None,
        joint_limits: JointLimits | None = None,
    ) -> LinearMotion:
        """Straight TCP line from the TCP at ``start_q`` to ``target_pose``'s position, orientation kept.

        ``cartesian_limits`` replaces the planner's path limits for this line (e.g. a slower push),
        ``joint_limits`` the joint limits the line is checked against.
        """
        return LinearMotion(
            self.kinematics,
            start_q,
            target_pose,
            cartesian_limits or self.cartesian_limits,
            joint_limits or self.joint_limits,
            self.control_period_s,
            orientation_tolerance_rad=orientation_tolerance_rad,
        )
