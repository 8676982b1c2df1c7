"""Blackboard keys, one namespace per object: ``/red/pose``, ``/red/offset_mm``, ...

A key is never typed: ``keys.pose("red")`` is ``"/red/pose"``, ``keys.offset_mm("red")`` is
``"/red/offset_mm"``, one function per key below (``key(obj, FIELD)`` builds any of them from its
field constant).

- ``/<obj>/target``, ``PlanarPose``: where the part goes (world). Written by the tree's target setter
  (``SetBlackboardVariable``), before the part's first step; read by Place, Inspect, Push; Pick and Detect among
  identical parts.
- ``/<obj>/pose``, ``Pose``: the part's centre as last measured (world). Written by Detect, Inspect and Recheck,
  each time the camera finds the part (EstimateGraspFromDepth from depth); read by Pick, Push, CheckStanding.
- ``/<obj>/offset_mm``, ``float``: the planar distance from the measured centre to the target (mm). Written by
  Inspect, each time it finds the part; read by RepeatUntilWithin.
- ``/<obj>/offset_xy_mm``, ``(float, float)``: target minus measured centre, in the target's frame (mm). Written by
  Inspect, each time it finds the part; read by Push.
- ``/<obj>/yaw_error_deg``, ``float``: measured minus target yaw, folded to the part's symmetry. Written by Inspect,
  each time it finds the part; read by RepeatUntilWithin, Push.
- ``/<obj>/measured_on``, ``"whole face"``, ``"free edges"`` when the part's face merged with a neighbour's of its
  colour, or ``"not measured"`` when the last look did not find it. Written by Inspect, at each look; read by
  RepeatUntilWithin, the report (only a whole face confirms "within": else the part is reported unconfirmed).
- ``/<obj>/placed_offset_mm``, ``float``: the offset at the first look after placing. Written by
  ``Inspect(after_placing=True)``, once after Place; read by the report, and the trees (its existence says the part
  was placed).
- ``/<obj>/placed_yaw_error_deg``, ``float``: the yaw error at that look. Written by
  ``Inspect(after_placing=True)``, once after Place; read by the report.
- ``/<obj>/corrections``, ``int``: the pushes the correction loop has made. Written by RepeatUntilWithin, 0 as it
  starts, then after each correction; read by the report.
- ``/<obj>/pushes_stalled``, ``"no"``, or ``"stalled"`` once the pushes stopped converging. Written by
  ``RepeatUntilWithin(stall_after=N)``, as it starts and as it gives up; read by the tree (a regrasp).
- ``/<obj>/push_axis``, ``"x"`` or ``"y"``: the axis of the *next* push, not of the last one. Written by Push, as it
  starts a push along the other axis; read by Push (the axes alternate).
- ``/<obj>/blocked_towards``, ``"+x"`` ...: the push needed, which a neighbour blocks, or ``"none"`` when the last
  push was free. Written by Push, as it chooses its push; read by the tree's restaging and by
  ``RepeatUntilWithin(release_again=True)`` (a correction that released the part again).
- ``/<obj>/blocked_by``, the neighbour that blocks that push (``"red"``), or ``"none"``. Written by Push, as it
  chooses its push; read by RepeatUntilWithin (its last word names the neighbour), and by the tree, which moves
  that neighbour aside when the layout found it alone in the way.
- ``/<obj>/release_again``, ``"allowed"``, or why the part may not be released again past its place for a blocked
  push (no correction left to push it back; the last time did not bring it closer). Written by
  ``RepeatUntilWithin(release_again=True)``, before each correction; read by the tree's restaging.
- ``/<obj>/push_bias_mm``, ``(float, float)``: where pushes land beyond their aim. Written by Push with strategy
  learned or diagonal, as it starts a push; read by Push.
- ``/<obj>/last_push``, ``(axis, aim_mm)``: that push's axis and aimed landing. Written by Push with strategy
  learned or diagonal, as it starts a push; read by Push.
- ``/<obj>/moved_mm``, ``float``: how far the part moved since it was last looked at (camera). Written by Recheck,
  when it finds the part again; read by the report.
- ``/<obj>/max_moved_mm``, ``float``: the most later steps moved it. Written by Recheck, when it finds the part
  again; read by the report.
- ``/<obj>/touching``, ``"touching parts"`` when the look before the pick failed on parts of the colour that touch
  (a blob no face explains, the part in a blob it shares, a neighbour beside it), else ``"no"``. Written by
  ``Detect(alone=True)``, at each look; read by the tree (``Separate`` runs only then).
- ``/<obj>/grasp_half_turn``, ``bool``: the gripper holds the part half a turn round. Written by Pick, as it starts
  (when it chooses the grasp); read by Place.
- ``/<obj>/held_look``, ``"held look"`` (among neighbours, an irregular part measured in the fingers) or
  ``"set down"`` (set down where it was picked and picked again centred). Written by LookAtHeld, each time it
  starts (``"set down"``) and when its measurement is trusted; read by the report.
- ``/<obj>/held_correction``, ``PlanarPose`` or None: the placing's TCP correction (TCP frame) from the part
  measured in the fingers. Written by LookAtHeld, each time it starts (None) and when it measures; read by
  ``Place(held=True)``.
- ``/<obj>/top_height_error_mm``, ``float``: a raised part's top face (depth) minus its planned height (mm). Written
  by CheckStanding, when it measures; read by the report.
- ``/<obj>/tilt_deg``, ``float``: the tilt of a raised part's top face (depth). Written by CheckStanding, when it
  measures; read by the report.

One key is not a part's: ``/camera/margin_mm`` (``bt_arrange.uncertainty.CAMERA_MARGIN_KEY``), the
camera's own error, written by the session before the first tick and read by RepeatUntilWithin.
"""

from __future__ import annotations

#: Who writes ``/<obj>/target``, as the messages name it.
TARGET_SETTER = "the tree's target setter (a SetBlackboardVariable, bt_arrange.trees.steps.set_target)"

TARGET = "target"
POSE = "pose"
OFFSET_MM = "offset_mm"
OFFSET_XY_MM = "offset_xy_mm"
PLACED_OFFSET_MM = "placed_offset_mm"
CORRECTIONS = "corrections"
#: ``STALLED`` once the object's correction ended because its pushes stopped converging
#: (``RepeatUntilWithin.stall_after``), else ``"no"``: a text, as XML trees compare them.
PUSHES_STALLED = "pushes_stalled"
STALLED = "stalled"
PUSH_AXIS = "push_axis"
YAW_ERROR_DEG = "yaw_error_deg"
#: What the last look measured the part on: ``WHOLE_FACE``, or ``FREE_EDGES`` when its face merged
#: with a neighbour's of its colour (``Detection.merged``): such a look steers a push but cannot
#: confirm "within" (the part is then reported ``unconfirmed``).
MEASURED_ON = "measured_on"
WHOLE_FACE = "whole face"
FREE_EDGES = "free edges"
#: The last look did not find the part: its last offset is stale.
NOT_MEASURED = "not measured"
PLACED_YAW_ERROR_DEG = "placed_yaw_error_deg"
BLOCKED_TOWARDS = "blocked_towards"
#: ``/<obj>/blocked_towards`` (and ``/<obj>/blocked_by``) after a free push.
NOT_BLOCKED = "none"
BLOCKED_BY = "blocked_by"
#: ``ALLOWED``, or why the part may not be released again past its place (a text, as XML trees compare them).
RELEASE_AGAIN = "release_again"
ALLOWED = "allowed"
#: ``TOUCHING_PARTS`` when the look before the pick failed on touching parts of the colour, else ``"no"``:
#: a text, as XML trees compare them.
TOUCHING = "touching"
TOUCHING_PARTS = "touching parts"
MOVED_MM = "moved_mm"
MAX_MOVED_MM = "max_moved_mm"
PUSH_BIAS_MM = "push_bias_mm"
LAST_PUSH = "last_push"
#: Pick takes a part without half-turn symmetry with the gripper turned half a turn when that
#: turns the last wrist joint less over the pick, the carry and the look after it.
GRASP_HALF_TURN = "grasp_half_turn"
#: Among neighbours, how the part's place in the pads was known before its placing: ``HELD_LOOK`` (measured
#: in the fingers by ``LookAtHeld``) or ``SET_DOWN`` (set down where it was picked and picked again centred).
HELD_LOOK = "held_look"
LOOKED_IN_FINGERS = "held look"
SET_DOWN = "set down"
#: ``LookAtHeld``'s correction for Place: the planned TCP pose to the TCP pose that puts the part where the
#: plan expects it (a ``PlanarPose`` in the TCP's frame), or None when the part was not measured in the fingers.
HELD_CORRECTION = "held_correction"
#: A raised part's top face, measured by ``CheckStanding``.
TOP_HEIGHT_ERROR_MM = "top_height_error_mm"
TILT_DEG = "tilt_deg"


def key(obj: str, field: str) -> str:
    """The absolute blackboard key of ``field`` for object ``obj``."""
    return f"/{obj}/{field}"


def object_of_key(absolute_key: str) -> str | None:
    """The object of a key built by ``key`` (``/red/offset_mm`` -> ``red``), or None for another key."""
    parts = absolute_key.split("/")
    if len(parts) == 3 and parts[0] == "" and parts[1] and parts[2]:
        return parts[1]
    return None


# -- a part's keys: ``pose("red") == "/red/pose"``, one function per field above ------------------


def target(obj: str) -> str:
    """``/<obj>/target``: where the part goes, set by the tree before the part's first step."""
    return key(obj, TARGET)


def pose(obj: str) -> str:
    """``/<obj>/pose``: the part's centre as last measured (Detect, Inspect, Recheck)."""
    return key(obj, POSE)


def offset_mm(obj: str) -> str:
    """``/<obj>/offset_mm``: the planar distance to the target, written by Inspect each time it finds the part."""
    return key(obj, OFFSET_MM)


def offset_xy_mm(obj: str) -> str:
    """``/<obj>/offset_xy_mm``: target minus measured centre in the target's frame (Inspect)."""
    return key(obj, OFFSET_XY_MM)


def yaw_error_deg(obj: str) -> str:
    """``/<obj>/yaw_error_deg``: measured minus target yaw, folded to the part's symmetry (Inspect)."""
    return key(obj, YAW_ERROR_DEG)


def measured_on(obj: str) -> str:
    """``/<obj>/measured_on``: what the last look measured the part on, ``"whole face"`` or ``"free edges"``."""
    return key(obj, MEASURED_ON)


def placed_offset_mm(obj: str) -> str:
    """``/<obj>/placed_offset_mm``: the offset at the first look after placing (Inspect(after_placing=True))."""
    return key(obj, PLACED_OFFSET_MM)


def placed_yaw_error_deg(obj: str) -> str:
    """``/<obj>/placed_yaw_error_deg``: the yaw error at the first look after placing."""
    return key(obj, PLACED_YAW_ERROR_DEG)


def corrections(obj: str) -> str:
    """``/<obj>/corrections``: the pushes the correction loop has made (RepeatUntilWithin)."""
    return key(obj, CORRECTIONS)


def pushes_stalled(obj: str) -> str:
    """``/<obj>/pushes_stalled``: ``"stalled"`` once the correction gave up on pushes that stopped converging."""
    return key(obj, PUSHES_STALLED)


def push_axis(obj: str) -> str:
    """``/<obj>/push_axis``: the axis of the *next* push; Push writes it as it starts a push along the other."""
    return key(obj, PUSH_AXIS)


def blocked_towards(obj: str) -> str:
    """``/<obj>/blocked_towards``: the push needed (``"+x"`` ...) that a neighbour blocks, written as Push fails."""
    return key(obj, BLOCKED_TOWARDS)


def blocked_by(obj: str) -> str:
    """``/<obj>/blocked_by``: the neighbour that blocks the push needed (``"red"``), or ``"none"``, written by Push."""
    return key(obj, BLOCKED_BY)


def release_again(obj: str) -> str:
    """``/<obj>/release_again``: ``"allowed"``, or why the part may not be released again past its place."""
    return key(obj, RELEASE_AGAIN)


def touching(obj: str) -> str:
    """``/<obj>/touching``: ``"touching parts"`` when the look before the pick failed on touching parts, or ``"no"``."""
    return key(obj, TOUCHING)


def push_bias_mm(obj: str) -> str:
    """``/<obj>/push_bias_mm``: where pushes land beyond their aim (Push, strategies learned and diagonal)."""
    return key(obj, PUSH_BIAS_MM)


def last_push(obj: str) -> str:
    """``/<obj>/last_push``: the last push's axis and aimed landing (Push, strategies learned and diagonal)."""
    return key(obj, LAST_PUSH)


def moved_mm(obj: str) -> str:
    """``/<obj>/moved_mm``: how far the part moved since it was last looked at (Recheck)."""
    return key(obj, MOVED_MM)


def max_moved_mm(obj: str) -> str:
    """``/<obj>/max_moved_mm``: the most later steps moved the part (Recheck)."""
    return key(obj, MAX_MOVED_MM)


def grasp_half_turn(obj: str) -> str:
    """``/<obj>/grasp_half_turn``: the gripper holds the part half a turn round (Pick, for Place)."""
    return key(obj, GRASP_HALF_TURN)


def held_look(obj: str) -> str:
    """``/<obj>/held_look``: ``"held look"`` (measured in the fingers) or ``"set down"`` before its placing."""
    return key(obj, HELD_LOOK)


def held_correction(obj: str) -> str:
    """``/<obj>/held_correction``: LookAtHeld's correction of the placing's TCP pose (TCP frame), or None."""
    return key(obj, HELD_CORRECTION)


def top_height_error_mm(obj: str) -> str:
    """``/<obj>/top_height_error_mm``: a raised part's top face minus its planned height (CheckStanding)."""
    return key(obj, TOP_HEIGHT_ERROR_MM)


def tilt_deg(obj: str) -> str:
    """``/<obj>/tilt_deg``: the tilt of a raised part's top face (CheckStanding)."""
    return key(obj, TILT_DEG)
