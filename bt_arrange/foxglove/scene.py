"""What the recording draws and the JSON topics' schemas: parts as meshes or boxes, targets as outlines.

Every part is a ``bt_arrange.shapes.Prism``: a box (``rectangular``) is a Foxglove cube of its
``size_m``, any other prism a triangle mesh of its top face's convex pieces, its bottom and its
walls. A part's entity is drawn in the part's own frame (``frame_locked``), so it follows the
part's transform on ``/tf``; a target is a faint outline of the top face, fixed in the world.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
from foxglove import Schema
from foxglove.messages import (
    Color,
    CubePrimitive,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    TriangleListPrimitive,
    Vector3,
)

from bt_arrange.geometry import FloatArray

#: The world frame every other frame hangs from.
WORLD_FRAME = "world"
#: The camera's optical frame (OpenCV: x right, y down, z forward).
CAMERA_FRAME = "camera"
#: How opaque a target's outline is: faint, so the part over it stays readable.
TARGET_ALPHA = 0.35


def _schema(name: str, body: dict[str, Any]) -> Schema:
    return Schema(name=name, encoding="jsonschema", data=json.dumps(body).encode("utf-8"))


#: ``/tree``: every node of the tree at a tick that changed one.
TREE_SCHEMA = _schema(
    "bt_arrange.TreeStatus",
    {
        "type": "object",
        "properties": {
            "time_s": {"type": "number", "description": "world time of the tick, seconds"},
            "tree": {"type": "string"},
            "nodes": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "uid": {"type": "integer", "description": "as Groot2 numbers it: 1, 2, ... top-down"},
                        "type": {"type": "string", "description": "the BehaviorTree.CPP type, as the XML names it"},
                        "name": {"type": "string"},
                        "status": {"type": "string", "enum": ["INVALID", "RUNNING", "SUCCESS", "FAILURE"]},
                    },
                    "required": ["uid", "type", "name", "status"],
                },
            },
        },
        "required": ["time_s", "tree", "nodes"],
    },
)

#: ``/report``: the report as ``report.json`` holds it.
REPORT_SCHEMA = _schema("bt_arrange.Report", {"type": "object", "description": "bt_arrange SessionReport.to_dict()"})

#: ``/offsets``: each part's true distance from its target, for the layout's plot.
OFFSETS_SCHEMA = _schema(
    "bt_arrange.Offsets",
    {
        "type": "object",
        "properties": {
            "time_s": {"type": "number"},
            "parts": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {"name": {"type": "string"}, "offset_mm": {"type": "number"}},
                },
            },
        },
    },
)

#: ``/robot_description``: the URDF text, as ROS's ``std_msgs/String`` (which Foxglove's 3-D panel reads).
URDF_SCHEMA = _schema(
    "std_msgs/String", {"type": "object", "properties": {"data": {"type": "string"}}, "required": ["data"]}
)


def colour(rgb: tuple[float, float, float], alpha: float = 1.0) -> Color:
    """A Foxglove colour of an RGB paint (0..1)."""
    return Color(r=float(rgb[0]), g=float(rgb[1]), b=float(rgb[2]), a=alpha)


def pose(position_m: Any = (0.0, 0.0, 0.0), quaternion_xyzw: Any = (0.0, 0.0, 0.0, 1.0)) -> Pose:
    """A Foxglove pose."""
    x, y, z = (float(v) for v in position_m)
    qx, qy, qz, qw = (float(v) for v in quaternion_xyzw)
    return Pose(position=Vector3(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))


def yaw_quaternion(yaw_rad: float) -> tuple[float, float, float, float]:
    """The quaternion (x, y, z, w) of a turn about the world's z axis."""
    return (0.0, 0.0, math.sin(yaw_rad / 2), math.cos(yaw_rad / 2))


def _prism_mesh(shape: Any) -> list[Point3]:
    """Triangles (three points each) of a prism centred on its frame: top and bottom by convex piece, then walls."""
    half = float(shape.height_m) / 2
    points: list[Point3] = []
    for piece in shape.convex_pieces():
        corners = np.asarray(piece, dtype=float)
        for i in range(1, len(corners) - 1):
            for z, order in ((half, (0, i, i + 1)), (-half, (0, i + 1, i))):
                points.extend(Point3(x=float(corners[k][0]), y=float(corners[k][1]), z=z) for k in order)
    outline = np.asarray(shape.outline_m, dtype=float)
    for i in range(len(outline)):
        (x0, y0), (x1, y1) = outline[i], outline[(i + 1) % len(outline)]
        low0, low1 = Point3(x=x0, y=y0, z=-half), Point3(x=x1, y=y1, z=-half)
        high0, high1 = Point3(x=x0, y=y0, z=half), Point3(x=x1, y=y1, z=half)
        points.extend((low0, low1, high1, low0, high1, high0))
    return points


def part_entity(name: str, shape: Any, rgb: tuple[float, float, float]) -> SceneEntity:
    """Part ``name`` drawn in its own frame: a box of its size, or its prism as a mesh, in its paint."""
    paint = colour(rgb)
    if getattr(shape, "rectangular", False):
        x_m, y_m, z_m = (float(v) for v in shape.size_m)
        cube = CubePrimitive(pose=pose(), size=Vector3(x=x_m, y=y_m, z=z_m), color=paint)
        return SceneEntity(frame_id=name, id=f"part/{name}", frame_locked=True, cubes=[cube])
    mesh = TriangleListPrimitive(pose=pose(), points=_prism_mesh(shape), color=paint)
    return SceneEntity(frame_id=name, id=f"part/{name}", frame_locked=True, triangles=[mesh])


def target_entity(
    name: str, shape: Any, rgb: tuple[float, float, float], x_m: float, y_m: float, yaw_rad: float
) -> SceneEntity:
    """Where part ``name`` should be: its top face's outline, faint, on the table and at its height."""
    outline: FloatArray = np.asarray(shape.outline_m, dtype=float)
    height = float(shape.height_m)
    lines = [
        LinePrimitive(
            type=LinePrimitiveLineType.LineLoop,
            pose=pose((x_m, y_m, 0.0), yaw_quaternion(yaw_rad)),
            thickness=2.0,
            scale_invariant=True,
            points=[Point3(x=float(x), y=float(y), z=z) for x, y in outline],
            color=colour(rgb, TARGET_ALPHA),
        )
        for z in (0.0005, height)
    ]
    return SceneEntity(frame_id=WORLD_FRAME, id=f"target/{name}", lines=lines)
