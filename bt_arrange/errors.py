"""The exception family of bt-arrange: everything it raises on purpose is a ``BtArrangeError``.

Behaviours turn these into FAILURE with a feedback message; the CLI turns them into a
one-line error and a non-zero exit. Messages name the offending value and the limit, and the
errors carry them as attributes too (as pink's do), so a caller can act on them without parsing
the text: ``error.field``, ``error.value``, ``error.limit``, ``error.unit``; ``UnreachableError``
also ``error.pose``, ``error.joint`` and ``error.bound`` (the ``(lower, upper)`` range).

The errors of a bad value also inherit ``ValueError`` (``PlanError``, ``OutOfRangeError``,
``GeometryError``, ``PortValueError``), so callers that caught ``ValueError`` keep working.
"""

from __future__ import annotations

from typing import Any


class BtArrangeError(Exception):
    """Root of every error bt-arrange raises on purpose.

    ``field`` names what was wrong (an argument, a setting, a joint), ``value`` the offending
    value, ``limit`` the bound it broke and ``unit`` their unit; each is ``None`` when unknown.
    """

    def __init__(
        self,
        message: str = "",
        *,
        field: str | None = None,
        value: Any = None,
        limit: Any = None,
        unit: str | None = None,
    ) -> None:
        super().__init__(message)
        self.field = field
        self.value = value
        self.limit = limit
        self.unit = unit


class PlanError(BtArrangeError, ValueError):
    """An arrangement plan or a target is malformed or cannot be carried out.

    ``parts`` names what the error is about, as ``(role, name)`` pairs: ``("target", "red")``,
    ``("start", "red")``, ``("colour", "teal")``; a plan file turns them into its entries
    (``[[targets]] 3``, ``[colours.teal]``, ``bt_arrange.plan.check.in_plan``).
    """

    def __init__(
        self,
        message: str = "",
        *,
        parts: tuple[tuple[str, str], ...] = (),
        field: str | None = None,
        value: Any = None,
        limit: Any = None,
        unit: str | None = None,
    ) -> None:
        super().__init__(message, field=field, value=value, limit=limit, unit=unit)
        self.parts = tuple(parts)


class OutOfRangeError(BtArrangeError, ValueError):
    """A command value (a gripper width, a force, a limit) lies outside what the hardware allows."""


class GeometryError(BtArrangeError, ValueError):
    """A pose, a rotation or a joint vector that is not one (not finite, a zero quaternion, a wrong shape)."""


class UnreachableError(BtArrangeError):
    """The arm cannot reach a pose: too far, below the table, or outside the joint limits.

    ``pose`` is the target pose when one was asked for, ``joint`` the joint out of its range and
    ``bound`` that range ``(lower, upper)`` in radians.
    """

    def __init__(
        self,
        message: str = "",
        *,
        pose: Any = None,
        joint: str | None = None,
        bound: tuple[float, float] | None = None,
        value: Any = None,
        limit: Any = None,
        unit: str | None = None,
    ) -> None:
        super().__init__(message, field=joint, value=value, limit=limit if limit is not None else bound, unit=unit)
        self.pose = pose
        self.joint = joint
        self.bound = bound


class MotionError(BtArrangeError):
    """A trajectory could not be planned or followed."""


class PerceptionError(BtArrangeError):
    """The camera pipeline was misconfigured (an unknown colour, bad intrinsics)."""


class PortValueError(BtArrangeError, ValueError):
    """A node port's text is not a value of its type (``bt_arrange.ports``): ``field`` is the type, ``value`` the text.

    ``reason`` says why, without the type and the text (the XML reader adds the node, the port and the line).
    """

    def __init__(self, message: str = "", *, reason: str = "", field: str | None = None, value: Any = None) -> None:
        super().__init__(message, field=field, value=value)
        self.reason = reason or message


class TreeFileError(BtArrangeError):
    """A tree file cannot be loaded, or does not provide what the command needs."""


class XmlTreeError(TreeFileError):
    """An XML tree cannot be read or written: malformed, an unregistered node, a bad port value."""


class DisplayError(BtArrangeError):
    """A tree cannot be drawn as asked (an unknown format, no Graphviz, a file that cannot be written)."""


class BackendError(BtArrangeError):
    """No backend of that name is installed, or it does not offer what the command needs."""


class RecordError(BtArrangeError):
    """The run finished, its record did not: a file could not be written (a full disk, a folder gone or read-only).

    Raised after the work is done, so nothing measured is lost: ``result`` is what the call would
    have returned (a run's report, a campaign's summary rows), ``faults`` the ``WriteFault``s
    (``bt_arrange.files``: each a path and its cause). The command prints the result as usual,
    then this one line, and exits 3. The files named are absent or as they were before, never cut short.
    """

    def __init__(self, message: str, *, faults: Any = (), result: Any = None) -> None:
        super().__init__(message)
        self.faults = list(faults)
        self.result = result


class TrialsErroredError(BtArrangeError):
    """A campaign finished, but some of its trials errored (an exception, a worker that died).

    The others are recorded; ``summary`` holds the summary rows of the trials that did finish. The
    command prints them, then this one line, and exits 4 (``--resume`` reruns the errored trials).
    """

    def __init__(self, message: str, *, summary: Any = None) -> None:
        super().__init__(message)
        self.summary = list(summary or [])
