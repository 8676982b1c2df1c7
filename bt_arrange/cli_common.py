"""What the ``bt-arrange`` commands share: exit codes, option types, the threshold and cell checks."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any, NoReturn

from bt_arrange.errors import BtArrangeError

STACK = ("py-trees", "pybullet", "opencv-python-headless", "placo", "ruckig", "numpy")
EXIT_OK, EXIT_NOT_WITHIN, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE, EXIT_TERMINATED = 0, 1, 2, 130, 141, 143
#: The run finished, its record did not (a contract): a recorded file could not be written.
EXIT_RECORD = 3
#: A campaign finished with some trials errored (an exception, a worker that died): the others are recorded.
EXIT_TRIALS_ERRORED = 4

#: Every exit status of every command, with what it means (a contract): ``--help`` of each command
#: ends with this table, and docs/cli.md holds the same rows (tests/test_exit_codes.py compares them).
EXIT_CODES: tuple[tuple[int, str], ...] = (
    (EXIT_OK, "every object ended within the threshold (run, measured by the camera); every trial finished "
     "(experiment); the camera calibrated, its file written (calibrate); listed, drawn or checked (the others)"),
    (EXIT_NOT_WITHIN, "an object did not end within the threshold (run: outside, failed, or the time limit "
     "stopped it); too few usable views to calibrate (calibrate): the work ran and fell short"),
    (EXIT_USAGE, "a usage, file, plan or setup error (a bad option or file, a port in use, a missing library, "
     "an unreachable scheduler): one line on stderr, before anything moves"),
    (EXIT_RECORD, "the work finished, its record did not: a file of --record/--out could not be written (disk "
     "full, folder removed or read-only); one line names it, the results are printed, every file is whole or absent"),
    (EXIT_TRIALS_ERRORED, "some trials errored (experiment: an exception, a worker that died); the others are "
     "recorded and their tables printed, one line names the first; --resume reruns the errored ones"),
    (EXIT_INTERRUPTED, "interrupted (Ctrl-C); what was logged so far is kept"),
    (EXIT_BROKEN_PIPE, "the reader of the output went away (e.g. | head)"),
    (EXIT_TERMINATED, "terminated (SIGTERM, e.g. a cluster's job limit); what was logged so far is kept"),
)  # fmt: skip


def _exit_codes_help(width: int = 100) -> str:
    import textwrap

    lines = ["exit status: (the same table for every command)"]
    for code, meaning in EXIT_CODES:
        wrapped = textwrap.wrap(meaning, width - 7)
        lines.append(f"  {code:<4} {wrapped[0]}")
        lines += [f"       {line}" for line in wrapped[1:]]
    return "\n".join(lines)


#: The exit-status table as ``--help`` prints it (the epilog of every command).
EXIT_CODES_HELP = _exit_codes_help()


def exit_codes_markdown() -> str:
    """The exit-status table as docs/cli.md holds it."""
    rows = [f"| {code} | {meaning.replace('|', chr(92) + '|')} |" for code, meaning in EXIT_CODES]
    return "\n".join(["| exit status | meaning |", "|---|---|", *rows])


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (the usage is one ``--help`` away), exit status 2."""

    def error(self, message: str) -> NoReturn:
        """Print one line and exit with the usage status."""
        self.exit(
            EXIT_USAGE,
            f"bt-arrange: error: {self.prog.removeprefix('bt-arrange').strip() or 'usage'}: "
            f"{message} (see {self.prog} --help)\n",
        )


def _whole(minimum: int) -> Any:
    """An argparse type: a whole number of at least ``minimum``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{value} must be {minimum} or more")
        return value

    return parse


def _positive_seconds(text: str) -> float:
    """An argparse type: a positive, finite number of seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text} must be a positive number of seconds")
    return value


def _groot_port(text: str) -> int:
    """An argparse type: the Groot2 server port (the next one is its publisher socket)."""
    from bt_arrange.groot2 import check_port

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a port number (put the tree file before --groot, or give the port)"
        ) from None
    try:
        return check_port(value)
    except BtArrangeError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _seconds_or_zero(text: str) -> float:
    """An argparse type: a finite number of seconds, 0 or more."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text} must be 0 or more seconds")
    return value


def _pace(text: str) -> float:
    """An argparse type: a positive, finite multiple of real time."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number (1 is real time)") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text} must be a positive multiple of real time (1 is real time)")
    return value


def _millimetres(text: str) -> float:
    """An argparse type: a number (the plan check decides whether a push can correct it)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of millimetres") from None


def _check_threshold_option(threshold_mm: float | None) -> None:
    if threshold_mm is None:
        return
    from bt_arrange.trees import check_threshold

    try:
        check_threshold(threshold_mm)
    except BtArrangeError as error:
        raise BtArrangeError(f"--threshold-mm {threshold_mm:g}: {error}") from error


CELL_HELP = (
    "the work cell: ideal (default; today's simulated cell), real (the paper's real cell's errors, "
    "docs/simulation.md) or FILE.toml with your own values (the sim backend)"
)


def _note_uncalibrated(cells: str, calibration: Path | None) -> None:
    """One line on stderr when a real cell runs on its nominal camera (a lens and a pose off by centimetres)."""
    if calibration is None and "real" in [c.strip() for c in cells.split(",")]:
        print(
            "bt-arrange: the real cell's camera is uncalibrated (its nominal intrinsics and pose): "
            "bt-arrange calibrate --cell real --out camera.toml, then --calibration camera.toml",
            file=sys.stderr,
        )


def connect_backend(backend: Any, args: argparse.Namespace) -> None:
    """Hand ``--robot HOST`` and ``--camera SPEC`` to a backend that reaches a real cell; refuse them otherwise."""
    from bt_arrange import backends

    robot, camera = getattr(args, "robot", None), getattr(args, "camera", None)
    if robot is None and camera is None:
        return
    backends.require(backend, backends.ConnectingBackend, "reach a real cell (--robot, --camera)")
    backend.connect_to(robot, camera)


def _speed_fraction(text: str) -> float:
    """An argparse type: a fraction of the full speed, 0 < f <= 1."""
    from bt_arrange.motion.safety import check_speed_fraction

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number (1 is the full speed)") from None
    try:
        return check_speed_fraction(value)
    except BtArrangeError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def add_cell_options(command: argparse.ArgumentParser) -> None:
    """``--robot HOST`` and ``--camera SPEC``: where a real cell is (``--backend ur``; docs/real-cell.md)."""
    command.add_argument(
        "--robot",
        metavar="HOST",
        default=None,
        help="the robot controller's address (--backend ur: RTDE 30004, script 30003, dashboard 29999, the "
        "Robotiq URCap's socket 63352); docs/real-cell.md",
    )
    command.add_argument(
        "--camera",
        metavar="SPEC",
        default=None,
        help="the top camera (--backend ur): a network camera's snapshot URL ending in / (http://HOST:PORT/), "
        "a V4L2 device (/dev/video0 or 0) or a stream URL; default: the camera at http://ROBOT:8081/",
    )
