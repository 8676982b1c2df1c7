"""``python -m bt_arrange_sim.ursim TREE_OR_PLAN --seed N [--truth FILE]``: a UR controller backed by the pybullet cell.

Builds the scene ``bt-arrange run TREE_OR_PLAN --seed N`` builds on the sim backend, opens the
controller's ports, prints one line ``ready camera=SPEC`` on stdout once they accept connections,
and runs the cell in real time until SIGTERM or SIGINT; then it writes every part's true pose to
``--truth FILE`` (JSON: name to ``[x_m, y_m, z_m, yaw_rad]``) and exits 0. Everything else it
says goes to stderr. See docs/ursim.md.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
from pathlib import Path
from typing import Any

#: The ports a CB3 serves them on (the client libraries connect to these).
DASHBOARD_PORT = 29999
SCRIPT_PORT = 30003
RTDE_PORT = 30004
ROBOTIQ_PORT = 63352
DEFAULT_CAMERA_PORT = 8081
DEFAULT_FAULTS_PORT = 30099


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """The command line."""
    parser = argparse.ArgumentParser(
        prog="python -m bt_arrange_sim.ursim",
        description="A UR5 CB3 controller (dashboard, RTDE, script port, Robotiq socket, a network camera) "
        "on the pybullet work cell, in real time.",
    )
    parser.add_argument("tree_or_plan", nargs="?", help="the tree or plan whose scene to build (as bt-arrange run)")
    parser.add_argument("--seed", type=int, default=None, help="the scene's seed (default: the plan's own, or 0)")
    parser.add_argument("--truth", type=Path, default=None, help="where to write the parts' true poses at exit")
    parser.add_argument("--cell", default="ideal", help="ideal, real or a cell file (.toml), as bt-arrange run --cell")
    parser.add_argument("--host", default="127.0.0.1", help="the loopback address to serve on (default 127.0.0.1)")
    parser.add_argument("--camera-port", type=int, default=DEFAULT_CAMERA_PORT, help="the camera's HTTP port")
    parser.add_argument("--faults-port", type=int, default=DEFAULT_FAULTS_PORT, help="the fault injection port")
    parser.add_argument(
        "--board", action="store_true", help="the ChArUco board on the flange and the sheet on the table (calibration)"
    )
    parser.add_argument(
        "--realtime-factor", type=float, default=1.0, help="world seconds per wall second (default 1: real time)"
    )
    parser.add_argument("--parent-pid", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.tree_or_plan is None and not args.board:
        parser.error("a tree or plan is needed (or --board for a calibration cell)")
    if not args.realtime_factor > 0:
        parser.error("--realtime-factor must be positive")
    return args


def open_scene(args: argparse.Namespace) -> tuple[Any, Any]:
    """The cell and what owns it (closed at exit): the run's scene, or the calibration cell with ``--board``."""
    from bt_arrange import backends, treefile

    # The sim backend, found through its entry point as `bt-arrange run` finds it: its runs build the cell.
    backend: Any = backends.load("sim")
    if args.board:
        # The calibration procedure's cell (board on the flange, sheet on the table); its tree never ticks.
        calibration = backend.open_calibration(views=2, cell=args.cell, run_seed=args.seed or 0)
        return calibration.world.cell, calibration
    module = treefile.load(args.tree_or_plan)
    root = treefile.build_root(module)
    seed = args.seed if args.seed is not None else int(getattr(module, "default_seed", 0))
    starts = treefile.scene(module, seed, backend=backend)
    options = {"cell": args.cell, "run_seed": seed} if args.cell != "ideal" else {}
    run = backend.open_run(root, starts, **options)
    return run.cell, run


def end_with_parent(parent_pid: int) -> None:
    """SIGTERM this process when ``parent_pid`` dies (Linux's parent-death signal), as if it were stopped.

    Set in the child itself (not between fork and exec, where taking a lock can deadlock a threaded
    parent); a parent that is already gone ends it at once.
    """
    if sys.platform.startswith("linux"):
        import ctypes

        set_parent_death_signal = 1  # PR_SET_PDEATHSIG
        ctypes.CDLL(None, use_errno=True).prctl(set_parent_death_signal, signal.SIGTERM)
    if os.getppid() != parent_pid:
        os.kill(os.getpid(), signal.SIGTERM)


def write_truth(path: Path, truth: dict[str, list[float]]) -> None:
    """The truth file, written whole (a temporary file renamed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    partial.write_text(json.dumps(truth) + "\n")
    partial.replace(path)


def main(argv: list[str] | None = None) -> int:
    """Run the controller until SIGTERM or SIGINT; 0 after a clean stop, 2 when it cannot start."""
    args = parse_args(argv)
    # stdout carries the ready line alone: anything else printed (by us or a library) goes to stderr.
    sys.stdout.flush()
    ready_out = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr

    from bt_arrange_sim.ursim.controller import Controller

    stop_requested = []

    def request_stop(signum: int, frame: object) -> None:
        stop_requested.append(signum)
        if controller_box:
            controller_box[0].stop()

    controller_box: list[Controller] = []
    signal.signal(signal.SIGTERM, request_stop)
    signal.signal(signal.SIGINT, request_stop)
    if args.parent_pid is not None:
        end_with_parent(args.parent_pid)

    from bt_arrange.errors import BtArrangeError

    try:
        cell, owner = open_scene(args)
    except (BtArrangeError, OSError) as error:
        print(f"ursim: {error}", file=sys.stderr)
        return 2
    controller = Controller(cell, realtime_factor=args.realtime_factor)
    controller_box.append(controller)
    if stop_requested:
        controller.stop()
    servers = start_servers(controller, args)
    if servers is None:
        owner.close()
        return 2
    camera_spec = f"http://{args.host}:{args.camera_port}/"
    ready_out.write(f"ready camera={camera_spec}\n")
    ready_out.flush()
    print(
        f"ursim: serving on {args.host}: dashboard {DASHBOARD_PORT}, script {SCRIPT_PORT}, RTDE {RTDE_PORT}, "
        f"Robotiq {ROBOTIQ_PORT}, camera {args.camera_port}, faults {args.faults_port}",
        file=sys.stderr,
    )
    try:
        controller.run()
    finally:
        truth = controller.part_truth()
        if args.truth is not None:
            write_truth(args.truth, truth)
        print(
            f"ursim: stopped after {controller.snapshot.time_s:.2f} s of world time, "
            f"real-time ratio {controller.realtime_ratio():.3f}",
            file=sys.stderr,
        )
        for server in servers:
            with contextlib.suppress(Exception):
                server.close()
        with contextlib.suppress(Exception):
            owner.close()
    return 0


def start_servers(controller: Any, args: argparse.Namespace) -> list[Any] | None:
    """Every port bound and serving; None (the reason on stderr) when one cannot be bound."""
    from bt_arrange_sim.ursim.camera import CameraServer
    from bt_arrange_sim.ursim.ports import DashboardServer, FaultsServer, GripperServer, ScriptServer
    from bt_arrange_sim.ursim.rtde_server import RtdeServer
    from bt_arrange_sim.ursim.servers import ClientRegistry

    clients = ClientRegistry()
    plan = [
        (DashboardServer, DASHBOARD_PORT),
        (ScriptServer, SCRIPT_PORT),
        (RtdeServer, RTDE_PORT),
        (GripperServer, ROBOTIQ_PORT),
        (FaultsServer, args.faults_port),
        (CameraServer, args.camera_port),
    ]
    servers: list[Any] = []
    for kind, port in plan:
        try:
            servers.append(kind(controller, args.host, port, clients))
        except OSError as error:
            print(f"ursim: cannot serve on {args.host}:{port} ({kind.__name__}): {error.strerror}", file=sys.stderr)
            for server in servers:
                server.close()
            return None
    for server in servers:
        server.start()
    return servers


if __name__ == "__main__":
    sys.exit(main())
