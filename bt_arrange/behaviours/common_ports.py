"""The ports several behaviours declare (in ``provided_ports`` of Detect, Inspect, Recheck, Pick, Place, Push)."""

from __future__ import annotations

from bt_arrange.behaviours import keys
from bt_arrange.objects import CUBE
from bt_arrange.ports import DOUBLE, INOUT, INPUT, OBJECT_TYPE, OUTPUT, POSES, STRING, Port, entry_port

OBJ = Port("obj", STRING, description="the object's name: its blackboard namespace (/<obj>/pose ...)")
COLOUR = Port("colour", STRING, "", "the colour the camera looks for (empty: the object's name)")
OBJECT_TYPE_PORT = Port(
    "object_type", OBJECT_TYPE, CUBE, "NAME=outline_mm X:Y X:Y X:Y ... height_mm H (empty: the 5 cm cube)"
)
#: Layers: the height of the support the part stands on where the node handles it (0: the table).
Z_PORT = Port("z_m", DOUBLE, 0.0, "the part's bottom face above the table there [m] (0: on the table)", optional=True)
KIND_TARGETS = Port(
    "kind_targets", POSES, (), "identical parts: the targets of the kind, x_m,y_m,yaw_rad;... (empty: none)"
)

#: What each blackboard entry of an object holds, for the entry ports' descriptions (``bt_arrange.behaviours.keys``).
_ENTRY_MEANINGS = {
    keys.TARGET: "the target, a PlanarPose",
    keys.POSE: "the measured pose",
    keys.OFFSET_MM: "the planar distance to the target [mm]",
    keys.OFFSET_XY_MM: "target minus pose in the target's frame [mm]",
    keys.YAW_ERROR_DEG: "measured minus target yaw [deg]",
    keys.MEASURED_ON: "what the last look measured it on: whole face, or free edges (cannot confirm within)",
    keys.PLACED_OFFSET_MM: "the offset after placing [mm]",
    keys.PLACED_YAW_ERROR_DEG: "the yaw error after placing [deg]",
    keys.GRASP_HALF_TURN: "the gripper holds it half a turn round",
    keys.PUSH_AXIS: "the axis of the next push",
    keys.BLOCKED_TOWARDS: "a push a neighbour blocks (none: the last push was free)",
    keys.BLOCKED_BY: "the neighbour that blocks that push (none: the last push was free)",
    keys.TOUCHING: "the look before the pick failed on touching parts of the colour",
    keys.PUSH_BIAS_MM: "where pushes land beyond their aim [mm]",
    keys.LAST_PUSH: "the last push's axis and aimed landing",
    keys.MOVED_MM: "how far it moved since it was last looked at [mm]",
    keys.MAX_MOVED_MM: "the most later steps moved it [mm]",
    keys.TOP_HEIGHT_ERROR_MM: "raised top face minus planned height [mm]",
    keys.TILT_DEG: "the tilt of a raised part's top face [deg]",
    keys.HELD_CORRECTION: "the placing's TCP correction from the part measured in the fingers (TCP frame)",
    keys.HELD_LOOK: "held look (measured in the fingers) or set down, before its placing",
}


def entries(
    inputs: tuple[str, ...] = (), outputs: tuple[str, ...] = (), inouts: tuple[str, ...] = ()
) -> tuple[Port, ...]:
    """The blackboard entries a node reads (``inputs``), writes (``outputs``) or both, as its entry ports.

    Each defaults to the object's own entry (``{pose}``: ``/<obj>/pose``, as ``keys.key`` builds it);
    an XML tree remaps it (``pose="{/elsewhere/pose}"``).
    """
    ports = [entry_port(f, INPUT, _ENTRY_MEANINGS[f]) for f in inputs]
    ports += [entry_port(f, OUTPUT, _ENTRY_MEANINGS[f]) for f in outputs]
    ports += [entry_port(f, INOUT, _ENTRY_MEANINGS[f]) for f in inouts]
    return tuple(ports)


#: Detect's entries: it writes the pose, and reads the target when it chooses among identical parts.
DETECT_ENTRIES = entries((keys.TARGET,), (keys.POSE,))
#: Inspect's: Detect's, and the offsets and yaw errors it measures.
INSPECT_ENTRIES = entries(
    (keys.TARGET,),
    (
        keys.POSE,
        keys.OFFSET_MM,
        keys.OFFSET_XY_MM,
        keys.YAW_ERROR_DEG,
        keys.MEASURED_ON,
        keys.PLACED_OFFSET_MM,
        keys.PLACED_YAW_ERROR_DEG,
    ),
)
