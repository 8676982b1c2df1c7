"""The ``bt-arrange`` command line.

    bt-arrange run TREE_FILE [--seed N] [--threshold-mm X] [--gui] [--live] [--record DIR] [--json]
    bt-arrange show TREE_FILE [--format text|dot|png|svg|xml] [--blackboard] [--out FILE]
    bt-arrange experiment [--rows ...] [--trials 100] [--seed 0] [--threshold-mm 1.0] [--workers N] [--out DIR]
    bt-arrange info

Exit status: 0 when every object ends within the threshold, 1 when one does not, 2 for a usage,
tree-file or plan error (a one-line message, never a traceback), 130 when interrupted.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

from bt_arrange import treefile
from bt_arrange.errors import BtArrangeError

STACK = ("py-trees", "pybullet", "opencv-python-headless", "placo", "ruckig", "numpy")
EXIT_OK, EXIT_NOT_WITHIN, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


def _info(_: argparse.Namespace) -> int:
    print(f"bt-arrange {metadata.version('bt-arrange')}")
    for package in STACK:
        try:
            print(f"  {package} {metadata.version(package)}")
        except metadata.PackageNotFoundError:
            print(f"  {package} missing (pip install -e . installs it)")
    from bt_arrange.motion import default_urdf_path
    from bt_arrange_sim import WorkCell

    with WorkCell() as cell:
        cell.settle(0.1)
        print(f"  robot description: {default_urdf_path()}")
        print(f"  headless work cell: ok (TCP at {cell.arm.tcp_pose()})")
    return EXIT_OK


def _run(args: argparse.Namespace) -> int:
    if args.threshold_mm is not None and not (math.isfinite(args.threshold_mm) and args.threshold_mm > 0):
        raise BtArrangeError(f"--threshold-mm {args.threshold_mm:g} must be a positive number of millimetres")
    module = treefile.load(args.tree_file)
    root = treefile.build_root(module, threshold_mm=args.threshold_mm)
    starts = treefile.scene(module, args.seed)

    from bt_arrange_sim.runs import SimulatedRun

    with SimulatedRun(
        root,
        starts,
        gui=args.gui,
        record_dir=args.record,
        time_limit_s=args.time_limit_s,
        title=Path(args.tree_file).name,
    ) as run:
        if args.live:
            from bt_arrange.display import LiveView

            view = LiveView(sys.stderr if args.json else sys.stdout)
            run.tick_hooks.append(lambda tree_root: view.update(tree_root, run.cell.clock.now()))
        report = run.run()
        if args.live:
            view.close()
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        _print_report(report, args)
    return EXIT_OK if report.all_within_threshold else EXIT_NOT_WITHIN


def _print_report(report: Any, args: argparse.Namespace) -> None:
    def mm(value: float | None) -> str:
        return "-" if value is None else f"{value:.2f}"

    rows = [("object", "target x, y (m), yaw (deg)", "placed", "pushed", "truth", "pushes", "status")]
    for o in report.objects:
        x, y, yaw = o.target
        status = o.status if not o.reason else f"{o.status}: {o.reason}"
        rows.append(
            (
                o.name,
                f"{x:.3f}, {y:.3f}, {math.degrees(yaw):.1f}",
                mm(o.placed_offset_mm),
                mm(o.final_offset_mm),
                mm(o.final_offset_truth_mm),
                str(o.pushes),
                status,
            )
        )
    if report.objects:
        widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
        for row in rows:
            print("  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False)) + "  " + row[-1])
        print(
            f"offsets in mm: placed and pushed measured by the camera after placing and after pushing; "
            f"truth = the simulator's ground truth (evaluation only); threshold {report.threshold_mm:g} mm"
        )
    speed = report.sim_seconds / report.wall_seconds if report.wall_seconds > 0 else float("inf")
    ending = "stopped at the time limit" if report.timed_out else report.tree_status
    print(
        f"{Path(args.tree_file).name}: {ending} after {report.sim_seconds:.1f} s of world time "
        f"in {report.wall_seconds:.1f} s ({speed:.1f}x real time)"
    )
    if args.record:
        print(f"recorded images, report.json, transitions.jsonl and replay.html in {args.record}")


def _experiment(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from bt_arrange_sim.experiment import markdown_table, parse_rows, run_experiment

    rows = parse_rows(args.rows)
    if not (math.isfinite(args.threshold_mm) and args.threshold_mm > 0):
        raise BtArrangeError(f"--threshold-mm {args.threshold_mm:g} must be a positive number of millimetres")
    bar = tqdm(total=len(rows) * args.trials, unit="trial", desc="trials", file=sys.stderr, dynamic_ncols=True)

    def progress(record: dict, done: int, total: int) -> None:
        bar.n = done
        bar.set_postfix_str(f"{record['row']} #{record['trial']}: {record['status']}", refresh=False)
        bar.refresh()

    try:
        summary = run_experiment(
            rows, args.trials, args.seed, args.threshold_mm, args.out, workers=args.workers, on_trial=progress
        )
    finally:
        bar.close()
    print(markdown_table(summary), end="")
    print(f"trials, summary.json, summary.csv, summary.md and fig4.png in {args.out}")
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
        print(f"wrote {result}")
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
    parser = argparse.ArgumentParser(prog="bt-arrange", description="Behaviour trees for precise robotic arrangement.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {metadata.version('bt-arrange')}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = commands.add_parser("run", help="run a tree file in the simulated work cell (headless by default)")
    run.add_argument(
        "tree_file",
        metavar="TREE_FILE",
        help="a Python file exposing create_root() and create_scene(), or a BehaviorTree.CPP .xml tree",
    )
    run.add_argument("--seed", type=int, default=0, help="seed of the scene (where the cubes start); default 0")
    run.add_argument("--threshold-mm", type=float, help="accuracy threshold in mm (the tree file's default if absent)")
    run.add_argument("--gui", action="store_true", help="open the pybullet window (needs a display)")
    run.add_argument("--live", action="store_true", help="redraw the tree with its statuses while it runs")
    run.add_argument(
        "--record", type=Path, metavar="DIR", help="save top-camera images, the transition log and replay.html"
    )
    run.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    run.add_argument(
        "--time-limit-s", type=float, default=1800.0, help="stop after this much world time (default 1800 s)"
    )
    run.set_defaults(handler=_run)

    show = commands.add_parser("show", help="draw a tree file's tree without starting a simulator")
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

    experiment = commands.add_parser("experiment", help="reproduce the paper's Table 1 and Fig. 4 in simulation")
    experiment.add_argument(
        "--rows",
        default="system,translation,orientation,grasp-estimator",
        help="comma-separated rows (default: all four)",
    )
    experiment.add_argument("--trials", type=int, default=100, help="trials per row (default 100)")
    experiment.add_argument("--seed", type=int, default=0, help="experiment seed (default 0)")
    experiment.add_argument("--threshold-mm", type=float, default=1.0, help="accuracy threshold in mm (default 1)")
    experiment.add_argument("--workers", type=int, default=1, help="worker processes, each with its own world")
    experiment.add_argument(
        "--out", type=Path, default=Path("runs/experiment"), help="output folder (default runs/experiment)"
    )
    experiment.set_defaults(handler=_experiment)

    info = commands.add_parser("info", help="library versions, and a check that a headless cell starts")
    info.set_defaults(handler=_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bt-arrange`` console script."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except BtArrangeError as error:
        print(f"bt-arrange: error: {error}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("bt-arrange: interrupted; what was logged so far is kept", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
