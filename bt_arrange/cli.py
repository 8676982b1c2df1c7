"""The ``bt-arrange`` command line.

    bt-arrange run TREE_FILE [--backend NAME] [--robot HOST] [--camera SPEC] [--speed-fraction F] [--dry-run]
                   [--seed N] [--threshold-mm X] [--cell ideal|real|FILE.toml]
                   [--calibration FILE] [--inject ERROR[,ERROR...]] [--gui] [--live] [--record DIR] [--json]
                   [--groot [PORT]] [--groot-wait-s S] [--groot-bind ADDR] [--pace F]
                   [--foxglove [PORT]] [--foxglove-bind ADDR]
    bt-arrange show TREE_FILE [--format text|dot|png|svg|xml] [--blackboard] [--out FILE]
    bt-arrange experiment [--rows ...] [--trials 100] [--seed 0] [--threshold-mm 1.0 | --thresholds 0.29,0.5,1,2]
                          [--cell ideal|real|FILE.toml[,...]] [--strategy paper|learned|diagonal]
                          [--object cube|bar[,...]]
                          [--executor local|dask] [--workers N] [--scheduler tcp://HOST:PORT] [--out DIR]
                          [--record DIR] [--resume]
    bt-arrange calibrate [--backend NAME] [--robot HOST] [--camera SPEC] [--cell ideal|real|FILE.toml]
                         [--views 20] [--out camera.toml] [--seed N] [--gui] [--live] [--record DIR] [--json]
    bt-arrange examples
    bt-arrange info [--backend NAME] [--robot HOST] [--camera SPEC]

Exit status (``cli_common.EXIT_CODES``, the table every command's ``--help`` ends with): 0 when
every object ends within the threshold, 1 when one does not (or too few views to calibrate), 2 for
a usage, file, plan or setup error (a one-line message, never a traceback, before anything moves),
3 when the work finished but its record did not (a file of ``--record``/``--out`` could not be
written: one line naming it, the results printed as usual), 4 when some of a campaign's trials
errored (the others recorded; ``--resume`` reruns them), 130 when interrupted, 141 when the reader
of the output went away (``| head``), 143 when terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from importlib import metadata
from pathlib import Path
from typing import Any

from bt_arrange import backends, treefile
from bt_arrange.cli_calibrate import _calibrate
from bt_arrange.cli_common import (
    CELL_HELP,
    EXIT_BROKEN_PIPE,
    EXIT_CODES_HELP,
    EXIT_INTERRUPTED,
    EXIT_NOT_WITHIN,
    EXIT_OK,
    EXIT_RECORD,
    EXIT_TERMINATED,
    EXIT_TRIALS_ERRORED,
    EXIT_USAGE,
    STACK,
    _groot_port,
    _millimetres,
    _pace,
    _Parser,
    _positive_seconds,
    _seconds_or_zero,
    _speed_fraction,
    _whole,
    add_cell_options,
    connect_backend,
)
from bt_arrange.cli_experiment import _experiment
from bt_arrange.cli_run import _run
from bt_arrange.errors import BtArrangeError, RecordError, TrialsErroredError
from bt_arrange.foxglove.streams import DEFAULT_PORT as FOXGLOVE_PORT
from bt_arrange.foxglove.streams import port_argument as foxglove_port
from bt_arrange.motion.safety import SafetyStop


def _info(args: argparse.Namespace) -> int:
    print(f"bt-arrange {metadata.version('bt-arrange')}")
    for package in STACK:
        try:
            print(f"  {package} {metadata.version(package)}")
        except metadata.PackageNotFoundError:
            print(f"  {package} missing (pip install -e . installs it)")
    backend = backends.load(args.backend)
    connect_backend(backend, args)
    for line in backend.check():
        print(f"  {line}")
    return EXIT_OK


def _examples(args: argparse.Namespace) -> int:
    from bt_arrange import examples

    names = examples.names()
    width = max((len(name) for name in names), default=0)
    for name in names:
        print(f"{name.ljust(width)}  {examples.describe(name)}")
    first = examples.path_of(names[0]) if names else None
    if first is not None:
        print(f"run one with: bt-arrange run NAME (the files are in {first.parent})")
    return EXIT_OK


def _show(args: argparse.Namespace) -> int:
    from bt_arrange.display import render_tree

    module = treefile.load(args.tree_file)
    root = treefile.build_root(module)
    if args.format == "xml":
        return _show_xml(root, args)
    result = render_tree(root, args.format, blackboard=args.blackboard, out=args.out, name=Path(args.tree_file).stem)
    if args.format in ("text", "dot") and args.out is None:
        print(result)
    else:
        # render_tree returns the text itself for text and dot, the picture's path otherwise.
        print(f"wrote {args.out if args.out is not None else result}")
    return EXIT_OK


def _show_xml(root: Any, args: argparse.Namespace) -> int:
    from bt_arrange import xmltree

    stem = Path(args.tree_file).stem
    text = xmltree.to_xml(
        root,
        tree_id=stem,
        comment=f"generated from {Path(args.tree_file).name} by bt-arrange show (format xml)",
        model="full" if args.full_model else "used",
    )
    if args.out is None:
        print(text, end="")
        return EXIT_OK
    try:
        args.out.write_text(text, encoding="utf-8")
    except OSError as error:
        raise BtArrangeError(f"cannot write {args.out}: {error.strerror}") from error
    print(f"wrote {args.out}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    """The argument parser, with one sub-command per job."""
    # The experiment's rows come from the default backend's registry of rows; loading it starts
    # no simulator (the sim backend imports neither pybullet nor matplotlib at module level).
    try:
        default_experiment = backends.load().experiment
    except BtArrangeError:
        default_experiment = None
    rows = tuple(default_experiment.ROWS) if default_experiment is not None else ()
    default_rows = tuple(getattr(default_experiment, "DEFAULT_ROWS", rows))
    row_labels = dict(default_experiment.ROW_LABELS) if default_experiment is not None else {}

    parser = _Parser(
        prog="bt-arrange",
        description="Behaviour trees for precise robotic arrangement.",
        epilog=EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {metadata.version('bt-arrange')}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def add_command(name: str, help_text: str, epilog: str = EXIT_CODES_HELP) -> argparse.ArgumentParser:
        return commands.add_parser(
            name,
            help=help_text,
            description=help_text,
            epilog=epilog,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )

    def add_backend(command: argparse.ArgumentParser) -> None:
        command.add_argument(
            "--backend",
            default=backends.DEFAULT_BACKEND,
            metavar="NAME",
            help=f"what to run on (default {backends.DEFAULT_BACKEND}: the simulated work cell)",
        )

    run = add_command("run", "run a tree file in the simulated work cell (headless by default)")
    run.add_argument(
        "tree_file",
        metavar="TREE_FILE",
        help="a Python file exposing create_root() and create_scene(), a BehaviorTree.CPP .xml tree, "
        "a .toml plan, or the name of an example (bt-arrange examples)",
    )
    run.add_argument(
        "--seed",
        type=_whole(0),
        default=None,
        help="seed of the scene (where the parts start), 0 or more; default a plan's [scene] seed, else 0",
    )
    run.add_argument(
        "--threshold-mm", type=_millimetres, help="accuracy threshold in mm (the tree file's default if absent)"
    )
    run.add_argument("--gui", action="store_true", help="open the pybullet window (needs a display)")
    run.add_argument("--live", action="store_true", help="redraw the tree with its statuses while it runs")
    run.add_argument(
        "--record", type=Path, metavar="DIR", help="save top-camera images, the transition log and replay.html"
    )
    run.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    run.add_argument(
        "--time-limit-s",
        type=_positive_seconds,
        default=1800.0,
        help="stop after this much world time (default 1800 s)",
    )
    add_backend(run)
    run.add_argument("--cell", default="ideal", help=CELL_HELP)
    run.add_argument(
        "--calibration",
        type=Path,
        metavar="FILE",
        help="a camera.toml from bt-arrange calibrate: the detector uses its intrinsics, distortion and pose "
        "(default: the cell's nominal camera)",
    )
    add_cell_options(run)
    run.add_argument(
        "--speed-fraction",
        type=_speed_fraction,
        default=None,
        metavar="F",
        help="scale every motion's velocity, acceleration and jerk limits to F of the planned ones (0 < F <= 1; "
        "time-scaled: the same paths, 1/F times slower); default the backend's (ur: 0.5, the simulators: 1)",
    )
    run.add_argument(
        "--dry-run",
        action="store_true",
        help="plan every motion of the tree from the robot's measured joints without moving it (--backend ur): a "
        "kinematic shadow of the arm and gripper, the real camera for looks; says what it could not plan",
    )
    run.add_argument(
        "--inject",
        metavar="ERROR[,ERROR...]",
        help="inject the paper's Sec. 3 errors into every part the tree picks, by the names of experiment --rows "
        "(translation, orientation, perception, surface, slip, sticking, release, tilt, or all), at Table 1's "
        "magnitudes, drawn from --seed; --json lists what went into which part (the sim backends)",
    )
    run.add_argument(
        "--groot",
        type=_groot_port,
        nargs="?",
        const=1667,
        default=None,
        metavar="PORT",
        help="serve the running tree to Groot2 (BehaviorTree.CPP 4's protocol) on PORT and PORT+1 "
        "(default 1667), read-only; docs/groot2.md",
    )
    run.add_argument(
        "--groot-wait-s",
        type=_seconds_or_zero,
        default=None,
        metavar="S",
        help="with --groot: wait up to S seconds of wall time for a client to fetch the tree before the first tick",
    )
    run.add_argument(
        "--groot-bind",
        default=None,
        metavar="ADDR",
        help="with --groot: the address to serve on (default 127.0.0.1, this machine only; 0.0.0.0 for all)",
    )
    run.add_argument(
        "--foxglove",
        type=foxglove_port,
        nargs="?",
        const=FOXGLOVE_PORT,
        default=None,
        metavar="PORT",
        help=f"serve the run live to Foxglove (its WebSocket protocol) on PORT (default {FOXGLOVE_PORT}; 0: any "
        "free port), read-only: the streams of run.mcap; needs the foxglove extra; docs/foxglove.md",
    )
    run.add_argument(
        "--foxglove-bind",
        default=None,
        metavar="ADDR",
        help="with --foxglove: the address to serve on (default 127.0.0.1, this machine only; 0.0.0.0 for all)",
    )
    run.add_argument(
        "--pace",
        type=_pace,
        default=None,
        metavar="F",
        help="run the world at F times real time (default: as fast as it goes), e.g. 1 to watch it",
    )
    run.set_defaults(handler=_run)

    calibrate = add_command(
        "calibrate",
        "calibrate the top camera with a ChArUco board on the flange: intrinsics, distortion, camera to base",
    )
    calibrate.add_argument("--views", type=_whole(6), default=20, help="board poses to try (default 20, at least 6)")
    calibrate.add_argument(
        "--out", type=Path, default=Path("camera.toml"), help="the calibration file to write (default camera.toml)"
    )
    calibrate.add_argument("--seed", type=_whole(0), default=0, help="seed of a real cell's per-run errors (default 0)")
    calibrate.add_argument("--gui", action="store_true", help="open the pybullet window (needs a display)")
    calibrate.add_argument("--live", action="store_true", help="redraw the tree with its statuses while it runs")
    calibrate.add_argument(
        "--record", type=Path, metavar="DIR", help="save the transition log, report.json and replay.html"
    )
    calibrate.add_argument("--json", action="store_true", help="print one JSON object instead of the summary")
    calibrate.add_argument(
        "--time-limit-s", type=_positive_seconds, default=1800.0, help="stop after this much world time"
    )
    add_backend(calibrate)
    add_cell_options(calibrate)
    calibrate.add_argument(
        "--speed-fraction",
        type=_speed_fraction,
        default=None,
        metavar="F",
        help="every motion at F of its planned speed (0 < F <= 1); default the backend's (ur: 0.5)",
    )
    calibrate.add_argument("--cell", default="ideal", help=CELL_HELP)
    calibrate.set_defaults(handler=_calibrate)

    show = add_command("show", "draw a tree file's tree without starting a simulator")
    show.add_argument("tree_file", metavar="TREE_FILE")
    show.add_argument(
        "--format",
        choices=("text", "dot", "png", "svg", "xml"),
        default="text",
        help="default text; xml: BehaviorTree.CPP v4 for Groot2",
    )
    show.add_argument("--blackboard", action="store_true", help="include the blackboard keys read and written")
    show.add_argument(
        "--full-model",
        action="store_true",
        help="xml: every port of each node, described, in the TreeNodesModel (an editor's palette)",
    )
    show.add_argument("--out", type=Path, metavar="FILE", help="write to FILE (png/svg default: <tree>.png/.svg)")
    show.set_defaults(handler=_show)

    rows_help = "\n".join(f"  {row:<16} {row_labels.get(row, '')}" for row in rows)
    experiment = add_command(
        "experiment",
        "reproduce the paper's Table 1 and Fig. 4 in simulation; sweeps; local or Dask",
        f"rows (--rows):\n{rows_help}\n\n{EXIT_CODES_HELP}",
    )
    experiment.add_argument(
        "--rows",
        default=",".join(default_rows),
        help=f"comma-separated rows, listed below (default: {','.join(default_rows)})",
    )
    experiment.add_argument("--trials", type=_whole(1), default=100, help="trials per row (default 100)")
    experiment.add_argument("--seed", type=_whole(0), default=0, help="experiment seed, 0 or more (default 0)")
    experiment.add_argument("--threshold-mm", type=_millimetres, help="accuracy threshold in mm (default 1)")
    experiment.add_argument(
        "--thresholds", metavar="MM,MM,...", help="sweep: comma-separated thresholds in mm, one folder each"
    )
    experiment.add_argument(
        "--executor", default="local", choices=("local", "dask"), help="local process pool (default) or Dask"
    )
    experiment.add_argument(
        "--workers",
        type=_whole(1),
        default=1,
        help="worker processes (local pool or Dask LocalCluster), each with its own world (default 1)",
    )
    experiment.add_argument(
        "--scheduler", metavar="tcp://HOST:PORT", help="with --executor dask: an existing cluster's scheduler"
    )
    experiment.add_argument(
        "--out", type=Path, default=Path("runs/experiment"), help="output folder (default runs/experiment)"
    )
    experiment.add_argument(
        "--record",
        type=Path,
        metavar="DIR",
        help="one MCAP file per trial (Foxglove's; the foxglove extra): DIR/[COMBINATION/]ROW/trial-NNNN.mcap, "
        "named by each record's mcap key (docs/foxglove.md)",
    )
    experiment.add_argument(
        "--resume",
        action="store_true",
        help="continue the campaign in --out (after Ctrl-C, SIGTERM or a kill): its recorded trials are kept, "
        "the missing and errored ones run; refused if --out holds another specification",
    )
    add_backend(experiment)
    experiment.add_argument(
        "--cell", default="ideal", help=CELL_HELP + "; several, comma-separated (ideal,real), one folder each"
    )
    experiment.add_argument(
        "--strategy",
        choices=("paper", "learned", "diagonal"),
        default="paper",
        help="push strategy: paper (alternating x/y, Table 1's; default), learned or diagonal (docs/experiments.md)",
    )
    experiment.add_argument(
        "--object",
        dest="object_name",
        metavar="NAME[,NAME...]",
        default="cube",
        help="the part's type: cube (the paper's 50 mm cube; default) or bar (80 x 40 x 40 mm); "
        "several, comma-separated (cube,bar), one folder each",
    )
    experiment.add_argument(
        "--calibration",
        type=Path,
        metavar="FILE",
        help="a camera.toml from bt-arrange calibrate for every trial's detector (default: the nominal camera)",
    )
    experiment.set_defaults(handler=_experiment)

    examples = add_command("examples", "list the example plans shipped in the package (bt-arrange run NAME runs one)")
    examples.set_defaults(handler=_examples)

    info = add_command("info", "library versions, and a check that a headless cell starts")
    add_backend(info)
    add_cell_options(info)
    info.set_defaults(handler=_info)
    return parser


class Terminated(BaseException):
    """SIGTERM arrived: unwinds like Ctrl-C, so a campaign's pool is shut down and its files closed.

    A ``BaseException``, so no ``except Exception`` on the way (a lost trial's) swallows it.
    """


def _terminate(signum: int, frame: object, *, main_pid: int) -> None:
    if os.getpid() != main_pid:
        # A forked pool worker inherits the handler: it ends as SIGTERM would have ended it.
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        return
    raise Terminated


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bt-arrange`` console script."""
    args = build_parser().parse_args(argv)
    main_pid = os.getpid()
    # Signal handlers belong to the main thread (a test or an embedding may call main from another).
    handles_sigterm = threading.current_thread() is threading.main_thread()
    if handles_sigterm:
        previous = signal.signal(signal.SIGTERM, lambda signum, frame: _terminate(signum, frame, main_pid=main_pid))
    try:
        code = int(args.handler(args))
        sys.stdout.flush()  # a closed pipe shows here, inside the try, rather than at exit
        return code
    except BrokenPipeError:
        # The reader (| head) has what it wanted; point stdout at nothing so the exit flush is quiet.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    except RecordError as error:
        print(f"bt-arrange: error: {error}", file=sys.stderr)
        return EXIT_RECORD
    except TrialsErroredError as error:
        # Not a usage error: the campaign ran, the other trials are recorded and their tables printed.
        print(f"bt-arrange: error: {error}", file=sys.stderr)
        return EXIT_TRIALS_ERRORED
    except BtArrangeError as error:
        print(f"bt-arrange: error: {error}", file=sys.stderr)
        return EXIT_USAGE
    except SafetyStop as stop:
        # A stop outside a tree's ticks (a camera lost while a record's image is taken): the same one line.
        print(f"bt-arrange: safety stop: {stop.reason}", file=sys.stderr)
        return EXIT_NOT_WITHIN
    except KeyboardInterrupt:
        print("bt-arrange: interrupted; what was logged so far is kept", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print("bt-arrange: terminated; what was logged so far is kept", file=sys.stderr)
        return EXIT_TERMINATED
    finally:
        if handles_sigterm:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
