"""The choices a plan makes, as enums: how pushes are chosen, and when parts are corrected.

Each is a ``str`` enum, so a choice compares equal to its name (``PushStrategy.PAPER == "paper"``),
is written to XML, JSON and reports as that name, and is parsed from a string only at the edges (the
Python builders, the CLI, a plan file, an XML port) by ``parse``, which names the choices on a typo.
"""

from __future__ import annotations

from enum import Enum
from typing import TypeVar

from bt_arrange.errors import PlanError
from bt_arrange.suggest import did_you_mean

C = TypeVar("C", bound="Choice")


class Choice(str, Enum):
    """A named choice: its value is the name a user writes."""

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)

    @classmethod
    def parse(cls: type[C], value: object, field: str) -> C:
        """The choice named ``value`` (a name or a member), or a ``PlanError`` naming ``field`` and the choices."""
        if isinstance(value, cls):
            return value
        names = [member.value for member in cls]
        if isinstance(value, str) and value in names:
            return cls(value)
        hint = did_you_mean(value, names) if isinstance(value, str) else ""
        raise PlanError(f"{field}={value!r}{hint}: choose one of {', '.join(names)}")


class PushStrategy(Choice):
    """How a correction chooses its pushes.

    ``PAPER`` alternates x and y, pushing by the axis' offset (Table 1's); ``LEARNED`` pushes the
    larger axis first and learns each push's landing error; ``DIAGONAL`` is ``LEARNED`` whose push
    also corrects the other axis.
    """

    PAPER = "paper"
    LEARNED = "learned"
    DIAGONAL = "diagonal"


class CorrectMode(Choice):
    """When parts are corrected: ``EACH`` right after placing (Algorithm 1), ``AFTER_ALL`` after all (Fig. 5)."""

    EACH = "each"
    AFTER_ALL = "after_all"
