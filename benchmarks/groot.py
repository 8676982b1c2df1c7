"""Overhead of serving a run to Groot2: the four-cube tree with and without the publisher and a 10 Hz client.

    python benchmarks/groot.py [--json] [--pairs 5] [--hz 10] [--tree trees/four_cubes.py]

Runs, in one process, ``--pairs`` pairs of the same simulated trial (same seed), each pair once
plain and once with a ``Groot2Publisher`` fed by the session's transition hook while a client
thread asks for the status buffer ``--hz`` times a second (as ``btview watch`` or Groot2 do) and
for the blackboard once a second. The order inside a pair alternates so that a machine warming
up or slowing down does not favour one side. Each run's wall time is the session's own
(``report.wall_seconds``: the ticks and the world's steps, not the cell's construction).

Key figure: ``overhead_ratio``, the summed wall time with the publisher over the summed wall time
without it (the target is under 1.05); beside it ``median_pair_ratio`` and ``hook_share``, the
fraction of the served runs' wall time spent in the publisher's transition hook (what it costs the
tree's thread itself, free of the machine's noise) and ``server_cpu_share``, the server thread's CPU
time over the same wall time (what answering the client costs, on another core or in turns).
Wall-clock figures depend on the machine and on what else runs on it: compare ratios from one run.
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from pathlib import Path

import zmq

from bt_arrange import treefile
from bt_arrange.groot2 import Groot2Publisher, protocol
from bt_arrange_sim.pybullet.runs import SimulatedRun

ROOT = Path(__file__).resolve().parent.parent


class PollingClient(threading.Thread):
    """A REQ client asking for the statuses at ``hz`` and the blackboard once a second, until stopped."""

    def __init__(self, port: int, hz: float, tree_id: str) -> None:
        super().__init__(daemon=True)
        self.port, self.period_s, self.tree_id = port, 1.0 / hz, tree_id
        self.stop = threading.Event()
        self.replies = 0

    def run(self) -> None:
        """Fetch the tree once, then poll until stopped."""
        context = zmq.Context()
        sock = context.socket(zmq.REQ)
        sock.setsockopt(zmq.RCVTIMEO, 2000)
        sock.setsockopt(zmq.LINGER, 0)
        sock.connect(f"tcp://127.0.0.1:{self.port}")
        request_id, last_board = 0, 0.0
        try:
            sock.send_multipart([protocol.pack_header(protocol.FULLTREE, request_id)])
            sock.recv_multipart()
            while not self.stop.wait(self.period_s):
                request_id += 1
                frames = [protocol.pack_header(protocol.STATUS, request_id)]
                if time.monotonic() - last_board >= 1.0:
                    frames = [protocol.pack_header(protocol.BLACKBOARD, request_id), self.tree_id.encode()]
                    last_board = time.monotonic()
                sock.send_multipart(frames)
                sock.recv_multipart()
                self.replies += 1
        finally:
            context.destroy(linger=0)


def one_run(tree: Path, seed: int, groot: bool, port: int, hz: float) -> dict:
    module = treefile.load(tree)
    root = treefile.build_root(module)
    starts = treefile.scene(module, seed)
    publisher = Groot2Publisher(root, port, tree_id=tree.stem) if groot else None
    client = PollingClient(port, hz, tree.stem) if publisher is not None else None
    spent = [0.0]
    try:
        with SimulatedRun(root, starts) as run:
            if publisher is not None and client is not None:
                run.transition_hooks.append(timed(publisher.on_transition, spent))
                client.start()
            report = run.run()
    finally:
        if client is not None:
            client.stop.set()
            client.join()
        if publisher is not None:
            publisher.close()
    return {
        "groot": groot,
        "wall_s": round(report.wall_seconds, 3),
        "world_s": round(report.sim_seconds, 3),
        "replies": client.replies if client is not None else 0,
        "transitions": len(report.transitions),
        "hook_s": round(spent[0], 5),
        "server_cpu_s": round(publisher.server_cpu_s, 5) if publisher is not None else 0.0,
    }


def timed(hook, spent: list[float]):
    """``hook``, adding the wall time it takes in the tree's thread to ``spent[0]``."""

    def call(transition) -> None:
        start = time.perf_counter()
        hook(transition)
        spent[0] += time.perf_counter() - start

    return call


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, default=ROOT / "trees" / "four_cubes.py")
    parser.add_argument("--pairs", type=int, default=5)
    parser.add_argument("--hz", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--port", type=int, default=protocol.DEFAULT_PORT + 100)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    runs = []
    for pair in range(args.pairs):
        for groot in (pair % 2 == 1, pair % 2 == 0):
            runs.append(one_run(args.tree, args.seed, groot, args.port, args.hz))
    plain = sum(r["wall_s"] for r in runs if not r["groot"])
    served = sum(r["wall_s"] for r in runs if r["groot"])
    pairs = [runs[i : i + 2] for i in range(0, len(runs), 2)]
    pair_ratios = sorted(
        next(r["wall_s"] for r in pair if r["groot"]) / next(r["wall_s"] for r in pair if not r["groot"])
        for pair in pairs
    )
    hook_share = sum(r["hook_s"] for r in runs if r["groot"]) / served if served else 0.0
    server_share = sum(r["server_cpu_s"] for r in runs if r["groot"]) / served if served else 0.0
    result = {
        "tree": args.tree.name,
        "hz": args.hz,
        "runs": runs,
        "plain_wall_s": round(plain, 3),
        "groot_wall_s": round(served, 3),
        "overhead_ratio": round(served / plain, 4),
        "median_pair_ratio": round(pair_ratios[len(pair_ratios) // 2], 4),
        "hook_share": round(hook_share, 5),
        "server_cpu_share": round(server_share, 5),
    }
    if args.json:
        print(json.dumps(result))
        return
    for run in runs:
        label = "with Groot2" if run["groot"] else "plain      "
        print(f"{label}  wall {run['wall_s']:7.2f} s  world {run['world_s']:6.2f} s  replies {run['replies']}")
    print(f"overhead ratio (with / without): {result['overhead_ratio']:.4f}  (target < 1.05)")
    print(f"median ratio of a pair: {result['median_pair_ratio']:.4f}")
    print(f"the publisher's share of the tree thread's wall time (transition hook): {hook_share:.3%}")
    print(f"the server thread's CPU time over the served runs' wall time: {server_share:.3%}")


if __name__ == "__main__":
    main()
