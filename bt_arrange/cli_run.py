"""``bt-arrange run``: a tree file, plan or XML tree run on a backend, with its report, Groot2 and pacing."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
from pathlib import Path
from typing import Any

from bt_arrange import backends, treefile
from bt_arrange.backends import RunReport
from bt_arrange.cli_common import (
    EXIT_NOT_WITHIN,
    EXIT_OK,
    _check_threshold_option,
    connect_backend,
)
from bt_arrange.errors import BtArrangeError, RecordError

#: How a real cell's camera is calibrated: what the refusal of ``--cell real`` without ``--calibration`` says.
CALIBRATE_COMMAND = "bt-arrange calibrate --cell real --out camera.toml"


def _run(args: argparse.Namespace) -> int:
    _check_threshold_option(args.threshold_mm)
    _check_groot_options(args)
    if args.foxglove is None and args.foxglove_bind is not None:
        raise BtArrangeError("--foxglove-bind serves a run to Foxglove only with --foxglove [PORT]")
    _check_calibrated(args.cell, args.calibration)
    module = treefile.load(args.tree_file)
    root = treefile.build_root(module, threshold_mm=args.threshold_mm)
    _warn_tight_sides(root)
    # A plan file names its own seed ([scene] seed); --seed overrides it.
    seed = args.seed if args.seed is not None else int(getattr(module, "default_seed", 0))
    backend = backends.load(args.backend)
    connect_backend(backend, args)
    inject = backends.check_inject(backend, args.inject) if args.inject is not None else []
    safety = _safety_options(backend, args)
    # Plans and XML trees scatter their parts through the chosen backend, never the default one behind its back.
    starts = treefile.scene(module, seed, backend=backend)
    # The Groot2 ports are taken before the world is built: a port in use is one line before anything moves.
    with (
        _groot_publisher(root, args) as groot,
        _foxglove_server(args) as foxglove,
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
            # The errors are drawn from the run's seed, as the scene is (a backend without them refused them above).
            **({"inject": inject, "inject_seed": seed} if inject else {}),
            # A speed fraction and a dry run only where asked for (a backend without them refused them above).
            **safety,
        ) as run,
    ):
        if groot is not None:
            run.transition_hooks.append(groot.on_transition)
            run.runner_hooks.append(lambda runner: _wait_for_groot(groot, args.groot_wait_s))
        if foxglove is not None:
            backends.require(run, backends.FoxgloveRun, "stream a run to Foxglove (--foxglove)", name=args.backend)
            run.foxglove_live = foxglove
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
    dry_run = getattr(report, "dry_run", None)
    if dry_run is not None:
        # What a dry run could plan and what it could not: on stderr, so --json stays one object.
        print(f"bt-arrange: dry run: {dry_run['summary']}", file=sys.stderr if args.json else sys.stdout)
    safety_stop = getattr(report, "safety_stop", "")
    if safety_stop:
        # The one line a lab reads first: what stopped the run. Nothing moved after it.
        print(f"bt-arrange: safety stop: {safety_stop}", file=sys.stderr)
        if fault is not None:
            raise fault
        return EXIT_NOT_WITHIN
    if fault is not None:
        raise fault
    if dry_run is not None:
        return EXIT_OK if dry_run["refused"] == 0 else EXIT_NOT_WITHIN
    return EXIT_OK if report.all_within_threshold else EXIT_NOT_WITHIN


def _warn_tight_sides(root: Any) -> None:
    """Before anything moves: each side a neighbour leaves the pads no room to push from, on stderr."""
    from bt_arrange.plan.push_room import warnings
    from bt_arrange.trees import plan_of

    for line in warnings(plan_of(root)):
        print(f"bt-arrange: warning: {line}", file=sys.stderr)


def _safety_options(backend: backends.Backend, args: argparse.Namespace) -> dict[str, Any]:
    """``speed_fraction`` and ``dry_run`` for ``open_run``, only when given; refused by a backend without them."""
    options: dict[str, Any] = {}
    if args.speed_fraction is not None:
        backends.require(backend, backends.SafetyBackend, "run at a speed fraction (--speed-fraction)")
        options["speed_fraction"] = args.speed_fraction
    if args.dry_run:
        backends.require(backend, backends.DryRunBackend, "plan a run without moving (--dry-run)")
        options["dry_run"] = True
    return options


def _check_calibrated(cell: str, calibration: Path | None) -> None:
    """Refuse a real cell on its nominal camera (a lens and a pose off by centimetres: every part would fail)."""
    if calibration is None and cell.strip() == "real":
        raise BtArrangeError(
            f"--cell real needs a calibrated camera (its nominal one puts parts centimetres off): "
            f"{CALIBRATE_COMMAND}, then add --calibration camera.toml"
        )


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
        f"({len(publisher.served)} nodes; btview snapshot -p {publisher.port})",
        file=sys.stderr,
    )
    return publisher


def _foxglove_server(args: argparse.Namespace) -> Any:
    """A context manager: the live Foxglove server (``--foxglove``), else None; bound before the world is built."""
    if args.foxglove is None:
        return contextlib.nullcontext(None)
    from bt_arrange.foxglove.streams import LiveServer

    server = LiveServer(args.foxglove, bind=args.foxglove_bind or "127.0.0.1")
    print(f"bt-arrange: serving the run to Foxglove on {server.address} (read-only)", file=sys.stderr)
    return server


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
        (
            "object",
            "target x, y (mm), yaw (deg)",
            "placed",
            "pushed",
            "truth",
            "yaw",
            "yaw truth",
            "pushes",
            "set down",
            "placed again",
            "regrasps",
            "separated",
            "held look",
            "moved aside",
            "status",
        )
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
                str(getattr(o, "set_downs", 0)),
                str(getattr(o, "placed_again", 0)),
                str(getattr(o, "regrasps_after_placing", 0)),
                str(getattr(o, "separations", 0)),
                getattr(o, "held_look", "") or "-",
                ", ".join(getattr(o, "moved_aside", [])) or "-",
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
            "offsets in mm: placed and pushed measured by the camera after placing (the first time) and after "
            "pushing; "
            "set down: set down where picked, to look again and pick centred; placed again: placed at the "
            "target again after the first placing; regrasps: picked up again after placing; separated: touching "
            "parts of its colour pushed apart before its pick; held look: among neighbours, measured in the "
            "fingers (held look) or set down to look again (set down); moved aside: neighbours pushed aside for a "
            "push they blocked, and put back; "
            f"yaw errors in deg (after pushing); {truth_text}; threshold {report.threshold_mm:g} mm{yaw_text}"
        )
        source = getattr(report, "camera_margin_source", "")
        if source:
            print(f"within: the camera's offset plus its own error under the threshold; camera error {source}")
    injected = getattr(report, "injected", None)
    if injected is not None:
        print(_injected_line(injected))
    if args.record:
        if recorded:
            mcap = ", run.mcap" if (Path(args.record) / "run.mcap").is_file() else ""
            print(f"recorded images, report.json, transitions.jsonl{mcap} and replay.html in {args.record}")
        else:
            print(f"the record in {args.record} is incomplete (the line on stderr says which file and why)")
    speed = report.sim_seconds / report.wall_seconds if report.wall_seconds > 0 else float("inf")
    timing = f"after {report.sim_seconds:.1f} s of world time in {report.wall_seconds:.1f} s ({speed:.1f}x real time)"
    # The last line is the verdict, and the exit status agrees with it (0 only when all are within): how many
    # parts are within and each that is not, with its offset and why; the tree's status only without parts.
    head, missed = report.within_text(), report.not_within()
    print(f"{Path(args.tree_file).name}: {head} {timing}" + (f"; not within: {missed}" if missed else ""))


def _injected_line(records: list[dict[str, Any]]) -> str:
    """One line: each injected error and the parts it went into (a part it never reached says so)."""
    parts: dict[str, list[str]] = {}
    for record in records:
        part = str(record.get("part"))
        parts.setdefault(str(record.get("error")), []).append(part if record.get("fired") else f"{part} (not reached)")
    if not parts:
        return "injected: nothing (no part to inject into)"
    listed = "; ".join(f"{error} into {', '.join(names)}" for error, names in parts.items())
    return f"injected: {listed} (the experiment's magnitudes; what each did: --json)"
