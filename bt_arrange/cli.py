"""The ``bt-arrange`` command line.

    bt-arrange run TREE_FILE [--backend NAME] [--seed N] [--threshold-mm X] [--cell ideal|real|FILE.toml]
                   [--gui] [--live] [--record DIR] [--json]
                   [--groot [PORT]] [--groot-wait-s S] [--groot-bind ADDR] [--pace F]
    bt-arrange show TREE_FILE [--format text|dot|png|svg|xml] [--blackboard] [--out FILE]
    bt-arrange experiment [--rows ...] [--trials 100] [--seed 0] [--threshold-mm 1.0 | --thresholds 0.29,0.5,1,2]
                          [--cell ideal|real|FILE.toml[,...]] [--strategy paper|learned|diagonal]
                          [--object cube|bar[,...]]
                          [--executor local|dask] [--workers N] [--scheduler tcp://HOST:PORT] [--out DIR]
    bt-arrange calibrate [--backend NAME] [--cell ideal|real|FILE.toml] [--views 20] [--out camera.toml]
                         [--seed N] [--gui] [--live] [--record DIR] [--json]
    bt-arrange examples
    bt-arrange info

Exit status: 0 when every object ends within the threshold, 1 when one does not, 2 for a usage,
tree-file or plan error (a one-line message, never a traceback), 3 when the run finished but its
record did not (a file of ``--record``/``--out`` could not be written: one line naming it, the results
printed as usual), 130 when interrupted, 141 when the reader of the output went away (``| head``),
143 when terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
import threading
from importlib import metadata
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from bt_arrange import backends, treefile
from bt_arrange.backends import Backend, Experiment, RunReport
from bt_arrange.errors import BackendError, BtArrangeError, RecordError

STACK = ("py-trees", "pybullet", "opencv-python-headless", "placo", "ruckig", "numpy")
EXIT_OK, EXIT_NOT_WITHIN, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE, EXIT_TERMINATED = 0, 1, 2, 130, 141, 143
#: The run finished, its record did not (a contract): a recorded file could not be written.
EXIT_RECORD = 3
EXIT_CODES_HELP = """exit status:
  0    every object ended within the threshold (measured by the camera)
  1    an object did not (outside, failed, or the time limit stopped the run)
  2    a usage, tree-file or plan error: one line on stderr, before anything moves
  3    the run finished, its record did not: a file of --record/--out could not be written
       (disk full, folder removed or read-only); one line names it, the results are printed,
       and every file is whole or absent
  130  interrupted (Ctrl-C); what was logged so far is kept
  141  the reader of the output went away (e.g. | head)
  143  terminated (SIGTERM, e.g. a cluster's job limit); what was logged so far is kept"""


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


def _info(args: argparse.Namespace) -> int:
    print(f"bt-arrange {metadata.version('bt-arrange')}")
    for package in STACK:
        try:
            print(f"  {package} {metadata.version(package)}")
        except metadata.PackageNotFoundError:
            print(f"  {package} missing (pip install -e . installs it)")
    for line in backends.load(args.backend).check():
        print(f"  {line}")
    return EXIT_OK


def _note_uncalibrated(cells: str, calibration: Path | None) -> None:
    """One line on stderr when a real cell runs on its nominal camera (a lens and a pose off by centimetres)."""
    if calibration is None and "real" in [c.strip() for c in cells.split(",")]:
        print(
            "bt-arrange: the real cell's camera is uncalibrated (its nominal intrinsics and pose): "
            "bt-arrange calibrate --cell real --out camera.toml, then --calibration camera.toml",
            file=sys.stderr,
        )


def _run(args: argparse.Namespace) -> int:
    _check_threshold_option(args.threshold_mm)
    _check_groot_options(args)
    module = treefile.load(args.tree_file)
    root = treefile.build_root(module, threshold_mm=args.threshold_mm)
    # A plan file names its own seed ([scene] seed); --seed overrides it.
    seed = args.seed if args.seed is not None else int(getattr(module, "default_seed", 0))
    backend = backends.load(args.backend)
    # Plans and XML trees scatter their parts through the chosen backend, never the default one behind its back.
    starts = treefile.scene(module, seed, backend=backend)
    _note_uncalibrated(args.cell, args.calibration)
    # The Groot2 ports are taken before the world is built: a port in use is one line before anything moves.
    with (
        _groot_publisher(root, args) as groot,
        backend.open_run(
            root,
            starts,
            gui=args.gui,
            record_dir=args.record,
            time_limit_s=args.time_limit_s,
            title=Path(args.tree_file).name,
            # Only a non-default cell is passed on: a backend without real-cell errors need not know the option.
            **({"cell": args.cell, "run_seed": seed} if args.cell != "ideal" else {}),
            **({"calibration": args.calibration} if args.calibration is not None else {}),
        ) as run,
    ):
        if groot is not None:
            run.transition_hooks.append(groot.on_transition)
            run.runner_hooks.append(lambda runner: _wait_for_groot(groot, args.groot_wait_s))
        if args.live:
            from bt_arrange.display import LiveView

            view = LiveView(sys.stderr if args.json else sys.stdout)
            run.tick_hooks.append(lambda tree_root: view.update(tree_root, run.elapsed_s()))
        if args.pace is not None:
            from bt_arrange.pacing import Pacer

            run.tick_hooks.append(Pacer(args.pace, run.elapsed_s).tick)
        fault: RecordError | None = None
        try:
            report = run.run()
        except RecordError as error:
            # The run finished, its record did not: the report is printed all the same, then the one line.
            fault, report = error, error.result
        if args.live:
            view.close()
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        _print_report(report, args, recorded=fault is None)
    if fault is not None:
        raise fault
    return EXIT_OK if report.all_within_threshold else EXIT_NOT_WITHIN


def _check_groot_options(args: argparse.Namespace) -> None:
    if args.groot is None:
        for option, value in (("--groot-wait-s", args.groot_wait_s), ("--groot-bind", args.groot_bind)):
            if value is not None:
                raise BtArrangeError(f"{option} serves a run to Groot2 only with --groot [PORT]")


def _groot_publisher(root: Any, args: argparse.Namespace) -> Any:
    """A context manager: the tree's Groot2 publisher (``--groot``), else None."""
    if args.groot is None:
        return contextlib.nullcontext(None)
    from bt_arrange.groot2 import Groot2Publisher

    publisher = Groot2Publisher(
        root, args.groot, bind=args.groot_bind or "127.0.0.1", tree_id=Path(args.tree_file).stem
    )
    print(
        f"bt-arrange: serving the tree to Groot2 on {publisher.address} "
        f"({len(publisher.nodes)} nodes; btview snapshot -p {publisher.port})",
        file=sys.stderr,
    )
    return publisher


def _wait_for_groot(publisher: Any, wait_s: float | None) -> None:
    if not wait_s:
        return
    print(f"bt-arrange: waiting up to {wait_s:g} s for a Groot2 client to fetch the tree", file=sys.stderr)
    if not publisher.wait_for_client(wait_s):
        print(f"bt-arrange: no Groot2 client after {wait_s:g} s; running", file=sys.stderr)


def _print_report(report: RunReport, args: argparse.Namespace, *, recorded: bool = True) -> None:
    def mm(value: float | None) -> str:
        return "-" if value is None else f"{value:.2f}"

    def deg(value: float | None) -> str:
        return "-" if value is None else f"{value:+.2f}"

    # A world without ground truth (a real cell) reports what the camera measured, and only that.
    has_truth = getattr(report, "ground_truth", True)
    truth_columns = (4, 6) if not has_truth else ()
    rows: list[tuple[str, ...]] = [
        ("object", "target x, y (mm), yaw (deg)", "placed", "pushed", "truth", "yaw", "yaw truth", "pushes", "status")
    ]
    for o in report.objects:
        x, y, yaw = o.target
        status = o.status if not o.reason else f"{o.status}: {o.reason}"
        rows.append(
            (
                o.name,
                f"{x * 1000:.1f}, {y * 1000:.1f}, {math.degrees(yaw):.1f}",
                mm(o.placed_offset_mm),
                mm(o.final_offset_mm),
                mm(o.final_offset_truth_mm),
                deg(getattr(o, "final_yaw_error_deg", None)),
                deg(getattr(o, "final_yaw_error_truth_deg", None)),
                str(o.pushes),
                status,
            )
        )
    rows = [tuple(cell for i, cell in enumerate(row) if i not in truth_columns) for row in rows]
    if report.objects:
        widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
        for row in rows:
            print("  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False)) + "  " + row[-1])
        yaw_threshold = getattr(report, "yaw_threshold_deg", None)
        yaw_text = f", yaw {yaw_threshold:g} deg" if yaw_threshold is not None else ""
        truth_text = (
            "truth = the simulator's ground truth (evaluation only)"
            if has_truth
            else "camera only: this world has no ground truth"
        )
        print(
            f"offsets in mm: placed and pushed measured by the camera after placing and after pushing; "
            f"yaw errors in deg (after pushing); {truth_text}; threshold {report.threshold_mm:g} mm{yaw_text}"
        )
    if args.record:
        if recorded:
            print(f"recorded images, report.json, transitions.jsonl and replay.html in {args.record}")
        else:
            print(f"the record in {args.record} is incomplete (the line on stderr says which file and why)")
    speed = report.sim_seconds / report.wall_seconds if report.wall_seconds > 0 else float("inf")
    ending = "stopped at the time limit" if report.timed_out else f"tree {report.tree_status}"
    if report.objects:
        within = sum(o.status == "within" for o in report.objects)
        yaw_threshold = getattr(report, "yaw_threshold_deg", None)
        yaw_text = f" and {yaw_threshold:g} deg" if yaw_threshold is not None else ""
        verdict = f"{within} of {len(report.objects)} objects within {report.threshold_mm:g} mm{yaw_text}; "
    else:
        verdict = ""
    # The last line is the verdict, and the exit status agrees with it (0 only when all are within).
    print(
        f"{Path(args.tree_file).name}: {verdict}{ending} after {report.sim_seconds:.1f} s of world time "
        f"in {report.wall_seconds:.1f} s ({speed:.1f}x real time)"
    )


def _experiment_of(backend: Backend) -> Experiment:
    experiment = backend.experiment
    if experiment is None:
        raise BackendError(f"backend {backend.name!r} cannot run the experiment")
    return experiment


#: The experiment's options beyond the Protocol's arguments, with their defaults: only a value other
#: than its default is passed on, so a backend that has not these options need not know them.
EXPERIMENT_OPTIONS = (
    ("cell", "ideal"),
    ("strategy", "paper"),
    ("thresholds", None),
    ("object_name", "cube"),
    ("executor", "local"),
    ("scheduler", None),
    ("calibration", None),
    ("resume", False),
)


def _experiment_options(
    backend: Backend, experiment: Experiment, args: argparse.Namespace, rows: list[str]
) -> dict[str, Any]:
    """The experiment's options (``EXPERIMENT_OPTIONS``), checked by the backend's ``check_options``.

    Only non-defaults are passed on; ``--workers`` is one of the Protocol's own arguments. With
    ``--object``, the check also gets the rows (a row may not know every type).
    """
    options = {key: getattr(args, key) for key, default in EXPERIMENT_OPTIONS if getattr(args, key) != default}
    check = getattr(experiment, "check_options", None)
    if options and check is None:
        raise BackendError(f"backend {backend.name!r} has no {', '.join('--' + key for key in options)}")
    if check is not None:
        check(
            cell=args.cell,
            strategy=args.strategy,
            workers=args.workers,
            **({"rows": rows} if "object_name" in options else {}),
            **{key: value for key, value in options.items() if key not in ("cell", "strategy")},
        )
    _note_uncalibrated(args.cell, args.calibration)
    return options


def _print_experiment(
    experiment: Experiment, summary: list[dict[str, Any]], out: Path, *, recorded: bool = True
) -> None:
    print(experiment.markdown_table(summary), end="")
    if not recorded:
        print(f"the record in {out} is incomplete (the line on stderr says which file and why)")
    elif any("folder" in row for row in summary):
        print(
            f"trials.jsonl, summary.json, summary.csv, summary.md and fig4.png in each folder of {out}; "
            f"campaign.json and thresholds.png (final offset and pushes against the threshold) in {out}"
        )
    else:
        print(f"trials.jsonl, summary.json, summary.csv, summary.md and fig4.png in {out}")


def _experiment(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    backend = backends.load(args.backend)
    experiment = _experiment_of(backend)
    # Every option is checked before the progress bar is drawn or a worker starts.
    rows = experiment.parse_rows(args.rows)
    if args.thresholds is not None and args.threshold_mm is not None:
        raise BtArrangeError("give --threshold-mm or --thresholds, not both")
    _check_threshold_option(args.threshold_mm)
    options = _experiment_options(backend, experiment, args, rows)
    try:
        backend.prepare_out(args.out)
    except BtArrangeError as error:
        raise BtArrangeError(f"--out {args.out}: {error}") from error
    # The total grows to the campaign's size (thresholds x cells) with the first finished trial.
    bar = tqdm(total=len(rows) * args.trials, unit="trial", desc="trials", file=sys.stderr, dynamic_ncols=True)

    def progress(record: dict, done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        where = f"{record['threshold_mm']:g} mm" + (
            f", {record['cell']} cell" if record.get("cell", "ideal") != "ideal" else ""
        )
        bar.set_postfix_str(f"{record['row']} #{record['trial']} at {where}: {record['status']}", refresh=False)
        bar.refresh()

    try:
        summary = experiment.run_experiment(
            rows,
            args.trials,
            args.seed,
            1.0 if args.threshold_mm is None else args.threshold_mm,
            args.out,
            workers=args.workers,
            on_trial=progress,
            **options,
        )
    except BtArrangeError as error:
        # Trials that errored, or files that could not be written: the summary is printed, then the one line.
        finished = error.result if isinstance(error, RecordError) else getattr(error, "summary", None)
        if finished:
            bar.close()
            _print_experiment(experiment, finished, args.out, recorded=not isinstance(error, RecordError))
        raise
    finally:
        bar.close()
    _print_experiment(experiment, summary, args.out)
    return EXIT_OK


def _calibrate(args: argparse.Namespace) -> int:
    from bt_arrange.calibration import matrix_rpy, write_calibration

    backend = backends.load(args.backend)
    open_calibration = getattr(backend, "open_calibration", None)
    if open_calibration is None:
        raise BackendError(f"backend {backend.name!r} cannot calibrate")
    out = Path(args.out)
    if out.parent and not out.parent.is_dir():
        raise BtArrangeError(f"--out {out}: the folder {out.parent} does not exist")
    with open_calibration(
        views=args.views,
        gui=args.gui,
        record_dir=args.record,
        time_limit_s=args.time_limit_s,
        **({"cell": args.cell, "run_seed": args.seed} if args.cell != "ideal" else {}),
    ) as run:
        if args.live:
            from bt_arrange.display import LiveView

            view = LiveView(sys.stderr if args.json else sys.stdout)
            run.tick_hooks.append(lambda tree_root: view.update(tree_root, run.elapsed_s()))
        outcome = run.run()
        if args.live:
            view.close()
        truth = run.true_camera() if hasattr(run, "true_camera") else None
    skipped = f"{outcome.unreachable} unreachable, {outcome.not_seen} with the board not seen"
    calibration = outcome.calibration
    if calibration is None:
        raise BtArrangeError(f"calibration failed: {outcome.reason} ({outcome.poses} poses: {skipped})")
    write_calibration(calibration, out)
    k, pose = calibration.intrinsics, calibration.camera_to_base
    result: dict[str, Any] = {
        "out": str(out),
        "views": calibration.views,
        "poses": outcome.poses,
        "unreachable": outcome.unreachable,
        "not_seen": outcome.not_seen,
        "reprojection_error_px": round(calibration.reprojection_error_px, 4),
        "hand_eye_residual_mm": round(calibration.hand_eye_residual_mm or 0.0, 4),
        "fx_px": round(k.fx_px, 3),
        "fy_px": round(k.fy_px, 3),
        "cx_px": round(k.cx_px, 3),
        "cy_px": round(k.cy_px, 3),
        "distortion": [round(v, 6) for v in k.distortion],
        "camera_to_base_mm": [round(float(v) * 1000, 3) for v in pose.position_m],
        "camera_to_base_rpy_deg": [round(math.degrees(a), 4) for a in matrix_rpy(pose.rotation)],
    }
    if truth is not None:
        true_k, true_pose = truth
        relative = true_pose.inverse() @ pose
        angle = math.acos(max(-1.0, min(1.0, (float(relative.rotation.trace()) - 1.0) / 2.0)))
        result["truth"] = {
            "position_error_mm": round(float(np.linalg.norm(relative.position_m)) * 1000, 4),
            "rotation_error_mrad": round(angle * 1000, 4),
            "fx_error_px": round(k.fx_px - true_k.fx_px, 4),
            "fy_error_px": round(k.fy_px - true_k.fy_px, 4),
            "cx_error_px": round(k.cx_px - true_k.cx_px, 4),
            "cy_error_px": round(k.cy_px - true_k.cy_px, 4),
        }
    if args.json:
        print(json.dumps(result))
        return EXIT_OK
    print(f"{calibration.views} views of {outcome.poses} poses ({skipped})")
    print(f"intrinsics: fx {k.fx_px:.2f}, fy {k.fy_px:.2f}, cx {k.cx_px:.2f}, cy {k.cy_px:.2f} px; "
          f"distortion {', '.join(f'{v:.5f}' for v in k.distortion)}")  # fmt: skip
    x, y, z = result["camera_to_base_mm"]
    roll, pitch, yaw = result["camera_to_base_rpy_deg"]
    print(f"camera to base: ({x:.2f}, {y:.2f}, {z:.2f}) mm, roll {roll:.3f}, pitch {pitch:.3f}, yaw {yaw:.3f} deg")
    print(
        f"reprojection error {calibration.reprojection_error_px:.3f} px; "
        f"hand-eye residual {calibration.hand_eye_residual_mm or 0.0:.3f} mm"
    )
    if truth is not None:
        t = result["truth"]
        print(
            f"against the simulator's true camera (evaluation only): {t['position_error_mm']:.3f} mm, "
            f"{t['rotation_error_mrad']:.3f} mrad; fx {t['fx_error_px']:+.2f}, fy {t['fy_error_px']:+.2f}, "
            f"cx {t['cx_error_px']:+.2f}, cy {t['cy_error_px']:+.2f} px"
        )
    print(f"wrote {out}")
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
        root, tree_id=stem, comment=f"generated from {Path(args.tree_file).name} by bt-arrange show (format xml)"
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
        "exit status: 0 calibrated (the file written), 2 a usage error or too few views (one line)",
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
    calibrate.add_argument("--cell", default="ideal", help=CELL_HELP)
    calibrate.set_defaults(handler=_calibrate)

    show = add_command(
        "show",
        "draw a tree file's tree without starting a simulator",
        "exit status: 0 drawn, 2 a usage or tree-file error",
    )
    show.add_argument("tree_file", metavar="TREE_FILE")
    show.add_argument(
        "--format",
        choices=("text", "dot", "png", "svg", "xml"),
        default="text",
        help="default text; xml: BehaviorTree.CPP v4 for Groot2",
    )
    show.add_argument("--blackboard", action="store_true", help="include the blackboard keys read and written")
    show.add_argument("--out", type=Path, metavar="FILE", help="write to FILE (png/svg default: <tree>.png/.svg)")
    show.set_defaults(handler=_show)

    rows_help = "\n".join(f"  {row:<16} {row_labels.get(row, '')}" for row in rows)
    experiment = add_command(
        "experiment",
        "reproduce the paper's Table 1 and Fig. 4 in simulation; sweeps; local or Dask",
        f"rows (--rows):\n{rows_help}\n\n"
        "exit status: 0 done, 2 a usage error or trials that errored (named; --resume reruns them),\n"
        "3 the campaign finished, its record did not (a file of --out could not be written: named),\n"
        "130 interrupted or 143 terminated (finished trials are kept; --resume continues)",
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

    examples = add_command(
        "examples",
        "list the example plans shipped in the package (bt-arrange run NAME runs one)",
        "exit status: 0 listed",
    )
    examples.set_defaults(handler=_examples)

    info = add_command(
        "info", "library versions, and a check that a headless cell starts", "exit status: 0 the cell starts"
    )
    add_backend(info)
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
    except BtArrangeError as error:
        print(f"bt-arrange: error: {error}", file=sys.stderr)
        return EXIT_USAGE
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
