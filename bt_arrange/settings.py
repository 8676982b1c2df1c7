"""How the arm handles a cube: heights, widths, forces and timeouts of pick, place and push."""

from __future__ import annotations

import math
from dataclasses import dataclass

from bt_arrange.errors import OutOfRangeError
from bt_arrange.motion.limits import CartesianLimits
from bt_arrange.objects import CUBE
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE
from bt_arrange.robot import GRIPPER_FORCE_RANGE_N, GRIPPER_MAX_WIDTH_M

#: Edge length of the paper's cubes, in metres (``bt_arrange.objects.CUBE``).
CUBE_EDGE_M = CUBE.size_m[0]
#: Top-face colours (RGB, 0..1) the simulated cell paints, read from the one colour table
#: (``bt_arrange.perception.DEFAULT_COLOUR_TABLE``, each range's ``rgb``): kept for callers that
#: want the paint by name; a new colour goes into the table (a plan's ``[colours.NAME]``).
CUBE_COLOURS_RGB: dict[str, tuple[float, float, float]] = {
    name: colour.paint_rgb for name, colour in DEFAULT_COLOUR_TABLE.items()
}
#: Sides of every cube: near-white, so a top camera sees only the top face in colour.
CUBE_SIDE_RGB = (0.85, 0.85, 0.82)


#: How ``Pick`` squares a cube pinched across its corners (``ManipulationSettings.squaring``).
SQUARINGS = ("shift", "sweep", "turn", "off")


@dataclass(frozen=True)
class ManipulationSettings:
    """Geometry and forces for 5 cm cubes on a table at z = 0 (metres, newtons, seconds).

    The TCP sits between the pads at mid-pad height, so ``grasp_height_m`` = half an edge grasps
    the cube through its centre of mass.
    """

    cube_edge_m: float = CUBE_EDGE_M
    #: TCP height for moves above the table: the pads' bottoms 3 cm clear of a resting cube's top,
    #: a held cube's bottom 2.5 cm (joint-space moves between two such poses did not dip below it
    #: in the four-cube tree). Lower means shorter descents and lifts.
    approach_height_m: float = 0.10
    grasp_height_m: float = CUBE_EDGE_M / 2
    #: The held cube is let go this far above resting: the arm's height error plus a little.
    release_clearance_m: float = 0.0005
    grip_force_n: float = 40.0
    #: Opening before a grasp: the full stroke, so a cube up to 17.5 mm off along the closing axis
    #: still lands between the pads (and is dragged to the centre as they close).
    open_width_m: float = 0.085
    #: A closed grip narrower than the cube by more than this means the cube is not between the pads.
    grasp_width_tolerance_m: float = 0.003
    #: A grip wider than this holds the cube more than about 13 degrees off square, or by two of its
    #: vertical edges (a cube turned about 27 degrees or more under the pads: 67 to 70 mm apart, measured):
    #: Pick squares it (``squaring``) and lets go to look again only when it is still this wide.
    #: Narrower turned grips are kept, as in the paper's orientation error: the pushes square the cube.
    max_grip_width_m: float = 0.060
    #: A grip wider than ``max_grip_width_m`` (the pads pinch two vertical edges of a cube turned
    #: about 27 degrees or more; no closing force turns it, its corners stick on the pads) is squared
    #: before it is given up (``Pick``): "shift" opens, moves ``squaring_shift_m`` along the pads so
    #: one corner falls beyond a pad's edge, closes (the pad's edge turns the face square), opens,
    #: comes back to the measured centre and closes again; "sweep" opens and sweeps
    #: ``squaring_sweep_m`` along the closing axis, a pad pushing the cube's leading corner as a
    #: flat fence, then closes; "turn" opens, turns the wrist by ``squaring_turn_deg`` about the
    #: TCP's vertical axis and closes, and if the grip is still that wide, opens, turns to minus
    #: that from the first yaw and closes again (the centred close then squares the cube about its
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
    #: Pads of the 2F-85: at an opening of edge - thickness the two pad centres sit on the cube's edges.
    pad_thickness_m: float = 0.008
    pad_width_m: float = 0.022
    push_height_m: float = CUBE_EDGE_M / 2
    #: The pads start this far from the face they push, and back off this far after.
    push_clearance_m: float = 0.010
    #: A push shorter than this along the alternated axis gives way to the other axis.
    min_push_m: float = 0.0002
    #: The line that pushes: slower than the planner's lines, so the cube stops when the pads do.
    push_limits: CartesianLimits = CartesianLimits(velocity_m_s=0.15, acceleration_m_s2=0.5, jerk_m_s3=3.5)
    #: After a motion, the arm gets this long to settle before the next step (the position-controlled
    #: joints lag their setpoints by a fraction of a millimetre at the end of a jerk-limited motion).
    settle_s: float = 0.05
    #: The fingers must stop within this time after an open or close command.
    gripper_timeout_s: float = 2.0

    def __post_init__(self) -> None:
        if self.squaring not in SQUARINGS:
            raise OutOfRangeError(f"squaring {self.squaring!r}: choose one of {', '.join(SQUARINGS)}")
        if not 0.0 < self.squaring_turn_deg < 45.0:
            raise OutOfRangeError(f"squaring turn {self.squaring_turn_deg:g} deg must lie between 0 and 45 deg")
        low, high = GRIPPER_FORCE_RANGE_N
        if not low <= self.grip_force_n <= high:
            raise OutOfRangeError(f"grip force {self.grip_force_n:.1f} N is outside {low:.0f} to {high:.0f} N")
        if not self.cube_edge_m < self.open_width_m <= GRIPPER_MAX_WIDTH_M:
            raise OutOfRangeError(
                f"open width {self.open_width_m * 1000:.1f} mm must exceed the cube's {self.cube_edge_m * 1000:.0f} mm "
                f"and stay within the gripper's {GRIPPER_MAX_WIDTH_M * 1000:.0f} mm"
            )

    @property
    def push_opening_m(self) -> float:
        """Opening for a push: both pads meet the face near its edges (the paper's width - thickness)."""
        return self.cube_edge_m - self.pad_thickness_m

    @property
    def min_threshold_mm(self) -> float:
        """The smallest threshold a push is sure to correct, in millimetres.

        An offset at the threshold may lie diagonally: ``threshold / sqrt(2)`` along each axis.
        Push skips an axis whose offset is below ``min_push_m``, so below ``sqrt(2) * min_push_m``
        an offset over the threshold could leave both axes without a push, and every "correction"
        would leave the cube where it is.
        """
        return math.sqrt(2.0) * self.min_push_m * 1000

    @property
    def push_reach_m(self) -> float:
        """From the cube's centre to the TCP when the pads' leading faces touch the pushed face."""
        return self.cube_edge_m / 2 + self.pad_width_m / 2
