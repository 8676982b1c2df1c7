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

import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from typing import Any

import numpy as np

from bt_arrange.errors import BtArrangeError, PlanError, PortValueError
from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import DEFAULT_TYPE, ObjectType, PartOnTable
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.plan.layout import DIRECTIONS, Release
from bt_arrange.shapes import Prism
from bt_arrange.shapes.prism import push_heading_rad


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


#: A port's directions, as the ``TreeNodesModel`` names them (``input_port`` ...).
INPUT, OUTPUT, INOUT = "input", "output", "inout"


@dataclass(frozen=True)
class Port:
    """A port: its name, type, default, what it means and its direction (``input``, ``output``, ``inout``).

    A port without a default (``REQUIRED``) must be given. An ``optional`` port (one added after
    files were written without it) is written only when its text is not the default's, so those
    files stay as they were.

    A port of type ``ENTRY`` is a blackboard entry the node reads or writes, named by the port
    (``pose``, ``offset_mm``): its default, ``{pose}``, is the entry of the node's object
    (``/<obj>/pose``); an XML author remaps it (``pose="{/elsewhere/pose}"``), and a ``SubTree``
    remaps the entries of its part.
    """

    name: str
    type: PortType
    default: Any = REQUIRED
    description: str = ""
    optional: bool = False
    direction: str = INPUT

    @property
    def entry(self) -> bool:
        """A blackboard entry of the node's object (``ENTRY``), not a value the node is built with."""
        return self.type is ENTRY

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


def _parse_targets(text: str, make: Callable[..., PartOnTable]) -> list[Any]:
    targets = []
    for entry in (part.strip() for part in text.split(";")):
        if not entry:
            continue
        fields = [f.strip() for f in entry.split(",")]
        if len(fields) not in (4, 5, 6, 7):
            raise ValueError(f"target {entry!r} is not colour,x_m,y_m,yaw_rad[,name[,object type[,z_m]]]")
        colour, x, y, yaw = fields[:4]
        name = fields[4] if len(fields) >= 5 and fields[4] else None
        kind = _parse_object_type(fields[5]) if len(fields) >= 6 else DEFAULT_TYPE
        # A raised target's height: only a target has one, and only when not on the table.
        raised = {"z_m": _parse_float(fields[6])} if len(fields) == 7 and _parse_float(fields[6]) != 0.0 else {}
        targets.append(
            make(colour, _parse_float(x), _parse_float(y), _parse_float(yaw), name=name, object_type=kind, **raised)
        )
    return targets


def _format_targets(targets: list[PartOnTable]) -> str:
    entries = []
    for t in targets:
        fields = [t.colour, _format_float(t.x_m), _format_float(t.y_m), _format_float(t.yaw_rad)]
        named = t.name is not None and t.name != t.colour
        z_m = float(getattr(t, "z_m", 0.0))
        if named or t.object_type != DEFAULT_TYPE or z_m:
            fields.append(t.name if named and t.name is not None else "")
        if t.object_type != DEFAULT_TYPE or z_m:
            fields.append(_format_object_type(t.object_type))
        if z_m:
            fields.append(_format_float(z_m))
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
    """``""`` (not among neighbours) or ``axis;opening_m[;offset_x_m;offset_y_m[;centre_x_m;centre_y_m]]``.

    In the target's frame; the centre is where the pads stand from the part's origin (an irregular
    part's grasp off its centroid), none for a box.
    """
    if not text.strip():
        return None
    parts = [part.strip() for part in text.split(";")]
    if len(parts) not in (2, 4, 6):
        raise ValueError(f"{text!r} is not axis;opening_m[;offset_x_m;offset_y_m[;centre_x_m;centre_y_m]]")
    axis = parts[0]
    if axis not in ("x", "y"):
        raise ValueError(f"axis {axis!r} is not x or y")
    opening_m = _parse_float(parts[1])
    if opening_m <= 0:
        raise ValueError(f"opening_m {parts[1]!r} is not positive")
    offset_m = (_parse_float(parts[2]), _parse_float(parts[3])) if len(parts) >= 4 else (0.0, 0.0)
    centre_m = (_parse_float(parts[4]), _parse_float(parts[5])) if len(parts) == 6 else (0.0, 0.0)
    return Release(axis, opening_m, offset_m, centre_m)


def _format_release(release: Release | None) -> str:
    if release is None:
        return ""
    text = f"{release.axis};{_format_float(release.opening_m)}"
    centred = release.centre_m == (0.0, 0.0)
    if release.staged or not centred:
        text += ";" + ";".join(_format_float(v) for v in release.offset_m)
    if not centred:
        text += ";" + ";".join(_format_float(v) for v in release.centre_m)
    return text


def _parse_directions(text: str) -> tuple[str, ...]:
    """Directions of the target's frame, ``+x,-y`` ..., or a prism's square pushes, ``@-54.0`` (``""``: none)."""
    directions = tuple(part.strip() for part in text.split(",") if part.strip())
    unknown = [d for d in directions if d not in DIRECTIONS and push_heading_rad(d) is None]
    if unknown:
        raise ValueError(
            f"direction {unknown[0]!r} is not one of {', '.join(DIRECTIONS)} nor a square push @DEG (@-54.0)"
        )
    return directions


def _format_directions(directions: tuple[str, ...]) -> str:
    return ",".join(directions)


def _parse_blockers(text: str) -> dict[str, str]:
    """Per push a neighbour blocks, that neighbour: ``+y=red;@61.5=tile 2`` (``""``: none)."""
    blockers: dict[str, str] = {}
    for entry in (part.strip() for part in text.split(";")):
        if not entry:
            continue
        towards, sep, name = (piece.strip() for piece in entry.partition("="))
        if not sep or not name:
            raise ValueError(f"blocker {entry!r} is not DIRECTION=NEIGHBOUR (+y=red)")
        _parse_directions(towards)
        blockers[towards] = name
    return blockers


def _format_blockers(blockers: Mapping[str, str]) -> str:
    return ";".join(f"{towards}={name}" for towards, name in blockers.items())


def _parse_limit(text: str) -> float:
    """A number, or ``inf``: a bound that never binds (a loop that only the yaw ends)."""
    if text.strip().lower() in ("inf", "+inf", "infinity"):
        return math.inf
    return _parse_float(text)


def _parse_off_float(text: str) -> float | None:
    value = _parse_float(text)
    return None if value == 0 else value


def _format_off_float(value: float | None) -> str:
    return _format_float(value or 0.0)


# ----------------------------------------------------------------------------------------------
# Object types: a name, an outline and a height in millimetres (docs/xml.md, "Object types")
# ----------------------------------------------------------------------------------------------

#: The keys of an object type's text, in the order written: those of a plan's ``[objects.NAME]``.
OUTLINE_KEY, HEIGHT_KEY, MASS_KEY, FRICTION_KEY = "outline_mm", "height_mm", "mass_kg", "friction"
#: What separates the fields and the targets of the ``Targets`` port, so never inside an object type.
_SEPARATORS = (",", ";")
#: A written outline whose vertices lie this close to the outline re-centred on its area centroid is
#: already in the part's own frame: it is kept exactly, so that a written part reads back identical.
_CENTRED_TOLERANCE_M = 1e-12
#: Object types read since the process started, by text: a tree repeats a part's type on every node
#: of the part, and each read searches the part's grasps.
_READ_TYPES_MAX = 512


def _decimal_shifted(text: str, places: int) -> Decimal:
    """The decimal ``text`` times ``10 ** places``, exactly (no rounding to a context's precision)."""
    value = Decimal(text)
    if not value.is_finite():
        raise ValueError(f"{text!r} is not a finite number")
    sign, digits, exponent = value.as_tuple()
    assert isinstance(exponent, int)  # finite
    return Decimal((sign, digits, exponent + places))


def _format_mm(value_m: float) -> str:
    """Metres as millimetres: the shortest text of ``value_m`` with its point moved, so it reads back exactly."""
    value_mm = _decimal_shifted(repr(float(value_m)), 3)
    # Below a ten-thousandth of a millimetre, as repr does below 1e-4, an exponent is shorter than the zeros.
    if value_mm and abs(value_mm) < Decimal("1e-4"):
        return str(value_mm).lower()
    return format(value_mm, "f")


def _parse_mm(text: str) -> float:
    """Millimetres as metres: the float nearest the exact decimal, so ``_format_mm`` reads back as it was."""
    try:
        return float(_decimal_shifted(text, -3))
    except InvalidOperation:
        raise ValueError(f"{text!r} is not a number of millimetres") from None


def _format_object_type(object_type: ObjectType) -> str:
    """``NAME=outline_mm X:Y X:Y ... height_mm H[ mass_kg M][ friction F]``; ``""`` for the default type."""
    if object_type == DEFAULT_TYPE:
        return ""
    name = object_type.name
    if name != name.strip() or "=" in name or any(s in name for s in _SEPARATORS):
        raise ValueError(f"object type {name!r}: a name in XML has no '=', ',' or ';' and no space at either end")
    shape = object_type.shape
    words = [OUTLINE_KEY, *(f"{_format_mm(x)}:{_format_mm(y)}" for x, y in shape.outline_m)]
    words += [HEIGHT_KEY, _format_mm(shape.height_m)]
    if object_type.mass_kg is not None:
        words += [MASS_KEY, _format_float(object_type.mass_kg)]
    if object_type.lateral_friction is not None:
        words += [FRICTION_KEY, _format_float(object_type.lateral_friction)]
    return f"{name}=" + " ".join(words)


def _parse_object_type(text: str) -> ObjectType:
    """``""`` (the default type, the cube), ``NAME=outline_mm ... height_mm H ...``, or the former ``NAME=x*y*z``."""
    if not text.strip():
        return DEFAULT_TYPE
    return _read_object_type(text.strip())


@functools.lru_cache(maxsize=_READ_TYPES_MAX)
def _read_object_type(text: str) -> ObjectType:
    name, equals, fields = (part.strip() for part in text.partition("="))
    if not equals or not name:
        raise ValueError(f"object type {text!r} is not NAME=outline_mm X:Y X:Y X:Y ... height_mm H")
    if "*" in fields:  # the former form: a box, x*y*z in metres
        parts = fields.split("*")
        if len(parts) != 3:
            raise ValueError(f"object type {text!r} is not name=x_m*y_m*z_m")
        x, y, z = (_parse_float(part) for part in parts)
        return ObjectType(name, (x, y, z))
    words = fields.split()
    if not words or words[0] != OUTLINE_KEY:
        raise ValueError(f"object type {text!r} does not start its shape with {OUTLINE_KEY}")
    points_m: list[tuple[float, float]] = []
    at = 1
    while at < len(words) and ":" in words[at]:
        x_text, _, y_text = words[at].partition(":")
        if ":" in y_text:
            raise ValueError(f"vertex {words[at]!r} is not X:Y in millimetres")
        points_m.append((_parse_mm(x_text), _parse_mm(y_text)))
        at += 1
    values: dict[str, str] = {}
    rest = words[at:]
    if len(rest) % 2:
        raise ValueError(f"object type {text!r}: {rest[-1]!r} has no value")
    for key, value in zip(rest[::2], rest[1::2], strict=True):
        if key not in (HEIGHT_KEY, MASS_KEY, FRICTION_KEY) or key in values:
            known = ", ".join((HEIGHT_KEY, MASS_KEY, FRICTION_KEY))
            raise ValueError(f"object type {name!r}: {key!r} is not one of {known} (each once, after the outline)")
        values[key] = value
    if HEIGHT_KEY not in values:
        raise ValueError(f"object type {name!r} has no {HEIGHT_KEY}")
    height_m = _parse_mm(values[HEIGHT_KEY])
    mass_kg = _parse_float(values[MASS_KEY]) if MASS_KEY in values else None
    friction = _parse_float(values[FRICTION_KEY]) if FRICTION_KEY in values else None
    try:
        shape = Prism.from_outline(points_m, height_m)
    except PlanError as error:
        raise ValueError(f"object type {name!r}: {error}") from None
    if not shape.rectangular and np.allclose(shape.outline_m, points_m, rtol=0.0, atol=_CENTRED_TOLERANCE_M):
        shape = Prism(tuple(points_m), height_m)
    return ObjectType(name, None, mass_kg, friction, shape=shape)


def targets_type(make: Callable[..., PartOnTable]) -> PortType:
    """The ``Targets`` type, read into ``make(colour, x_m, y_m, yaw_rad, name=, object_type=)`` (the plan's class)."""
    return PortType("Targets", lambda text: _parse_targets(text, make), _format_targets)


def starts_type(make: Callable[..., PartOnTable]) -> PortType:
    """Where the parts start, written as ``Targets`` are; ``""`` is None (scattered from the scene's seed)."""
    return PortType(
        "Targets",
        lambda text: _parse_targets(text, make) if text.strip() else None,
        lambda starts: "" if starts is None else _format_targets(starts),
    )


STRING = PortType("std::string", str, str)


def _parse_key(text: str) -> str | None:
    """A blackboard key: ``{/red/pose}`` (a reference, the writer's form) or ``/red/pose`` (files before it)."""
    text = text.strip()
    if text.startswith("{") and text.endswith("}"):
        text = text[1:-1].strip()
    return text or None


def _format_key(key: str | None) -> str:
    return "{" + key + "}" if key else ""


#: A blackboard key a node is built with (``offset_key`` ...): written ``{/red/offset_mm}``, read with or
#: without the braces; empty is None.
KEY = PortType("std::string", _parse_key, _format_key)
#: A blackboard entry of the node's object (``Port.entry``): None is the object's own (``/<obj>/<port>``),
#: else the absolute key it is remapped to, written ``{/elsewhere/pose}``.
ENTRY = PortType("BlackboardEntry", _parse_key, _format_key)


def entry_port(name: str, direction: str, description: str) -> Port:
    """A blackboard entry port (``ENTRY``): ``name`` is the entry's field (``pose`` is ``/<obj>/pose``)."""
    return Port(name, ENTRY, None, description, optional=True, direction=direction)


#: A text whose empty value means "none" (``None`` in Python).
OFF_STRING = PortType("std::string", lambda text: text or None, lambda value: value or "")
DOUBLE = PortType("double", _parse_float, _format_float)
#: A number that may be ``inf``, written so (BehaviorTree.CPP's ``std::stod`` reads it too).
LIMIT = PortType("double", _parse_limit, _format_float)
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
BLOCKERS = PortType("Blockers", _parse_blockers, _format_blockers)
