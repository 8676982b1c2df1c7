"""The gripper's figures, in one value: stroke, pads, clearances, and the openings they give.

Every step that closes, opens or pushes with the fingers reads a :class:`Gripper` (the settings
hold one, :data:`ROBOTIQ_2F85` by default) instead of keeping its own copy of a pad's size or the
stroke. The figures are the Robotiq 2F-85's (``shared/FACTS.md``) and the bundled URDF's.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Gripper:
    """A parallel gripper with flat pads (metres, newtons, metres per second)."""

    name: str = "Robotiq 2F-85"
    #: The widest opening between the pads.
    stroke_m: float = 0.085
    force_range_n: tuple[float, float] = (20.0, 235.0)
    speed_range_m_s: tuple[float, float] = (0.020, 0.150)
    #: A pad's size: along the face it touches (width), out from it (thickness), and half its
    #: height (the TCP sits at mid-pad, so the pad's bottom is this far below the TCP).
    pad_width_m: float = 0.022
    pad_thickness_m: float = 0.008
    pad_half_height_m: float = 0.01875
    #: How far a finger reaches out from the face its pad touches, at a resting part's height: the
    #: pad is 8 mm thick, but the finger above it (which comes down to the top of a 5 cm cube at
    #: grasp height) stands 3 mm further out (the URDF's finger box).
    finger_depth_m: float = 0.011
    #: A side the fingers close across must leave this much of the stroke free (each side of the part
    #: together): room for the part's measured position to be off a little as the pads come down.
    grasp_clearance_m: float = 0.005
    #: The room kept between a pad's bottom and the table when grasping or pushing (more than the
    #: 3 mm the kinematics demand of any pose).
    table_clearance_m: float = 0.004
    #: A finger keeps this far from a neighbour's face (the arm's error and pybullet's 1 mm
    #: collision margins; 1 mm was measured to shove a neighbour 1.6 mm).
    neighbour_clearance_m: float = 0.002
    #: The pads' friction coefficient (the simulated cell's pads; a contact's friction is the
    #: product of the pads' and the part's, as Bullet combines them).
    pad_friction: float = 1.2
    #: The gripper's own mass: it counts against the arm's payload.
    mass_kg: float = 0.925

    def friction_lift_kg(self, grip_force_n: float, part_friction: float, safety: float = 2.0) -> float:
        """The heaviest part the pads hold by friction: two pads, each ``pad_friction x part_friction x force``.

        ``safety`` covers the moves' accelerations and the pads' wear (2: half of what holds it at rest).
        """
        return 2.0 * self.pad_friction * part_friction * grip_force_n / (9.81 * safety)

    @property
    def max_grasp_width_m(self) -> float:
        """The widest side the fingers close across: the stroke less the clearance."""
        return self.stroke_m - self.grasp_clearance_m

    @property
    def lowest_tcp_m(self) -> float:
        """The lowest TCP height above the table at which the pads work (grasp or push)."""
        return self.pad_half_height_m + self.table_clearance_m

    def free_push_opening_m(self, face_width_m: float) -> float:
        """The opening for a push with nothing beside the part: both pads meet the face near its edges.

        The paper's "width - thickness" (42 mm on the 5 cm cube), at most the stroke.
        """
        return min(face_width_m - self.pad_thickness_m, self.stroke_m)

    def neighbour_push_opening_m(self, face_width_m: float) -> float:
        """The opening for a push among neighbours: both fingers stay within the face's width.

        Each finger reaches ``finger_depth_m`` beyond its pad and keeps ``neighbour_clearance_m``
        from the neighbours' faces in line with the pushed face (24 mm on the 5 cm cube).
        """
        return max(0.0, 2 * (face_width_m / 2 - self.finger_depth_m - self.neighbour_clearance_m))


#: The paper's gripper, and the default of every setting.
ROBOTIQ_2F85 = Gripper()
