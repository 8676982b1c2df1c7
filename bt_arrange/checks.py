"""One home for the checks of a number given by a user: finite, positive, whole.

Each returns the value (as ``float`` or ``int``) or raises ``PlanError`` (or the ``error`` class
given, e.g. ``OutOfRangeError``) whose message names the field and the value, and whose
attributes carry them (``error.field``, ``error.value``, ``error.limit``, ``error.unit``)::

    positive_number("threshold_mm", 0, "mm")      # threshold_mm=0 must be a positive number of millimetres
    whole_number("max_pushes", -1)                # max_pushes=-1 must be a whole number, 0 or more
    positive_number("time limit", 0, "s", style="unit")   # time limit 0 s must be a positive number of seconds

``style="="`` (the default) shows ``name=value``, as a keyword argument is written; ``style="unit"``
shows ``name value unit``, as a quantity is spoken; ``where`` prefixes the message (``"target 1 (red): "``).
A ``bool`` is never a number here (``True`` is not 1 millimetre).
"""

from __future__ import annotations

import math
from numbers import Integral, Real
from typing import Any, Literal

from bt_arrange.errors import BtArrangeError, PlanError

#: How a unit is spelt out in a message.
UNIT_WORDS = {"mm": "millimetres", "m": "metres", "s": "seconds", "deg": "degrees", "rad": "radians", "": ""}

Style = Literal["=", "unit"]


def _shown(name: str, value: object, unit: str, style: Style) -> str:
    if style == "unit":
        return f"{name} {value!r} {unit}".rstrip() if unit else f"{name} {value!r}"
    return f"{name}={value!r}"


def _of_unit(unit: str) -> str:
    words = UNIT_WORDS.get(unit, unit)
    return f" of {words}" if words else ""


def is_real(value: object) -> bool:
    """True for an int or float (numpy's too), never for a bool."""
    return isinstance(value, Real) and not isinstance(value, bool)


def finite_number(
    name: str,
    value: object,
    unit: str = "",
    *,
    where: str = "",
    style: Style = "=",
    error: type[BtArrangeError] = PlanError,
) -> float:
    """``value`` as a float, or ``error`` saying it "is not a finite number"."""
    if not is_real(value) or not math.isfinite(value):  # type: ignore[arg-type]
        raise error(
            f"{where}{_shown(name, value, unit, style)} is not a finite number", field=name, value=value, unit=unit
        )
    return float(value)  # type: ignore[arg-type]


def positive_number(
    name: str,
    value: object,
    unit: str = "",
    *,
    where: str = "",
    style: Style = "=",
    finite: bool = True,
    error: type[BtArrangeError] = PlanError,
) -> float:
    """``value`` as a float, or ``error`` saying it "must be a positive number" (and finite, unless ``finite=False``).

    NaN is not positive; infinity is positive but not finite: that message says "finite".
    """
    shown = _shown(name, value, unit, style)
    if not is_real(value) or not value > 0:  # type: ignore[operator]
        raise error(
            f"{where}{shown} must be a positive number{_of_unit(unit)}", field=name, value=value, limit=0, unit=unit
        )
    if finite and not math.isfinite(value):  # type: ignore[arg-type]
        raise error(f"{where}{shown} must be a finite number{_of_unit(unit)}", field=name, value=value, unit=unit)
    return float(value)  # type: ignore[arg-type]


def whole_number(
    name: str,
    value: object,
    minimum: int = 0,
    *,
    where: str = "",
    style: Style = "=",
    error: type[BtArrangeError] = PlanError,
) -> int:
    """``value`` as an int, or ``error`` saying it "must be a whole number, <minimum> or more"."""
    if not isinstance(value, Integral) or isinstance(value, bool) or value < minimum:
        raise error(
            f"{where}{_shown(name, value, '', style)} must be a whole number, {minimum} or more",
            field=name,
            value=value,
            limit=minimum,
        )
    return int(value)


def at_mm(x_m: float, y_m: float) -> str:
    """A point on the table as a plan file writes it: ``x 450 mm, y 50 mm``."""
    return f"x {x_m * 1000:.0f} mm, y {y_m * 1000:.0f} mm"


def toml_shown(value: Any) -> str:
    """A plan file's value as the user wrote it, roughly: strings quoted, booleans lower-case."""
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)
