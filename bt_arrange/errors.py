"""The exception family of bt-arrange: everything it raises on purpose is a ``BtArrangeError``.

Behaviours turn these into FAILURE with a feedback message; the CLI turns them into a
one-line error and a non-zero exit. Messages name the offending value and the limit.
"""

from __future__ import annotations


class BtArrangeError(Exception):
    """Root of every error bt-arrange raises on purpose."""


class PlanError(BtArrangeError, ValueError):
    """An arrangement plan or a target is malformed or cannot be carried out."""


class OutOfRangeError(BtArrangeError, ValueError):
    """A command value (a gripper width, a force, a limit) lies outside what the hardware allows."""


class UnreachableError(BtArrangeError):
    """The arm cannot reach a pose: too far, below the table, or outside the joint limits."""


class MotionError(BtArrangeError):
    """A trajectory could not be planned or followed."""


class PerceptionError(BtArrangeError):
    """The camera pipeline was misconfigured (an unknown colour, bad intrinsics)."""


class TreeFileError(BtArrangeError):
    """A tree file cannot be loaded, or does not provide what the command needs."""
