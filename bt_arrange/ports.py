"""Node ports, as BehaviorTree.CPP declares them: a ``Port`` (name, type, default, description) and its types.

A node declares its own ports on its class, as BehaviorTree.CPP's ``static PortsList
providedPorts()`` does::

    class Pick(StagedBehaviour):
        @classmethod
        def provided_ports(cls) -> tuple[Port, ...]:
            return (OBJ, OBJECT_TYPE_PORT, Port("grasp", RELEASE, None, "among neighbours: ...", optional=True))

A ``PortType`` is a port's type name in the ``TreeNodesModel`` and its codec: how a value is
written as text and read back. Reading a bad text raises ``PortValueError`` (one of the project's
errors) naming the type and the text; the XML reader adds the node, the port and the line.

This module sits low, beside the value types it converts (poses, part types, releases, colours):
the behaviours import it, and the XML writer and reader (``bt_arrange.xmltree``) import the
behaviours, never the other way round.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from bt_arrange.errors import BtArrangeError, PortValueError
from bt_arrange.geometry import PlanarPose
from bt_arrange.layout import DIRECTIONS, Release
from bt_arrange.objects import DEFAULT_TYPE, ObjectType, PartOnTable
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.shapes import Cuboid


@dataclass(frozen=True)
class PortType:
    """A port's type: its name in the ``TreeNodesModel`` and how its value converts to and from text."""

    name: str
    from_text: Callable[[str], Any]
    to_text: Callable[[Any], str]

    def parse(self, text: str) -> Any:
        """The value of ``text``; a text that is not one is a ``PortValueError`` naming the type and the text."""
        try:
            return self.from_text(text)
        except PortValueError:
            raise
        except (ValueError, TypeError, KeyError, IndexError, BtArrangeError) as error:
            reason = str(error.args[0] if isinstance(error, KeyError) and error.args else error)
            raise PortValueError(
                f"{text!r} is not a {self.name}: {reason}", reason=reason, field=self.name, value=text
            ) from error

    def format(self, value: Any) -> str:
        """The text of ``value``; a value that is not one is a ``PortValueError`` naming the type and the value."""
        try:
            return self.to_text(value)
        except (ValueError, TypeError, AttributeError) as error:
            raise PortValueError(
                f"{value!r} is not a {self.name}: {error}", reason=str(error), field=self.name, value=value
            ) from error


class _Required:
    """The default of a port that has none: the file must give it."""

    def __repr__(self) -> str:
        return "REQUIRED"


#: A port's default when it has none (``Port.required``).
REQUIRED: Any = _Required()


@dataclass(frozen=True)
class Port:
    """An input port: its name, type, default and what it means.

    A port without a default (``REQUIRED``) must be given. An ``optional`` port (one added after
    files were written without it) is written only when its text is not the default's, so those
    files stay as they were.
    """

    name: str
    type: PortType
    default: Any = REQUIRED
    description: str = ""
    optional: bool = False

    @property
    def required(self) -> bool:
        """A port without a default must be given."""
        return self.default is REQUIRED


# ----------------------------------------------------------------------------------------------
# The codecs: text <-> Python values
# ----------------------------------------------------------------------------------------------


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
    """``""`` (the default type, the cube) or ``name=x*y*z`` in metres."""
    if not text.strip():
        return DEFAULT_TYPE
    name, _, size = text.partition("=")
    parts = size.split("*")
    if len(parts) != 3:
        raise ValueError(f"object type {text!r} is not name=x_m*y_m*z_m")
    x, y, z = (_parse_float(part) for part in parts)
    return ObjectType(name.strip(), (x, y, z))


def _format_object_type(object_type: ObjectType) -> str:
    if object_type == DEFAULT_TYPE:
        return ""
    if not isinstance(object_type.shape, Cuboid):
        raise ValueError(
            f"object type {object_type.name!r} is a {object_type.shape.describe()}: XML trees describe cuboids "
            "(name=x_m*y_m*z_m) only; run its plan file instead"
        )
    return f"{object_type.name}=" + "*".join(_format_float(v) for v in object_type.size_m)


def _parse_targets(text: str, make: Callable[..., PartOnTable]) -> list[Any]:
    targets = []
    for entry in (part.strip() for part in text.split(";")):
        if not entry:
            continue
        fields = [f.strip() for f in entry.split(",")]
        if len(fields) not in (4, 5, 6):
            raise ValueError(f"target {entry!r} is not colour,x_m,y_m,yaw_rad[,name[,type=x_m*y_m*z_m]]")
        colour, x, y, yaw = fields[:4]
        name = fields[4] if len(fields) >= 5 and fields[4] else None
        kind = _parse_object_type(fields[5]) if len(fields) == 6 else DEFAULT_TYPE
        targets.append(make(colour, _parse_float(x), _parse_float(y), _parse_float(yaw), name=name, object_type=kind))
    return targets


def _format_targets(targets: list[PartOnTable]) -> str:
    entries = []
    for t in targets:
        fields = [t.colour, _format_float(t.x_m), _format_float(t.y_m), _format_float(t.yaw_rad)]
        named = t.name is not None and t.name != t.colour
        if named or t.object_type != DEFAULT_TYPE:
            fields.append(t.name if named and t.name is not None else "")
        if t.object_type != DEFAULT_TYPE:
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


def _parse_off_float(text: str) -> float | None:
    value = _parse_float(text)
    return None if value == 0 else value


def _format_off_float(value: float | None) -> str:
    return _format_float(value or 0.0)


def targets_type(make: Callable[..., PartOnTable]) -> PortType:
    """The ``Targets`` type, read into ``make(colour, x_m, y_m, yaw_rad, name=, object_type=)`` (the plan's class)."""
    return PortType("Targets", lambda text: _parse_targets(text, make), _format_targets)


STRING = PortType("std::string", str, str)
#: A text whose empty value means "none" (``None`` in Python).
OFF_STRING = PortType("std::string", lambda text: text or None, lambda value: value or "")
DOUBLE = PortType("double", _parse_float, _format_float)
#: A number whose zero means "off" (``None`` in Python).
OFF_DOUBLE = PortType("double", _parse_off_float, _format_off_float)
INT = PortType("int", _parse_int, str)
BOOL = PortType("bool", _parse_bool, lambda value: "true" if value else "false")
PLANAR_POSE = PortType("PlanarPose", _parse_planar_pose, _format_planar_pose)
OBJECT_TYPE = PortType("ObjectType", _parse_object_type, _format_object_type)
POSES = PortType("PlanarPoses", _parse_poses, _format_poses)
COLOURS = PortType("Colours", _parse_colours, _format_colours)
RELEASE = PortType("Release", _parse_release, _format_release)
DIRECTIONS_TYPE = PortType("Directions", _parse_directions, _format_directions)
