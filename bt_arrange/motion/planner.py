"""``MotionPlanner``: one object that holds the kinematics, the limits and the control period.

A behaviour receives a planner and asks it for motions; it never builds ruckig inputs itself.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from numpy.typing import ArrayLike

from bt_arrange.geometry import Pose
from bt_arrange.motion.kinematics import ArmKinematics
from bt_arrange.motion.limits import CartesianLimits, JointLimits
from bt_arrange.motion.trajectory import (
    DEFAULT_LINE_ORIENTATION_TOLERANCE_RAD,
    JointMotion,
    LinearMotion,
    Motion,
    check_control_period,
)

if TYPE_CHECKING:
    from bt_arrange.motion.safety import MotionSafety


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

    ``safety`` (``bt_arrange.motion.safety.MotionSafety``) applies to every motion: its speed fraction scales
    the limits each motion plans with (the planner's own and those a call passes), and its workspace
    box, when the cell gives one, is checked against each planned motion before it is returned (a
    ``WorkspaceStop`` naming the motion and the box; nothing of it was sent).
    """

    def __init__(
        self,
        kinematics: ArmKinematics,
        joint_limits: JointLimits,
        cartesian_limits: CartesianLimits,
        control_period_s: float,
        safety: MotionSafety | None = None,
    ) -> None:
        """Hold the kinematics, the limits of both kinds of motion, the arm's control period and the safety."""
        from bt_arrange.motion.safety import MotionSafety

        self.kinematics = kinematics
        self.joint_limits = joint_limits
        self.cartesian_limits = cartesian_limits
        self.control_period_s = check_control_period(control_period_s)
        #: The speed fraction and workspace box every motion is planned under.
        self.safety = safety if safety is not None else MotionSafety()
        #: Called with every motion planned (and what it is, in words), e.g. to count a dry run's motions.
        self.planned_hooks: list[Callable[[Motion, str], object]] = []

    def _checked(self, motion: JointMotion | LinearMotion, what: str) -> None:
        """Refuse ``motion`` (``WorkspaceStop``) when its TCP path leaves the workspace box, if there is one."""
        if self.safety.workspace is not None:
            self.safety.workspace.check_motion(motion, self.kinematics, what)
        for hook in self.planned_hooks:
            hook(motion, what)

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
        motion = JointMotion(
            start_q,
            target_q,
            self.safety.joint_limits(joint_limits or self.joint_limits),
            self.control_period_s,
            start_velocities_rad_s=start_velocities_rad_s,
            start_accelerations_rad_s2=start_accelerations_rad_s2,
        )
        if self.safety.workspace is not None or self.planned_hooks:
            end = self.kinematics.forward(motion.target_positions_rad).position_m
            self._checked(motion, f"the joint move to TCP ({end[0]:.3f}, {end[1]:.3f}, {end[2]:.3f}) m")
        return motion

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
        motion = LinearMotion(
            self.kinematics,
            start_q,
            target_pose,
            self.safety.cartesian_limits(cartesian_limits or self.cartesian_limits),
            self.safety.joint_limits(joint_limits or self.joint_limits),
            self.control_period_s,
            orientation_tolerance_rad=orientation_tolerance_rad,
        )
        x, y, z = (float(v) for v in target_pose.position_m)
        self._checked(motion, f"the line to TCP ({x:.3f}, {y:.3f}, {z:.3f}) m")
        return motion
