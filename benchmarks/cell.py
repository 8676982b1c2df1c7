"""Pick-and-place benchmark of the work cell, steered by ground truth.

    python benchmarks/cell.py --trials 50 --seed 0 --json

Each trial builds a fresh headless cell, puts a cube at a random reachable pose, picks it and
places it at a random target, and measures the cube's true planar distance to the target after
release. Perception is not involved: the robot is told the cube's true pose, so this measures
what the arm, the gripper and the physics can do. Prints one JSON object with ``--json``.
``--out FILE`` appends every trial to a JSON-lines file as soon as it ends.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from bt_arrange.geometry import fold_yaw
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.scripted import ScriptedPickPlace

#: Where cubes start and land: in the top camera's view, within comfortable reach of the UR5.
X_RANGE_M = (0.32, 0.68)
Y_RANGE_M = (-0.30, 0.30)
MAX_RADIUS_M = 0.72


def random_table_pose(rng: np.random.Generator) -> tuple[float, float, float]:
    """A planar pose (x_m, y_m, yaw_rad) the arm reaches with the gripper pointing down."""
    while True:
        x, y = rng.uniform(*X_RANGE_M), rng.uniform(*Y_RANGE_M)
        if math.hypot(x, y) <= MAX_RADIUS_M:
            return x, y, rng.uniform(-math.pi, math.pi)


def run_trial(seed: int, index: int) -> dict:
    """One pick and place; returns its measurements (all ground truth)."""
    rng = np.random.default_rng([seed, index])
    start, target = random_table_pose(rng), random_table_pose(rng)
    wall_start = time.perf_counter()
    with WorkCell() as cell:
        cell.add_cube("red", *start)
        cell.settle(0.3)
        script = ScriptedPickPlace(cell)
        pick = script.pick(*cell.part_planar_truth("red"))
        if pick.grasped:
            script.place(*target)
        x, y, yaw = cell.part_planar_truth("red")
        sim_seconds = cell.clock.now()
    return {
        "trial": index,
        "start": [round(v, 6) for v in start],
        "target": [round(v, 6) for v in target],
        "grasped": pick.grasped,
        "grip_width_mm": round(pick.grip_width_m * 1000, 3),
        "placed_error_mm": math.hypot(x - target[0], y - target[1]) * 1000 if pick.grasped else None,
        "yaw_error_deg": abs(math.degrees(fold_yaw(yaw - target[2]))) if pick.grasped else None,
        "sim_seconds": sim_seconds,
        "wall_seconds": time.perf_counter() - wall_start,
    }


def summarise(trials: list[dict]) -> dict:
    """The benchmark's figures over all trials."""
    placed = np.array([t["placed_error_mm"] for t in trials if t["grasped"]])
    yaw = np.array([t["yaw_error_deg"] for t in trials if t["grasped"]])
    sim_seconds = sum(t["sim_seconds"] for t in trials)
    wall_seconds = sum(t["wall_seconds"] for t in trials)

    def stats(values: np.ndarray, keys: tuple[str, ...]) -> dict:
        if values.size == 0:
            return dict.fromkeys(keys)
        table = {"mean": values.mean(), "std": values.std(), "max": values.max()}
        return {key: round(float(table[key]), 4) for key in keys}

    return {
        "benchmark": "cell",
        "steered_by": "ground truth (no perception): measures arm, gripper and physics only",
        "trials": len(trials),
        "placed_error_mm": stats(placed, ("mean", "std", "max")),
        "yaw_error_deg": stats(yaw, ("mean", "max")),
        "grasp_failures": sum(not t["grasped"] for t in trials),
        "sim_seconds": round(sim_seconds, 2),
        "wall_seconds": round(wall_seconds, 2),
        "real_time_factor": round(sim_seconds / wall_seconds, 1),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=10, help="pick-and-place trials (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--out", type=Path, help="append each trial to this JSON-lines file as it ends")
    args = parser.parse_args(argv)
    if args.trials < 1:
        parser.error(f"--trials must be at least 1, got {args.trials}")

    trials = []
    for index in range(args.trials):
        trial = run_trial(args.seed, index)
        trials.append(trial)
        if args.out:
            with args.out.open("a") as out:
                out.write(json.dumps(trial) + "\n")
        if not args.json:
            error = "grasp failed" if not trial["grasped"] else f"{trial['placed_error_mm']:.3f} mm"
            print(f"trial {index + 1}/{args.trials}: {error}", file=sys.stderr)
    summary = summarise(trials)
    if args.json:
        print(json.dumps(summary))
    else:
        placed, yaw = summary["placed_error_mm"], summary["yaw_error_deg"]
        print(f"steered by {summary['steered_by']}")
        print(f"placed error: mean {placed['mean']} mm, std {placed['std']} mm, max {placed['max']} mm")
        print(f"yaw error: mean {yaw['mean']} deg, max {yaw['max']} deg")
        print(f"grasp failures: {summary['grasp_failures']} of {summary['trials']}")
        print(
            f"{summary['sim_seconds']} s simulated in {summary['wall_seconds']} s: "
            f"{summary['real_time_factor']}x real time"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
