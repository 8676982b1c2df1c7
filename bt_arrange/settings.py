"""How the arm handles a part: heights, widths, forces and timeouts of pick, place and push.

The part's own geometry is its shape's and the pads' figures are the gripper's
(``bt_arrange.shapes``): the settings hold the gripper and the handling policy around both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from bt_arrange.errors import OutOfRangeError
from bt_arrange.motion.limits import HARDWARE_JOINT_VELOCITY_RAD_S, CartesianLimits, JointLimits
from bt_arrange.shapes import ROBOTIQ_2F85, Gripper, Shape, preferred_grasp

#: How ``Pick`` squares a part pinched across its corners (``ManipulationSettings.squaring``).
SQUARINGS = ("shift", "sweep", "turn", "off")


#: The least gap between two targets at a threshold of 1 mm or more (m).
DEFAULT_TARGET_GAP_M = 0.002


@dataclass(frozen=True)
class ManipulationSettings:
    """Heights, widths and forces of handling parts on a table at z = 0 (metres, newtons, seconds).

    The TCP sits between the pads at mid-pad height; the grasp holds a part at the height its
    shape's grasp gives (through the centre of mass where the pads allow, ``tcp_heights_m``).
    """

    #: The gripper: its stroke, pads and clearances.
    gripper: Gripper = ROBOTIQ_2F85
    #: TCP height for moves above the table: the pads' bottoms 3 cm clear of a resting 5 cm cube's
    #: top, a held cube's bottom 2.5 cm (joint-space moves between two such poses did not dip below
    #: it in the four-cube tree). Lower means shorter descents and lifts.
    approach_height_m: float = 0.10
    #: A taller part raises the moves above the table: the TCP stays at least this far above its top.
    approach_clearance_m: float = 0.05
    #: A tree built for a plan of parts all lower than a cube moves above the table at
    #: ``flat_approach_clearance_m`` over the plan's tallest part instead (shorter descents, lifts,
    #: lowerings and retreats).
    #: False keeps ``approach_height_m`` as the floor: for a table holding taller things than the plan's parts.
    approach_over_plan: bool = True
    #: The TCP's height (m) over the tallest top of a plan of flat parts placed free (``approach_over_plan``):
    #: 0.06 m for 20 mm parts, the pads' bottoms 21 mm over the parts' tops (31 mm at 0.05). Each of a
    #: transfer's four lines 10 mm shorter; no contact of the arm with a part other than the one it
    #: handles over the five-outline plans at seeds 0 to 19 (docs/motion.md).
    flat_approach_clearance_m: float = 0.04
    #: The held part is let go this far above resting: the arm's height error plus a little.
    release_clearance_m: float = 0.0005
    #: Layers: a part released on others is let go at least this far above its support. A
    #: held part sinks along the pads in the carry (about 0.4 mm in MuJoCo's soft pads), so at 0.5 mm it
    #: could be let go already standing on its support, and the opening pads dragged it and its
    #: support with it by friction; at 2 mm the drop moved the support 0.2 mm (docs/stacking.md).
    raised_release_clearance_m: float = 0.001
    grip_force_n: float = 40.0
    #: The arm's payload (the UR5's 5 kg): the gripper and the part it carries together.
    arm_payload_kg: float = 5.0
    #: The pads must hold a part with this factor to spare (``Gripper.friction_lift_kg``).
    lift_safety: float = 2.0
    #: Opening before a grasp: the full stroke, so a cube up to 17.5 mm off along the closing axis
    #: still lands between the pads (and is dragged to the centre as they close).
    open_width_m: float = ROBOTIQ_2F85.stroke_m
    #: A closed grip narrower than the part by more than this means the part is not between the pads.
    grasp_width_tolerance_m: float = 0.003
    #: A grip wider than the grasped side by more than this (60 mm on a 5 cm cube) holds the part
    #: more than about 13 degrees off square, or by two of its vertical edges (a cube turned about 27
    #: degrees or more under the pads: 67 to 70 mm apart, measured): Pick squares it (``squaring``)
    #: and lets go to look again only when it is still this wide. Narrower turned grips are kept, as
    #: in the paper's orientation error: the pushes square the part.
    turned_grip_margin_m: float = 0.010
    #: A grip wider than the turned-grip margin allows (the pads pinch two vertical edges of a cube turned
    #: about 27 degrees or more; no closing force turns it, its corners stick on the pads) is squared
    #: before it is given up (``Pick``): "shift" opens, moves ``squaring_shift_m`` along the pads so
    #: one corner falls beyond a pad's edge, closes (the pad's edge turns the face square), opens,
    #: comes back to the measured centre and closes again; "sweep" opens and sweeps
    #: ``squaring_sweep_m`` along the closing axis, a pad pushing the part's leading corner as a
    #: flat fence, then closes; "turn" opens, turns the wrist by ``squaring_turn_deg`` about the
    #: TCP's vertical axis and closes, and if the grip is still that wide, opens, turns to minus
    #: that from the first yaw and closes again (the centred close then squares the part about its
    #: centre, as it does any cube turned less than about 27 degrees); "off" lets go at once.
    #: "turn" is the default: in Table 1 row 3 it squared all 45 pinched cubes of 100 and moved them
    #: 0.9 to 2.4 mm on average, where "shift" and "sweep", pivoting about a corner, moved them 13 to 19 mm.
    squaring: str = "turn"
    #: Half a pad's width: the pad's edge comes to where its centre was, so the corner that landed
    #: on it (within 11 mm of its centre for any turn of 27 to 45 degrees) falls beyond it.
    squaring_shift_m: float = 0.011
    squaring_sweep_m: float = 0.060
    #: The wrist turn of ``squaring = "turn"`` (degrees): it brings a pinched turn of 27 to 45 degrees
    #: to 4.5 to 22.5 degrees from the pads, under the 27 at which the corners stick (the middle of
    #: the 18 to 27 degrees that bring both 27 and 45 under 27).
    squaring_turn_deg: float = 22.5
    #: The pads start this far from the face they push, and back off this far after.
    push_clearance_m: float = 0.010
    #: A push shorter than this along the alternated axis gives way to the other axis. A threshold
    #: finer than ``min_threshold_mm`` lowers it to fit (``for_threshold``), down to ``finest_push_m``.
    min_push_m: float = 0.0002
    #: The shortest push made at all (m): pushes of 0.3 to 0.8 mm kept all but 0.010 to 0.016 mm of
    #: what they moved (docs/irregular.md, "Sub-millimetre pushes"), so 0.05 mm is still a push.
    finest_push_m: float = 0.00005
    #: Two targets closer than this could touch once each lies within the threshold: twice the
    #: threshold, at most 2 mm (the gap a 1 mm threshold needs, and what coarser ones keep) and at
    #: least ``finest_gap_m``. ``for_threshold`` sets it from the run's threshold.
    min_target_gap_m: float = DEFAULT_TARGET_GAP_M
    #: The least gap between two targets at all (m): twice the 0.25 mm the precision runs are held to.
    finest_gap_m: float = 0.0005
    #: The line that pushes: slower than the planner's lines, so the part stops when the pads do.
    push_limits: CartesianLimits = CartesianLimits(velocity_m_s=0.15, acceleration_m_s2=0.5, jerk_m_s3=3.5)
    #: Layers: the gentler line that pushes a part standing on others. It drags its support
    #: by friction however fast it goes, but at a third of the speed the pads meet the face with a
    #: ninth of the kinetic energy, and the part stops within less of its support's edge.
    raised_push_limits: CartesianLimits = CartesianLimits(velocity_m_s=0.05, acceleration_m_s2=0.25, jerk_m_s3=2.0)
    #: Joint moves with empty pads (above a part, home, out of the camera's view): the UR5's own joint
    #: speeds (the URDF's 3.15 and 3.2 rad/s), 16 rad/s^2 (0.2 s to full speed; the pendant allows 40)
    #: and 200 rad/s^3. The lines that carry a part (the lift, the lowering) run at the planner's
    #: gentler limits (``CartesianLimits()``: 0.6 m/s, 3 m/s^2), a push at ``push_limits``.
    free_joint_limits: JointLimits = JointLimits(
        velocity_rad_s=HARDWARE_JOINT_VELOCITY_RAD_S, acceleration_rad_s2=16.0, jerk_rad_s3=200.0
    )
    #: The carry of a held part above its target: as fast as a move with empty pads. Its inertia asks
    #: little of the grip (a 5 cm wooden cube at the 13 m/s^2 that 16 rad/s^2 gives at the UR5's reach:
    #: 1.6 N of the pads' 96 N of friction at 40 N); measured in Table 1 (40 trials a row) and the
    #: four-cube tree, the parts landed as close as at 2 rad/s and 8 rad/s^2. A part held off its
    #: centre of mass (an irregular part's grasp) takes it too: the irregular and fresco benchmarks
    #: (three seeds each) held 15 of 15 and 18 of 18 within, as at the planner's limits.
    carry_joint_limits: JointLimits = JointLimits(
        velocity_rad_s=HARDWARE_JOINT_VELOCITY_RAD_S, acceleration_rad_s2=16.0, jerk_rad_s3=200.0
    )
    #: Straight lines with empty pads (down to a part, up from one just released): the UR5's typical
    #: TCP speed of 1 m/s, 4 m/s^2 and 40 m/s^3 (a 7.5 cm line in about 0.3 s, at rest at both ends).
    free_line_limits: CartesianLimits = CartesianLimits(velocity_m_s=1.0, acceleration_m_s2=4.0, jerk_m_s3=40.0)
    #: A line up from a part (the lift, the retreat) hands on to the joint move after it this far
    #: below its end, without stopping there (m): the pads are then 1.65 cm above the part's top (a
    #: held part's bottom 1.5 cm above a neighbour as tall), and the next move goes on rising.
    hand_on_remaining_m: float = 0.015
    #: After a motion the arm counts as settled once every joint moves slower than this (rad/s; 1 mrad/s
    #: is under a millimetre per second at the TCP). Measured in the cell: the position-controlled
    #: joints are that still within one or two control periods of a jerk-limited motion's end.
    settled_speed_rad_s: float = 0.001
    #: The longest the arm is given to settle after a motion (s): a joint still moving then is left to
    #: the next step.
    settle_s: float = 0.05
    #: The 2F-85's finger speed for closing on a part and for releasing one (the datasheet's
    #: 20 to 150 mm/s; 150: a 35 mm close takes 0.23 s).
    finger_speed_m_s: float = 0.15
    #: The finger speed of a close that squares a part pinched across its corners (``squaring``):
    #: the pads turn the part as they meet it. Measured: at 75 to 150 mm/s a cube turned 33 degrees
    #: was held up to 6 degrees off square after the wrist turn; at 50 mm/s under 5 (both ways).
    squaring_finger_speed_m_s: float = 0.05
    #: A close that meets a part at ``squaring_finger_speed_m_s`` (an off-centre grasp's, whose pads
    #: meeting the outline fast turn the part) runs at ``finger_speed_m_s`` until the pads stand this
    #: far (m) from the grasped side on each side: the pads meet the part as slowly as before, without
    #: crossing the rest of the stroke slowly (85 mm to a 50 mm side took 0.7 s).
    slow_close_clearance_per_side_m: float = 0.003
    #: Layers: the finger speed of a release on others (the datasheet's slowest). Two pads
    #: never leave a part at the same instant: the later one drags it, and a part standing on others
    #: drags its support with it by friction.
    raised_release_finger_speed_m_s: float = 0.02
    #: A first close wider than the grasped side by more than this (m) left the part a little turned
    #: in the pads (a 5 cm cube about 1.1 degrees): Pick opens just clear of it and closes again slowly.
    square_grip_tolerance_m: float = 0.001
    #: A release opens the pads only this far beyond the held part's width on each side (m), enough
    #: for the straight retreat up (the next pick opens them fully on its way).
    release_clearance_per_side_m: float = 0.008
    #: A part held off its centre (an irregular part), picked where the camera found it, is approached
    #: with the pads open this far beyond its grasped side on each side (m), not to the full stroke
    #: (85 mm): its close crosses that much less free stroke at 150 mm/s (a 36 mm kite's 9 mm). Over
    #: five times the real-cell model's per-grasp offset (3.5 mm), and most of Table 1's injected pick
    #: translation (up to 25 mm): at 12 mm a pad came down on an ell picked 14.7 mm off. A cuboid,
    #: and a grasp a layout gives, open as before.
    off_centre_pick_clearance_per_side_m: float = 0.020
    #: The fingers must stop within this time after an open or close command.
    gripper_timeout_s: float = 2.0

    def __post_init__(self) -> None:
        if self.squaring not in SQUARINGS:
            raise OutOfRangeError(f"squaring {self.squaring!r}: choose one of {', '.join(SQUARINGS)}")
        if not 0.0 < self.squaring_turn_deg < 45.0:
            raise OutOfRangeError(f"squaring turn {self.squaring_turn_deg:g} deg must lie between 0 and 45 deg")
        low, high = self.gripper.force_range_n
        if not low <= self.grip_force_n <= high:
            raise OutOfRangeError(f"grip force {self.grip_force_n:.1f} N is outside {low:.0f} to {high:.0f} N")
        low_speed, high_speed = self.gripper.speed_range_m_s
        for name, speed in (
            ("finger speed", self.finger_speed_m_s),
            ("squaring finger speed", self.squaring_finger_speed_m_s),
            ("raised release finger speed", self.raised_release_finger_speed_m_s),
        ):
            if not low_speed <= speed <= high_speed:
                raise OutOfRangeError(
                    f"{name} {speed * 1000:.0f} mm/s is outside the gripper's "
                    f"{low_speed * 1000:.0f} to {high_speed * 1000:.0f} mm/s"
                )
        if not self.settled_speed_rad_s > 0.0:
            raise OutOfRangeError(f"settled speed {self.settled_speed_rad_s:g} rad/s must be positive")
        if not self.settle_s >= 0.0:
            raise OutOfRangeError(f"settle time {self.settle_s:g} s must not be negative")
        for name, value in (
            ("hand-on distance", self.hand_on_remaining_m),
            ("release clearance per side", self.release_clearance_per_side_m),
            ("off-centre pick clearance per side", self.off_centre_pick_clearance_per_side_m),
            ("flat approach clearance", self.flat_approach_clearance_m),
            ("raised release clearance", self.raised_release_clearance_m),
        ):
            if not value >= 0.0:
                raise OutOfRangeError(f"{name} {value * 1000:g} mm must not be negative")
        if not 0.0 < self.open_width_m <= self.gripper.stroke_m:
            raise OutOfRangeError(
                f"open width {self.open_width_m * 1000:.1f} mm must be positive "
                f"and stay within the gripper's {self.gripper.stroke_m * 1000:.0f} mm"
            )

    @property
    def max_payload_part_kg(self) -> float:
        """The heaviest part the arm carries: its payload less the gripper's mass."""
        return self.arm_payload_kg - self.gripper.mass_kg

    def max_lift_kg(self, part_friction: float) -> float:
        """The heaviest part of that friction the pads lift at ``grip_force_n`` (``Gripper.friction_lift_kg``)."""
        return self.gripper.friction_lift_kg(self.grip_force_n, part_friction, self.lift_safety)

    def tcp_heights_m(self, shape: Shape) -> tuple[float, float, float]:
        """(grasp, approach, push) TCP heights above the table for a part of ``shape``.

        The grasp and the push hold the pads at the shape's grasp height (through the centre of
        mass where the pads allow); the moves above the table rise with a part taller than 5 cm.
        """
        grasp_m = preferred_grasp(shape, self.gripper).height_m
        approach_m = max(self.approach_height_m, shape.height_m + self.approach_clearance_m)
        return grasp_m, approach_m, grasp_m

    @property
    def min_threshold_mm(self) -> float:
        """The smallest threshold a push is sure to correct, in millimetres.

        An offset at the threshold may lie diagonally: ``threshold / sqrt(2)`` along each axis.
        Push skips an axis whose offset is below ``min_push_m``, so below ``sqrt(2) * min_push_m``
        an offset over the threshold could leave both axes without a push, and every "correction"
        would leave the part where it is.
        """
        return math.sqrt(2.0) * self.min_push_m * 1000

    @property
    def finest_threshold_mm(self) -> float:
        """The smallest threshold a tree takes (mm): ``min_threshold_mm`` at ``finest_push_m``."""
        return math.sqrt(2.0) * self.finest_push_m * 1000

    def for_tallest_part(self, height_m: float) -> ManipulationSettings:
        """These settings for a plan whose tallest part's top is ``height_m`` above the table.

        With ``approach_over_plan``, when ``approach_clearance_m`` over that top is lower than
        ``approach_height_m`` (parts lower than a cube), the approach comes down to
        ``flat_approach_clearance_m`` over it, and so does every shape's (``tcp_heights_m``); a
        taller plan keeps these settings (the shapes' own heights raise it).
        """
        if not self.approach_over_plan or height_m + self.approach_clearance_m >= self.approach_height_m:
            return self
        clearance_m = min(self.approach_clearance_m, self.flat_approach_clearance_m)
        return replace(self, approach_height_m=height_m + clearance_m, approach_clearance_m=clearance_m)

    def for_threshold(self, threshold_mm: float) -> ManipulationSettings:
        """These settings for a run to ``threshold_mm``: the shortest push and the least gap between targets.

        An offset at the threshold may lie diagonally, ``threshold / sqrt(2)`` along each axis: under
        ``min_threshold_mm`` that becomes the shortest push (never under ``finest_push_m``). Two
        neighbours each within the threshold must not touch: the least gap between two targets is
        ``gap_for_threshold_m``. A threshold of 1 mm or more keeps these settings.
        """
        fitting_m = threshold_mm / 1000 / math.sqrt(2.0)
        min_push_m = max(fitting_m, self.finest_push_m) if fitting_m < self.min_push_m else self.min_push_m
        gap_m = min(self.gap_for_threshold_m(threshold_mm), self.min_target_gap_m)
        if min_push_m == self.min_push_m and gap_m == self.min_target_gap_m:
            return self
        return replace(self, min_push_m=min_push_m, min_target_gap_m=gap_m)

    def gap_for_threshold_m(self, threshold_mm: float) -> float:
        """The least gap two targets need at ``threshold_mm`` (m): twice it, within ``finest_gap_m`` and 2 mm.

        Each of two neighbours may end up to the threshold off its target, towards the other: with
        the gap at twice the threshold they may meet, never overlap. (A yaw error within the yaw
        threshold turns a piece's far corners further; the pushes that bring a piece within both
        keep it off its neighbour, and the figures say how close they came: docs/irregular.md.)
        """
        return min(DEFAULT_TARGET_GAP_M, max(self.finest_gap_m, 2.0 * threshold_mm / 1000))
