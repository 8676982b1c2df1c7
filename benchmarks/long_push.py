"""A staged piece's long push home: whether it squares a turned piece and carries it onto its line.

    python benchmarks/long_push.py [--tiles 1 3 4] [--turns-deg 0.5 1 1.5 2 3] [--across-mm 1 2 3 4]
                                   [--push-mm 20] [--across-limit-mm 1]

One piece of the example fresco (``bt_arrange/examples/fresco.toml``, tile ``--tiles``) is set on the
table of the ideal pybullet cell ``--push-mm`` behind its target along its widest square push, beside
that push's line by each of ``--across-mm`` (both sides) and turned by each of ``--turns-deg`` off its
target's yaw. A tree of Inspect, one ``Push`` among neighbours (only that push free, as a staged
piece's way home) and Inspect runs; ground truth (the simulator's, evaluation only) gives where the
piece ended: its offset from the target and its yaw error. ``--across-limit-mm`` holds the push to
that much across (the rule before: 1 mm for a piece turned 1 deg or more), to compare.

One JSON line per run as it ends; the last line counts the runs within 0.5 mm and 0.5 deg.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys

import numpy as np
import py_trees

from bt_arrange import examples, treefile
from bt_arrange.behaviours import Inspect, Push, square_pushes
from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import ObjectStart, ObjectType
from bt_arrange.shapes import ROBOTIQ_2F85
from bt_arrange_sim.pybullet.runs import SimulatedRun

#: Where the target lies (m, m, rad): inside the camera's view, turned off the table's axes.
TARGET = PlanarPose(0.5, 0.0, 0.3)
#: What counts as landed (mm, deg).
WITHIN_MM, WITHIN_DEG = 0.5, 0.5


def tile_type(index: int) -> ObjectType:
    """The example fresco's piece ``index`` (its fracture's own seed), named ``tile``."""
    path = examples.path_of("fresco")
    assert path is not None
    targets = treefile.build_root(treefile.load(path)).targets  # type: ignore[attr-defined]
    if not 0 <= index < len(targets):
        raise SystemExit(f"long_push.py: error: --tiles {index}: the example fresco has tiles 0 to {len(targets) - 1}")
    return dataclasses.replace(targets[index].object_type, name="tile")


def run_once(kind: ObjectType, turn_deg: float, across_mm: float, push_mm: float) -> dict:
    """One piece, one long push home; where it ended by truth."""
    name, push = max(kind.shape.named_pushes(ROBOTIQ_2F85).items(), key=lambda item: item[1].opening_m)
    heading = TARGET.yaw_rad + push.heading_rad
    along = np.array([math.cos(heading), math.sin(heading)])
    beside = np.array([-along[1], along[0]])
    x, y = np.array([TARGET.x_m, TARGET.y_m]) - push_mm / 1000 * along + across_mm / 1000 * beside
    start = ObjectStart("red", float(x), float(y), TARGET.yaw_rad + math.radians(turn_deg), "tile", kind)
    py_trees.blackboard.Blackboard.clear()
    root = py_trees.composites.Sequence(
        "a long push home",
        memory=True,
        children=[
            py_trees.behaviours.SetBlackboardVariable("the target", "/tile/target", TARGET, overwrite=True),
            Inspect("inspect", "tile", "red", object_type=kind),
            Push("push home", "tile", object_type=kind, towards=(name,), threshold_mm=0.8, yaw_threshold_deg=0.8),
            Inspect("inspect again", "tile", "red", object_type=kind),
        ],
    )
    pushed: list[str] = []
    with SimulatedRun(root, [start]) as run:
        run.transition_hooks.append(
            lambda change: pushed.append(change.feedback) if change.kind == "Push" and change.new != "RUNNING" else None
        )
        report = run.run()
        end_x, end_y, end_yaw = run.cell.part_planar_truth("tile")
    c, s = math.cos(TARGET.yaw_rad), math.sin(TARGET.yaw_rad)
    dx, dy = end_x - TARGET.x_m, end_y - TARGET.y_m
    return {
        "tile_push": name,
        "turn_deg": turn_deg,
        "across_mm": across_mm,
        "status": report.tree_status,
        "push": pushed[-1] if pushed else "",
        "final_mm": round(1000 * math.hypot(c * dx + s * dy, -s * dx + c * dy), 3),
        "final_yaw_deg": round(math.degrees(math.remainder(end_yaw - TARGET.yaw_rad, kind.shape.symmetry_rad)), 3),
    }


def main(argv: list[str] | None = None) -> int:
    """Every tile, turn and offset beside the line; a JSON line each and the count landed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiles", type=int, nargs="+", default=[1, 3, 4], help="pieces of the example fresco")
    parser.add_argument("--turns-deg", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0, 3.0])
    parser.add_argument("--across-mm", type=float, nargs="+", default=[1.0, 2.0, 3.0, 4.0], help="each side")
    parser.add_argument("--push-mm", type=float, default=20.0, help="the push's length along")
    parser.add_argument("--across-limit-mm", type=float, help="hold the push to this much across (to compare)")
    args = parser.parse_args(argv)
    if args.across_limit_mm is not None:
        held_mm = args.across_limit_mm
        square_pushes.long_push_across_limit_mm = lambda distance_mm: held_mm
    landed = total = 0
    for index in args.tiles:
        kind = tile_type(index)
        for turn_deg in args.turns_deg:
            for across_mm in (a * side for a in args.across_mm for side in (1.0, -1.0)):
                result = {"tile": index, **run_once(kind, turn_deg, across_mm, args.push_mm)}
                print(json.dumps(result), flush=True)
                total += 1
                landed += result["final_mm"] < WITHIN_MM and abs(result["final_yaw_deg"]) < WITHIN_DEG
    limit = "" if args.across_limit_mm is None else f", held to {args.across_limit_mm:g} mm across"
    within = f"within {WITHIN_MM} mm and {WITHIN_DEG} deg"
    print(f"{landed} of {total} long pushes of {args.push_mm:g} mm ended {within}{limit}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
