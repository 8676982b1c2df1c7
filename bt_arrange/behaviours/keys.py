"""Blackboard keys, one namespace per object: ``/red/pose``, ``/red/offset_mm``, ...

| key | type | written by | read by |
|---|---|---|---|
| ``/<obj>/target`` | ``PlanarPose`` | the tree (``SetBlackboardVariable``) | Place, Inspect, Push |
| ``/<obj>/pose`` | ``Pose`` (part centre, world) | Detect, Inspect | Pick, Push |
| ``/<obj>/offset_mm`` | ``float``, planar distance to the target | Inspect | RetryUntilThreshold |
| ``/<obj>/offset_xy_mm`` | ``(float, float)``, target minus pose in the target's frame | Inspect | Push |
| ``/<obj>/placed_offset_mm`` | ``float``, the first inspection after placing | Inspect(after placing) | reports |
| ``/<obj>/corrections`` | ``int``, pushes made by the correction loop | RetryUntilThreshold | reports |
| ``/<obj>/yaw_error_deg`` | ``float``, measured minus target yaw (folded) | Inspect | RepeatUntilWithin, Push |
| ``/<obj>/placed_yaw_error_deg`` | ``float``, the yaw error after placing | Inspect(after placing) | reports |
| ``/<obj>/push_axis`` | ``"x"`` or ``"y"``, the axis of the next push | Push | Push |
| ``/<obj>/blocked_towards`` | ``"+x"`` ..., a push a neighbour blocks | Push | the tree's restaging |
| ``/<obj>/moved_mm`` | ``float``, how far it moved since it was last looked at | Recheck | reports |
| ``/<obj>/max_moved_mm`` | ``float``, the most later steps moved it (camera) | Recheck | reports |
| ``/<obj>/push_bias_mm`` | ``(float, float)``, where pushes land beyond their aim ("learned") | Push | Push |
| ``/<obj>/last_push`` | ``(axis, aim_mm)``, the last push's axis and aimed landing (strategy "learned") | Push | Push |
| ``/<obj>/grasp_half_turn`` | ``bool``, the gripper holds it half a turn round (issue 36) | Pick | Place |
| ``/<obj>/top_height_error_mm`` | ``float``, raised top face (depth) minus planned height | CheckStanding | reports |
| ``/<obj>/tilt_deg`` | ``float``, the tilt of a raised part's top face from depth | CheckStanding | reports |
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
PLACED_YAW_ERROR_DEG = "placed_yaw_error_deg"
BLOCKED_TOWARDS = "blocked_towards"
MOVED_MM = "moved_mm"
MAX_MOVED_MM = "max_moved_mm"
PUSH_BIAS_MM = "push_bias_mm"
LAST_PUSH = "last_push"
#: Issue 36: Pick takes a part without half-turn symmetry with the gripper turned half a turn when
#: that turns the last wrist joint less over the pick, the carry and the look after it.
GRASP_HALF_TURN = "grasp_half_turn"
#: Layers (issue 33): written by ``CheckStanding``.
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
