"""Trees as BehaviorTree.CPP v4 XML: a writer with the ``TreeNodesModel`` Groot2 needs, and a safe reader.

An XML tree is data. ``load_xml`` builds a tree only from the nodes in ``REGISTRY`` (the
project's behaviours, and py_trees' composites and decorators under their BehaviorTree.CPP
names); any other tag, a BehaviorTree.CPP script attribute (``_skipIf``, ``_onSuccess`` ...), an
``<Include>`` of another file or a ``<!DOCTYPE>`` is refused with a one-line ``XmlTreeError``
naming the tag and the line. Nothing the file names is imported or evaluated.

py_trees 2.6 ships an experimental reader (``py_trees.parsers.behaviour_tree_xml``) that this
module does not use, because for shared files it does too much and for this project too little:
it resolves every ``PortsMixin`` class imported anywhere (``node_registry="auto"``), reaches every
class of ``py_trees.decorators`` by tag even with an explicit registry, imports a module named in
the file for a port typed ``type`` (``ports_utils.str_to_type``), inlines ``<Include>`` files from
disk, prefixes every node name with its parents' names, and takes only ``PortsMixin`` leaves (the
project's behaviours take their parameters in ``__init__``). It has no writer.

The mapping (``docs/xml.md`` has the whole table):

================================  ======================================================
py_trees                          BehaviorTree.CPP v4
================================  ======================================================
``Sequence(memory=True)``         ``Sequence`` (resumes a RUNNING child, restarts on FAILURE)
``Sequence(memory=False)``        ``ReactiveSequence``
``Selector(memory=True/False)``   ``Fallback`` / ``ReactiveFallback``
``Parallel(SuccessOnAll/One)``    ``Parallel success_count="-1"/"1" failure_count="1"``
``Retry(num_failures=N)``         ``RetryUntilSuccessful num_attempts="N"``
``Repeat(num_success=N)``         ``Repeat num_cycles="N"``
``FailureIsSuccess``              ``ForceSuccess``
``SuccessIsFailure``              ``ForceFailure``
``Inverter``                      ``Inverter``
``Success`` / ``Failure``         ``AlwaysSuccess`` / ``AlwaysFailure``
================================  ======================================================
"""

from __future__ import annotations

import math
import operator
import re
import xml.parsers.expat
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, NoReturn
from xml.sax.saxutils import escape, quoteattr

import py_trees
from py_trees.common import ParallelPolicy

from bt_arrange.behaviours import Detect, GraspGuard, Inspect, MoveHome, Pick, Place, Push
from bt_arrange.behaviours.looking import Recheck
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.errors import BtArrangeError, XmlTreeError
from bt_arrange.geometry import PlanarPose
from bt_arrange.layout import DIRECTIONS, Release
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.trees import Arrangement, Target, validate_targets

FORMAT_VERSION = "4"

#: Attributes BehaviorTree.CPP and Groot2 keep on any node as metadata (never code): ignored.
METADATA_ATTRIBUTES = frozenset({"_description", "_uid", "_fullpath", "_autoremap"})
#: BehaviorTree.CPP attributes whose values are scripts: code, so refused.
SCRIPT_ATTRIBUTES = frozenset(
    {"_skipIf", "_successIf", "_failureIf", "_while", "_onSuccess", "_onFailure", "_onHalted", "_post"}
)


# ----------------------------------------------------------------------------------------------
# Port types: text in the XML <-> Python values
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PortType:
    """A port's type: its name in the ``TreeNodesModel`` and how its text converts."""

    name: str
    parse: Callable[[str], Any]
    format: Callable[[Any], str]


def _parse_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite number")
    return value


def _parse_int(text: str) -> int:
    return int(text.strip())


def _parse_bool(text: str) -> bool:
    lowered = text.strip().lower()
    if lowered in ("true", "1"):
        return True
    if lowered in ("false", "0"):
        return False
    raise ValueError(f"{text!r} is not true or false")


def _format_float(value: float) -> str:
    return repr(float(value))  # the shortest text that reads back as the same float


def _parse_planar_pose(text: str) -> PlanarPose:
    parts = [part.strip() for part in text.split(";")]
    if len(parts) != 3:
        raise ValueError(f"{text!r} is not x_m;y_m;yaw_rad")
    return PlanarPose(*(_parse_float(part) for part in parts))


def _format_planar_pose(pose: PlanarPose) -> str:
    return ";".join(_format_float(v) for v in (pose.x_m, pose.y_m, pose.yaw_rad))


def _parse_object_type(text: str) -> ObjectType:
    """``""`` (the cube) or ``name=x*y*z`` in metres."""
    if not text.strip():
        return CUBE
    name, _, size = text.partition("=")
    parts = size.split("*")
    if len(parts) != 3:
        raise ValueError(f"object type {text!r} is not name=x_m*y_m*z_m")
    x, y, z = (_parse_float(part) for part in parts)
    return ObjectType(name.strip(), (x, y, z))


def _format_object_type(object_type: ObjectType) -> str:
    if object_type == CUBE:
        return ""
    return f"{object_type.name}=" + "*".join(_format_float(v) for v in object_type.size_m)


def _parse_targets(text: str) -> list[Target]:
    targets = []
    for entry in (part.strip() for part in text.split(";")):
        if not entry:
            continue
        fields = [f.strip() for f in entry.split(",")]
        if len(fields) not in (4, 5, 6):
            raise ValueError(f"target {entry!r} is not colour,x_m,y_m,yaw_rad[,name[,type=x_m*y_m*z_m]]")
        colour, x, y, yaw = fields[:4]
        name = fields[4] if len(fields) >= 5 and fields[4] else None
        kind = _parse_object_type(fields[5]) if len(fields) == 6 else CUBE
        targets.append(Target(colour, _parse_float(x), _parse_float(y), _parse_float(yaw), name=name, object_type=kind))
    return targets


def _format_targets(targets: list[Target]) -> str:
    entries = []
    for t in targets:
        fields = [t.colour, _format_float(t.x_m), _format_float(t.y_m), _format_float(t.yaw_rad)]
        named = t.name is not None and t.name != t.colour
        if named or t.object_type != CUBE:
            fields.append(t.name if named and t.name is not None else "")
        if t.object_type != CUBE:
            fields.append(_format_object_type(t.object_type))
        entries.append(",".join(fields))
    return ";".join(entries)


def _parse_poses(text: str) -> tuple[PlanarPose, ...]:
    """Planar poses ``x_m,y_m,yaw_rad`` separated by ``;`` (empty: none)."""
    poses = []
    for entry in (part.strip() for part in text.split(";")):
        if entry:
            poses.append(_parse_planar_pose(entry.replace(",", ";")))
    return tuple(poses)


def _format_poses(poses: tuple[PlanarPose, ...]) -> str:
    return ";".join(_format_planar_pose(p).replace(";", ",") for p in poses)


def _parse_colours(text: str) -> ColourTable:
    """A plan's own colours beside the default table: ``name:rgb:r,g,b`` or ``name:hsv:h0-h1+h2-h3,s0-s1,v0-v1``."""
    table = DEFAULT_COLOUR_TABLE
    for entry in (part.strip() for part in text.split(";")):
        if not entry:
            continue
        name, kind, values = (f.strip() for f in (entry.split(":", 2) + ["", ""])[:3])
        if kind == "rgb":
            r, g, b = (_parse_float(v) for v in values.split(","))
            table = table.with_colour(ColourRange.around_rgb(name, (r, g, b)))
        elif kind == "hsv":
            hues, saturation, value = values.split(",")
            ranges = tuple(tuple(_parse_float(v) for v in h.split("-")) for h in hues.split("+"))
            s0, s1 = (_parse_float(v) for v in saturation.split("-"))
            v0, v1 = (_parse_float(v) for v in value.split("-"))
            table = table.with_colour(ColourRange(name, ranges, (s0, s1), (v0, v1)))  # type: ignore[arg-type]
        else:
            raise ValueError(f"colour {entry!r} is not name:rgb:r,g,b or name:hsv:h0-h1,s0-s1,v0-v1")
    return table


def _format_colours(table: ColourTable) -> str:
    entries = []
    for name, colour in table.items():
        if DEFAULT_COLOUR_TABLE.get(name) == colour:
            continue
        if colour.rgb is not None and ColourRange.around_rgb(name, colour.rgb) == colour:
            entries.append(f"{name}:rgb:" + ",".join(_format_float(v) for v in colour.rgb))
        else:
            hues = "+".join(f"{_format_float(lo)}-{_format_float(hi)}" for lo, hi in colour.hue_ranges_deg)
            (s0, s1), (v0, v1) = colour.saturation_range, colour.value_range
            entries.append(
                f"{name}:hsv:{hues},{_format_float(s0)}-{_format_float(s1)},{_format_float(v0)}-{_format_float(v1)}"
            )
    return ";".join(entries)


def _parse_release(text: str) -> Release | None:
    """``""`` (not among neighbours) or ``axis;opening_m[;offset_x_m;offset_y_m]`` (target frame)."""
    if not text.strip():
        return None
    parts = [part.strip() for part in text.split(";")]
    if len(parts) not in (2, 4):
        raise ValueError(f"{text!r} is not axis;opening_m[;offset_x_m;offset_y_m]")
    axis = parts[0]
    if axis not in ("x", "y"):
        raise ValueError(f"axis {axis!r} is not x or y")
    opening_m = _parse_float(parts[1])
    if opening_m <= 0:
        raise ValueError(f"opening_m {parts[1]!r} is not positive")
    offset_m = (_parse_float(parts[2]), _parse_float(parts[3])) if len(parts) == 4 else (0.0, 0.0)
    return Release(axis, opening_m, offset_m)


def _format_release(release: Release | None) -> str:
    if release is None:
        return ""
    text = f"{release.axis};{_format_float(release.opening_m)}"
    if release.staged:
        text += ";" + ";".join(_format_float(v) for v in release.offset_m)
    return text


def _parse_directions(text: str) -> tuple[str, ...]:
    """Directions of the target's frame, ``+x,-y`` ... (``""``: none)."""
    directions = tuple(part.strip() for part in text.split(",") if part.strip())
    unknown = [d for d in directions if d not in DIRECTIONS]
    if unknown:
        raise ValueError(f"direction {unknown[0]!r} is not one of {', '.join(DIRECTIONS)}")
    return directions


def _format_directions(directions: tuple[str, ...]) -> str:
    return ",".join(directions)


STRING = PortType("std::string", str, str)
DOUBLE = PortType("double", _parse_float, _format_float)
INT = PortType("int", _parse_int, str)
BOOL = PortType("bool", _parse_bool, lambda value: "true" if value else "false")
PLANAR_POSE = PortType("PlanarPose", _parse_planar_pose, _format_planar_pose)
TARGETS = PortType("Targets", _parse_targets, _format_targets)
OBJECT_TYPE = PortType("ObjectType", _parse_object_type, _format_object_type)
POSES = PortType("PlanarPoses", _parse_poses, _format_poses)
COLOURS = PortType("Colours", _parse_colours, _format_colours)
RELEASE = PortType("Release", _parse_release, _format_release)
DIRECTIONS_TYPE = PortType("Directions", _parse_directions, _format_directions)


def _off_if_zero(value: float) -> float | None:
    return None if value == 0 else value


@dataclass(frozen=True)
class Port:
    """An input port: its name, type, default and what it means.

    ``required`` ports have no default. An ``optional`` port (one added after files were written
    without it) is written only when its value is not the default, so those files stay as they were.
    """

    name: str
    type: PortType
    default: Any = None
    description: str = ""
    optional: bool = False

    @property
    def required(self) -> bool:
        """A port without a default must be given (an optional one's default may be ``None``)."""
        return self.default is None and not self.optional


# ----------------------------------------------------------------------------------------------
# The registry of nodes an XML tree may use
# ----------------------------------------------------------------------------------------------

Children = list[py_trees.behaviour.Behaviour]


@dataclass(frozen=True)
class NodeModel:
    """How one XML tag maps to one py_trees class.

    ``build(name, values, children)`` makes the behaviour from its port values; ``ports_of(node)``
    reads them back from a behaviour (the writer); ``matches(node)`` picks between models of one
    class (``Sequence`` with or without memory). ``builtin`` models are BehaviorTree.CPP's own,
    which Groot2 knows, so they are left out of the ``TreeNodesModel``.
    """

    tag: str
    category: str  # Action, Condition, Control or Decorator, as in the TreeNodesModel
    cls: type
    ports: tuple[Port, ...]
    build: Callable[[str, dict[str, Any], Children], py_trees.behaviour.Behaviour]
    ports_of: Callable[[Any], dict[str, Any]] = lambda node: {}
    matches: Callable[[Any], bool] = lambda node: True
    builtin: bool = False
    description: str = ""

    @property
    def children(self) -> str:
        """How many children the node takes: ``none``, ``one`` or ``many``."""
        return {"Action": "none", "Condition": "none", "Decorator": "one"}.get(self.category, "many")


REGISTRY: dict[str, NodeModel] = {}


def register(model: NodeModel) -> NodeModel:
    """Make a node available to XML trees (the reader builds it, the writer writes it)."""
    if model.category not in ("Action", "Condition", "Control", "Decorator"):
        raise XmlTreeError(f"node model {model.tag}: category {model.category!r} is not a BehaviorTree.CPP one")
    REGISTRY[model.tag] = model
    return model


def _only(children: Children) -> py_trees.behaviour.Behaviour:
    return children[0]


_OBJ = Port("obj", STRING, description="the object's name: its blackboard namespace (/<obj>/pose ...)")
_COLOUR = Port("colour", STRING, "", "the colour the camera looks for (empty: the object's name)")
_TYPE = Port("object_type", OBJECT_TYPE, CUBE, "name=x_m*y_m*z_m (empty: the 5 cm cube)")
_KIND = Port("kind_targets", POSES, (), "identical parts: the targets of the kind, x_m,y_m,yaw_rad;... (empty: none)")

register(
    NodeModel(
        "Detect",
        "Action",
        Detect,
        (_OBJ, _COLOUR, _TYPE, _KIND),
        lambda name, v, _: Detect(name, v["obj"], v["colour"] or None, v["object_type"], v["kind_targets"]),
        lambda n: {"obj": n.obj, "colour": n.colour, "object_type": n.object_type, "kind_targets": n.kind_targets},
        description="camera -> /<obj>/pose",
    )
)
register(
    NodeModel(
        "Inspect",
        "Action",
        Inspect,
        (_OBJ, _COLOUR, Port("after_placing", BOOL, False, "also write /<obj>/placed_offset_mm"), _TYPE, _KIND),
        lambda name, v, _: Inspect(
            name,
            v["obj"],
            v["colour"] or None,
            after_placing=v["after_placing"],
            object_type=v["object_type"],
            kind_targets=v["kind_targets"],
        ),
        lambda n: {
            "obj": n.obj,
            "colour": n.colour,
            "after_placing": n.after_placing,
            "object_type": n.object_type,
            "kind_targets": n.kind_targets,
        },
        description="camera -> /<obj>/pose, /<obj>/offset_mm, /<obj>/yaw_error_deg",
    )
)
Builder = Callable[[str, dict[str, Any], Children], py_trees.behaviour.Behaviour]


def _with_memory(cls: type[py_trees.composites.Sequence] | type[py_trees.composites.Selector], memory: bool) -> Builder:
    return lambda name, values, children: cls(name, memory, children)


def _memory_is(memory: bool) -> Callable[[Any], bool]:
    return lambda node: node.memory is memory


def _decorating(cls: Callable[[str, py_trees.behaviour.Behaviour], py_trees.behaviour.Behaviour]) -> Builder:
    return lambda name, values, children: cls(name, _only(children))


def _named(cls: Callable[[str], py_trees.behaviour.Behaviour]) -> Builder:
    return lambda name, values, children: cls(name)


_GRASP = Port(
    "grasp",
    RELEASE,
    None,
    "among neighbours: axis;opening_m[;offset_x_m;offset_y_m], pads across that axis of the target's frame "
    "(empty: the free grasp)",
    optional=True,
)
_RELEASE = Port(
    "release",
    RELEASE,
    None,
    "among neighbours: axis;opening_m[;offset_x_m;offset_y_m], released that far from the target "
    "(empty: at the target, fully open)",
    optional=True,
)
_WHERE = Port("where", STRING, "target", "target, or pick: set down where it was picked", optional=True)
_TOWARDS = Port(
    "towards",
    DIRECTIONS_TYPE,
    tuple(DIRECTIONS),
    "the directions it may be pushed, +x,-y ... of the target's frame (default all four)",
    optional=True,
)
_OPENING = Port(
    "opening_m", DOUBLE, 0.0, "the finger opening for pushing among neighbours [m] (0: default)", optional=True
)

register(
    NodeModel(
        "Pick",
        "Action",
        Pick,
        (_OBJ, _TYPE, _GRASP),
        lambda name, v, _: Pick(name, v["obj"], v["object_type"], grasp=v["grasp"]),
        lambda n: {"obj": n.obj, "object_type": n.object_type, "grasp": n.grasp},
        description="grasp at /<obj>/pose",
    )
)
register(
    NodeModel(
        "Place",
        "Action",
        Place,
        (_OBJ, _TYPE, _RELEASE, _WHERE),
        lambda name, v, _: Place(name, v["obj"], v["object_type"], release=v["release"], where=v["where"]),
        lambda n: {"obj": n.obj, "object_type": n.object_type, "release": n.release, "where": n.where},
        description="release at /<obj>/target",
    )
)


def _push_ports(node: Push) -> dict[str, Any]:
    """The ports of a Push, among neighbours or not."""
    return {
        "obj": node.obj,
        "object_type": node.object_type,
        "yaw_threshold_deg": node.yaw_threshold_deg or 0.0,
        "towards": node.towards,
        "opening_m": node.opening_m or 0.0,
        "strategy": node.strategy,
    }


register(
    NodeModel(
        "Push",
        "Action",
        Push,
        (
            _OBJ,
            _TYPE,
            Port("yaw_threshold_deg", DOUBLE, 0.0, "square the part at this yaw error [deg] (0: never)"),
            _TOWARDS,
            _OPENING,
            Port("strategy", STRING, "paper", "how pushes are chosen: paper, learned or diagonal", optional=True),
        ),
        lambda name, v, _: Push(
            name,
            v["obj"],
            strategy=v["strategy"],
            object_type=v["object_type"],
            yaw_threshold_deg=_off_if_zero(v["yaw_threshold_deg"]),
            towards=v["towards"],
            opening_m=_off_if_zero(v["opening_m"]),
        ),
        _push_ports,
        description="one push",
    )
)
register(
    NodeModel(
        "Recheck",
        "Action",
        Recheck,
        (_OBJ, _COLOUR, Port("after", STRING, "", "the step whose effect is checked"), _TYPE, _KIND),
        lambda name, v, _: Recheck(
            name,
            v["obj"],
            v["colour"] or None,
            after=v["after"],
            object_type=v["object_type"],
            kind_targets=v["kind_targets"],
        ),
        lambda n: {
            "obj": n.obj,
            "colour": n.colour,
            "after": n.after,
            "object_type": n.object_type,
            "kind_targets": n.kind_targets,
        },
        description="camera -> /<obj>/pose, /<obj>/offset_mm, /<obj>/moved_mm: did a neighbour's step move it",
    )
)
register(NodeModel("MoveHome", "Action", MoveHome, (), lambda name, v, _: MoveHome(name), description="park the arm"))
register(
    NodeModel(
        "GraspGuard",
        "Decorator",
        GraspGuard,
        (),
        lambda name, v, children: GraspGuard(name, _only(children)),
        description="fails within a tick when the held cube slips out",
    )
)
register(
    NodeModel(
        # The tag keeps the decorator's former name: XML files written with it stay readable.
        "RetryUntilThreshold",
        "Decorator",
        RepeatUntilWithin,
        (
            Port("offset_key", STRING, description="blackboard key of the offset [mm]"),
            Port("threshold_mm", DOUBLE, description="succeed once the offset is under this [mm]"),
            Port("max_attempts", INT, 10, "corrections before giving up"),
            Port("corrections_key", STRING, "", "blackboard key counting the corrections (empty: none)"),
            Port("yaw_key", STRING, "", "blackboard key of the yaw error [deg] (empty: position only)"),
            Port("yaw_threshold_deg", DOUBLE, 0.0, "succeed once the yaw error is under this too [deg] (0: off)"),
        ),
        lambda name, v, children: RepeatUntilWithin(
            name,
            _only(children),
            offset_key=v["offset_key"],
            threshold_mm=v["threshold_mm"],
            max_attempts=v["max_attempts"],
            corrections_key=v["corrections_key"] or None,
            yaw_key=v["yaw_key"] or None,
            yaw_threshold_deg=_off_if_zero(v["yaw_threshold_deg"]),
        ),
        lambda n: {
            "offset_key": n.offset_key,
            "threshold_mm": n.threshold_mm,
            "max_attempts": n.max_attempts,
            "corrections_key": n.corrections_key or "",
            "yaw_key": n.yaw_key or "",
            "yaw_threshold_deg": n.yaw_threshold_deg or 0.0,
        },
        description="re-run the child until the offset is under the threshold",
    )
)
register(
    NodeModel(
        "Arrangement",
        "Control",
        Arrangement,
        (
            Port("targets", TARGETS, description="colour,x_m,y_m,yaw_rad[,name] per object, separated by ;"),
            Port("threshold_mm", DOUBLE, description="the accuracy threshold the report checks [mm]"),
            Port("yaw_threshold_deg", DOUBLE, 0.0, "the yaw threshold the report checks [deg] (0: position only)"),
            Port("colours", COLOURS, DEFAULT_COLOUR_TABLE, "the plan's own colours: name:rgb:r,g,b;... (empty: none)"),
        ),
        lambda name, v, children: Arrangement(
            name,
            children,
            validate_targets(v["targets"], colours=v["colours"].names),
            v["threshold_mm"],
            yaw_threshold_deg=_off_if_zero(v["yaw_threshold_deg"]),
            colours=v["colours"],
        ),
        lambda n: {
            "targets": n.targets,
            "threshold_mm": n.threshold_mm,
            "yaw_threshold_deg": n.yaw_threshold_deg or 0.0,
            "colours": n.colours,
        },
        description="a sequence with memory that knows its plan (the report and the scene come from it)",
    )
)
register(
    NodeModel(
        "SetBlackboardVariable",
        "Action",
        py_trees.behaviours.SetBlackboardVariable,
        (
            Port("variable_name", STRING, description="absolute blackboard key"),
            Port("variable_value", PLANAR_POSE, description="x_m;y_m;yaw_rad"),
            Port("overwrite", BOOL, True),
        ),
        lambda name, v, _: py_trees.behaviours.SetBlackboardVariable(
            name=name, variable_name=v["variable_name"], variable_value=v["variable_value"], overwrite=v["overwrite"]
        ),
        lambda n: {
            "variable_name": n.variable_name,
            "variable_value": _planar_value(n),
            "overwrite": n.overwrite,
        },
        description="write a planar pose (a target) to the blackboard",
    )
)
register(
    NodeModel(
        "CheckBlackboardVariableExists",
        "Condition",
        py_trees.behaviours.CheckBlackboardVariableExists,
        (Port("variable_name", STRING, description="absolute blackboard key"),),
        lambda name, v, _: py_trees.behaviours.CheckBlackboardVariableExists(
            name=name, variable_name=v["variable_name"]
        ),
        lambda n: {"variable_name": n.variable_name},
    )
)


def _equals_ports(node: py_trees.behaviours.CheckBlackboardVariableValue) -> dict[str, Any]:
    check = node.check
    value = check.value_generator()
    if check.operator is not operator.eq or not isinstance(value, str):
        raise XmlTreeError(
            f"cannot write {node.name!r} as XML: CheckBlackboardVariableValue compares with {check.operator!r} "
            f"and a {type(value).__name__}, and XML trees check a text for equality only"
        )
    return {"variable_name": check.variable, "expected_value": value}


register(
    NodeModel(
        "CheckBlackboardVariableValue",
        "Condition",
        py_trees.behaviours.CheckBlackboardVariableValue,
        (
            Port("variable_name", STRING, description="absolute blackboard key"),
            Port("expected_value", STRING, description="succeed when the variable equals this text"),
        ),
        lambda name, v, _: py_trees.behaviours.CheckBlackboardVariableValue(
            name=name,
            check=py_trees.common.ComparisonExpression(v["variable_name"], v["expected_value"], operator.eq),
        ),
        _equals_ports,
    )
)


def _planar_value(node: py_trees.behaviours.SetBlackboardVariable) -> PlanarPose:
    value = node.variable_value_generator()
    if not isinstance(value, PlanarPose):
        raise XmlTreeError(
            f"cannot write {node.name!r} as XML: SetBlackboardVariable writes a {type(value).__name__}, "
            "and XML trees set planar poses only"
        )
    return value


# BehaviorTree.CPP's own control nodes and decorators, as py_trees classes.
for _tag, _memory in (("Sequence", True), ("ReactiveSequence", False)):
    register(
        NodeModel(
            _tag,
            "Control",
            py_trees.composites.Sequence,
            (),
            _with_memory(py_trees.composites.Sequence, _memory),
            matches=_memory_is(_memory),
            builtin=True,
        )
    )
for _tag, _memory in (("Fallback", True), ("ReactiveFallback", False)):
    register(
        NodeModel(
            _tag,
            "Control",
            py_trees.composites.Selector,
            (),
            _with_memory(py_trees.composites.Selector, _memory),
            matches=_memory_is(_memory),
            builtin=True,
        )
    )


def _parallel(name: str, values: dict[str, Any], children: Children) -> py_trees.behaviour.Behaviour:
    if values["failure_count"] != 1:
        raise ValueError("failure_count must be 1 (a py_trees Parallel fails when any child fails)")
    policy: py_trees.common.ParallelPolicy.Base
    if values["success_count"] == -1:
        policy = ParallelPolicy.SuccessOnAll(synchronise=True)
    elif values["success_count"] == 1:
        policy = ParallelPolicy.SuccessOnOne()
    else:
        raise ValueError("success_count must be -1 (all children) or 1 (one child)")
    return py_trees.composites.Parallel(name, policy, children)


def _parallel_ports(node: py_trees.composites.Parallel) -> dict[str, Any]:
    policy = node.policy
    if isinstance(policy, ParallelPolicy.SuccessOnAll) and policy.synchronise:
        return {"success_count": -1, "failure_count": 1}
    if isinstance(policy, ParallelPolicy.SuccessOnOne):
        return {"success_count": 1, "failure_count": 1}
    raise XmlTreeError(
        f"cannot write Parallel {node.name!r} as XML: only SuccessOnAll(synchronise=True) and SuccessOnOne map "
        "to BehaviorTree.CPP's success_count"
    )


register(
    NodeModel(
        "Parallel",
        "Control",
        py_trees.composites.Parallel,
        (Port("success_count", INT, -1), Port("failure_count", INT, 1)),
        _parallel,
        _parallel_ports,
        builtin=True,
    )
)
register(
    NodeModel(
        "RetryUntilSuccessful",
        "Decorator",
        py_trees.decorators.Retry,
        (Port("num_attempts", INT, description="attempts in all, the first one included"),),
        lambda name, v, children: py_trees.decorators.Retry(name, _only(children), v["num_attempts"]),
        lambda n: {"num_attempts": n.num_failures},
        builtin=True,
    )
)
register(
    NodeModel(
        "Repeat",
        "Decorator",
        py_trees.decorators.Repeat,
        (Port("num_cycles", INT),),
        lambda name, v, children: py_trees.decorators.Repeat(name, _only(children), v["num_cycles"]),
        lambda n: {"num_cycles": n.num_success},
        builtin=True,
    )
)
for _tag, _decorator in (
    ("ForceSuccess", py_trees.decorators.FailureIsSuccess),
    ("ForceFailure", py_trees.decorators.SuccessIsFailure),
    ("Inverter", py_trees.decorators.Inverter),
):
    register(NodeModel(_tag, "Decorator", _decorator, (), _decorating(_decorator), builtin=True))
for _tag, _leaf in (("AlwaysSuccess", py_trees.behaviours.Success), ("AlwaysFailure", py_trees.behaviours.Failure)):
    register(NodeModel(_tag, "Action", _leaf, (), _named(_leaf), builtin=True))


def model_of(node: py_trees.behaviour.Behaviour) -> NodeModel:
    """The registered model that writes ``node`` (its exact class: a subclass is not the same node)."""
    for model in REGISTRY.values():
        if type(node) is model.cls and model.matches(node):
            return model
    raise XmlTreeError(
        f"cannot write {node.name!r} as XML: {type(node).__module__}.{type(node).__qualname__} is not a registered "
        "node (bt_arrange.xmltree.register adds one)"
    )


# ----------------------------------------------------------------------------------------------
# Writing
# ----------------------------------------------------------------------------------------------


def to_xml(root: py_trees.behaviour.Behaviour, tree_id: str = "MainTree", *, comment: str | None = None) -> str:
    """The tree as a BehaviorTree.CPP v4 document, with the ``TreeNodesModel`` of the non-builtin nodes it uses."""
    used: dict[str, NodeModel] = {}
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    if comment:
        lines.append(f"<!-- {comment.replace('--', '- -')} -->")
    lines.append(f'<root BTCPP_format="{FORMAT_VERSION}" main_tree_to_execute={quoteattr(tree_id)}>')
    lines.append(f"  <BehaviorTree ID={quoteattr(tree_id)}>")
    _write_node(root, lines, depth=2, used=used)
    lines.append("  </BehaviorTree>")
    lines.append("  <TreeNodesModel>")
    for tag in sorted(used):
        model = used[tag]
        if model.builtin:
            continue
        lines.append(f"    <{model.category} ID={quoteattr(model.tag)}>")
        for port in model.ports:
            default = "" if port.required else f" default={quoteattr(port.type.format(port.default))}"
            lines.append(
                f"      <input_port name={quoteattr(port.name)} type={quoteattr(port.type.name)}{default}>"
                f"{escape(port.description)}</input_port>"
            )
        if model.description:
            lines.append(
                f"      <MetadataFields><Metadata description={quoteattr(model.description)}/></MetadataFields>"
            )
        lines.append(f"    </{model.category}>")
    lines.append("  </TreeNodesModel>")
    lines.append("</root>")
    return "\n".join(lines) + "\n"


def _write_node(node: py_trees.behaviour.Behaviour, lines: list[str], depth: int, used: dict[str, NodeModel]) -> None:
    model = model_of(node)
    used[model.tag] = model
    values = model.ports_of(node)
    attributes = [f"name={quoteattr(node.name)}"]
    for port in model.ports:
        if port.optional and values[port.name] == port.default:
            continue
        attributes.append(f"{port.name}={quoteattr(port.type.format(values[port.name]))}")
    indent = "  " * depth
    opening = f"{indent}<{model.tag} {' '.join(attributes)}"
    if not node.children:
        lines.append(opening + "/>")
        return
    lines.append(opening + ">")
    for child in node.children:
        _write_node(child, lines, depth + 1, used)
    lines.append(f"{indent}</{model.tag}>")


# ----------------------------------------------------------------------------------------------
# Reading
# ----------------------------------------------------------------------------------------------


@dataclass
class Element:
    """One XML element with the line it starts on (``xml.etree`` keeps no line numbers)."""

    tag: str
    attributes: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)


def parse_elements(text: str, source: str = "<string>") -> Element:
    """Parse XML into ``Element``s with line numbers; a ``<!DOCTYPE>`` (entities) is refused."""
    parser = xml.parsers.expat.ParserCreate()
    stack: list[Element] = []
    top: list[Element] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = Element(tag, dict(attributes), parser.CurrentLineNumber)
        (stack[-1].children if stack else top).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    def doctype(name: str, *args: object) -> None:
        raise XmlTreeError(f"{source} line {parser.CurrentLineNumber}: <!DOCTYPE {name}> is not allowed in an XML tree")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as error:
        raise XmlTreeError(f"{source} line {error.lineno}: not well-formed XML: {_expat_message(error)}") from error
    return top[0]


def _expat_message(error: xml.parsers.expat.ExpatError) -> str:
    return xml.parsers.expat.ErrorString(error.code) if error.code is not None else str(error)


def load_xml(path: str | Path, tree_id: str | None = None) -> py_trees.behaviour.Behaviour:
    """Build the tree of a BehaviorTree.CPP v4 file from registered nodes only."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise XmlTreeError(f"cannot read XML tree {path}: {error.strerror}") from error
    except UnicodeDecodeError as error:
        raise XmlTreeError(f"XML tree {path} is not UTF-8 text") from error
    return from_xml(text, source=str(path), tree_id=tree_id)


def from_xml(text: str, source: str = "<string>", tree_id: str | None = None) -> py_trees.behaviour.Behaviour:
    """Build a tree from BehaviorTree.CPP v4 XML text (see ``load_xml``)."""
    return _Reader(parse_elements(text, source), source).build(tree_id)


class _Reader:
    def __init__(self, document: Element, source: str) -> None:
        self.source = source
        if document.tag != "root":
            self.fail(document, f'the document element is <{document.tag}>, not <root BTCPP_format="4">')
        version = document.attributes.get("BTCPP_format")
        if version != FORMAT_VERSION:
            self.fail(document, f'<root> needs BTCPP_format="4" (BehaviorTree.CPP v4), got {version!r}')
        self.document = document
        self.trees: dict[str, Element] = {}
        for child in document.children:
            if child.tag == "BehaviorTree":
                tree_id = child.attributes.get("ID")
                if not tree_id:
                    self.fail(child, "<BehaviorTree> needs an ID")
                if tree_id in self.trees:
                    self.fail(child, f"a second <BehaviorTree ID={tree_id!r}>")
                self.trees[tree_id] = child
            elif child.tag == "TreeNodesModel":
                continue  # the editor's description of the nodes; the registry decides what they are
            elif child.tag in ("Include", "Import"):
                self.fail(child, f"<{child.tag}> is not supported: an XML tree is one self-contained file")
            else:
                self.fail(child, f"<{child.tag}> is not allowed under <root> (BehaviorTree and TreeNodesModel are)")
        if not self.trees:
            self.fail(document, "no <BehaviorTree ID=...> in the file")

    def fail(self, element: Element, message: str) -> NoReturn:
        raise XmlTreeError(f"{self.source} line {element.line}: {message}")

    def build(self, tree_id: str | None) -> py_trees.behaviour.Behaviour:
        main = tree_id or self.document.attributes.get("main_tree_to_execute")
        if main is None:
            if len(self.trees) > 1:
                self.fail(self.document, "several <BehaviorTree>s and no main_tree_to_execute to choose one")
            main = next(iter(self.trees))
        if main not in self.trees:
            self.fail(
                self.document, f"main tree {main!r} is not one of the <BehaviorTree> IDs: {', '.join(self.trees)}"
            )
        return self._tree(self.trees[main], ())

    def _tree(self, element: Element, entered: tuple[str, ...]) -> py_trees.behaviour.Behaviour:
        if len(element.children) != 1:
            self.fail(element, f"<BehaviorTree ID={element.attributes['ID']!r}> must hold exactly one root node")
        return self._node(element.children[0], entered + (element.attributes["ID"],))

    def _node(self, element: Element, entered: tuple[str, ...]) -> py_trees.behaviour.Behaviour:
        if element.tag == "SubTree":
            return self._subtree(element, entered)
        model = REGISTRY.get(element.tag)
        if model is None:
            self.fail(element, f"<{element.tag}> is not a registered node (known: {', '.join(sorted(REGISTRY))})")
        assert model is not None
        name = element.attributes.get("name") or element.tag
        values = self._values(element, model)
        if model.children == "none" and element.children:
            self.fail(element, f"<{element.tag} name={name!r}> is a leaf and cannot hold children")
        if model.children == "one" and len(element.children) != 1:
            self.fail(
                element, f"<{element.tag} name={name!r}> decorates exactly one child, got {len(element.children)}"
            )
        if model.children == "many" and not element.children:
            self.fail(element, f"<{element.tag} name={name!r}> holds no children")
        children = [self._node(child, entered) for child in element.children]
        try:
            return model.build(name, values, children)
        except BtArrangeError as error:
            raise XmlTreeError(f"{self.source} line {element.line}: <{element.tag} name={name!r}>: {error}") from error
        except (ValueError, TypeError) as error:
            raise XmlTreeError(f"{self.source} line {element.line}: <{element.tag} name={name!r}>: {error}") from error

    def _values(self, element: Element, model: NodeModel) -> dict[str, Any]:
        ports = {port.name: port for port in model.ports}
        values: dict[str, Any] = {}
        for attribute, text in element.attributes.items():
            if attribute == "name" or attribute in METADATA_ATTRIBUTES:
                continue
            if attribute in SCRIPT_ATTRIBUTES:
                self.fail(element, f"<{element.tag}> {attribute}: BehaviorTree.CPP scripts are code and are not run")
            port = ports.get(attribute)
            if port is None:
                known = ", ".join(ports) or "none"
                self.fail(element, f"<{element.tag}> has no port {attribute!r} (its ports: {known})")
            assert port is not None
            if re.fullmatch(r"\s*\{.*\}\s*", text):
                self.fail(
                    element, f"<{element.tag}> {attribute}={text!r}: ports take values, not blackboard references"
                )
            try:
                values[attribute] = port.type.parse(text)
            except (ValueError, TypeError) as error:
                self.fail(element, f"<{element.tag}> {attribute}={text!r} is not a {port.type.name}: {error}")
        for port in model.ports:
            if port.name not in values:
                if port.required:
                    self.fail(element, f"<{element.tag}> needs port {port.name!r} ({port.type.name})")
                values[port.name] = port.default
        return values

    def _subtree(self, element: Element, entered: tuple[str, ...]) -> py_trees.behaviour.Behaviour:
        subtree_id = element.attributes.get("ID", "")
        if subtree_id not in self.trees:
            self.fail(element, f"<SubTree ID={subtree_id!r}> names no <BehaviorTree> of this file")
        if subtree_id in entered:
            self.fail(element, f"<SubTree ID={subtree_id!r}> includes itself")
        extra = set(element.attributes) - {"ID", "name"} - METADATA_ATTRIBUTES
        if extra:
            self.fail(
                element, f"<SubTree ID={subtree_id!r}>: port remapping ({', '.join(sorted(extra))}) is not supported"
            )
        return self._tree(self.trees[subtree_id], entered)


# ----------------------------------------------------------------------------------------------
# An XML file as a tree file: create_root() and create_scene(seed)
# ----------------------------------------------------------------------------------------------


def load_module(path: str | Path) -> ModuleType:
    """An XML tree as a tree-file module: ``create_root()`` builds it, ``create_scene(seed)`` places the cubes.

    The file is read and checked once, here; every ``create_root()`` builds a fresh tree. The scene
    is the one every file of ``trees/`` uses: the plan's cubes scattered by ``seed``, clear of the
    targets, so the XML root must be an ``<Arrangement>`` (its ``targets`` say what to scatter).
    """
    path = Path(path)
    text_root = load_xml(path)  # fails here, before anything runs, on any error of the file
    source = path.read_text(encoding="utf-8")
    module = ModuleType(f"bt_arrange_xml_tree_{path.stem}", f"BehaviorTree.CPP XML tree {path}")
    module.__file__ = str(path)

    def create_root(threshold_mm: float | None = None) -> py_trees.behaviour.Behaviour:
        if threshold_mm is not None:
            raise XmlTreeError(
                f"{path}: an XML tree states its threshold in its ports (threshold_mm of Arrangement and "
                "RetryUntilThreshold): edit them instead of passing --threshold-mm"
            )
        return from_xml(source, source=str(path))

    def create_scene(seed: int = 0) -> list[Any]:
        if not isinstance(text_root, Arrangement):
            raise XmlTreeError(
                f"{path}: the simulator places cubes from the plan of an <Arrangement> root; "
                f"this tree's root is <{model_of(text_root).tag}>"
            )
        from bt_arrange import backends  # the default backend's convention, loaded only to run

        targets = text_root.targets
        return backends.load().scatter(
            [t.colour for t in targets],
            seed,
            avoid=targets,
            object_types=[t.object_type for t in targets],
            names=[t.name for t in targets],
        )

    module.create_root = create_root  # type: ignore[attr-defined]
    module.create_scene = create_scene  # type: ignore[attr-defined]
    return module


def iter_structure(root: py_trees.behaviour.Behaviour) -> Iterator[tuple[int, str, str, dict[str, Any]]]:
    """``(depth, tag, name, port values)`` for every node top-down: what a round trip must keep."""

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> Iterator[tuple[int, str, str, dict[str, Any]]]:
        model = model_of(node)
        yield depth, model.tag, node.name, model.ports_of(node)
        for child in node.children:
            yield from walk(child, depth + 1)

    yield from walk(root, 0)
