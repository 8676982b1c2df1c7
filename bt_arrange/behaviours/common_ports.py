"""The ports several behaviours declare (in ``provided_ports`` of Detect, Inspect, Recheck, Pick, Place, Push)."""

from __future__ import annotations

from bt_arrange.objects import CUBE
from bt_arrange.ports import DOUBLE, OBJECT_TYPE, POSES, STRING, Port

OBJ = Port("obj", STRING, description="the object's name: its blackboard namespace (/<obj>/pose ...)")
COLOUR = Port("colour", STRING, "", "the colour the camera looks for (empty: the object's name)")
OBJECT_TYPE_PORT = Port(
    "object_type", OBJECT_TYPE, CUBE, "NAME=outline_mm X:Y X:Y X:Y ... height_mm H (empty: the 5 cm cube)"
)
#: Layers (issue 33): the height of the support the part stands on where the node handles it (0: the table).
Z_PORT = Port("z_m", DOUBLE, 0.0, "the part's bottom face above the table there [m] (0: on the table)", optional=True)
KIND_TARGETS = Port(
    "kind_targets", POSES, (), "identical parts: the targets of the kind, x_m,y_m,yaw_rad;... (empty: none)"
)
