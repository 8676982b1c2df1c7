"""Dense arrangements: run a tree file over seeds and report, by ground truth, how each part ended.

    python benchmarks/dense.py trees/dense_block.py --seeds 0 1 2 [--inject pick_translation] [--json]

Per run: each part's final offset by the camera and by ground truth (the simulator's, for
evaluation only), the smallest gap between two parts at the end (ground truth: footprints from
the true poses), and the most a later step moved each part between two looks at it (camera and
ground truth). Results are printed (and with ``--out FILE`` appended as JSON lines) as each run ends.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from bt_arrange import treefile
from bt_arrange.plan.layout import Rect, gap_m
from bt_arrange_sim.pybullet.runs import SimulatedRun


def run_once(path: Path, seed: int, inject: str | None, inject_seed: int) -> dict:
    """One run of the tree file at ``seed``; returns its figures."""
    module = treefile.load(path)
    root, scene = treefile.build_root(module), treefile.scene(module, seed)
    start = time.perf_counter()
    with SimulatedRun(root, scene) as run:
        if inject:
            from bt_arrange_sim.injection.registry import attach_all, make_injector

            for target in root.targets:
                attach_all(run, target.obj, [make_injector(inject)], inject_seed + seed)
        report = run.run()
        names = [t.obj for t in root.targets]
        rects = {}
        for target in root.targets:
            x, y, yaw = run.cell.part_planar_truth(target.obj)
            half_x_m, half_y_m = (v / 2 for v in target.object_type.shape.extent_m)
            rects[target.obj] = Rect(x, y, yaw, half_x_m, half_y_m)
    gaps = [gap_m(rects[a], rects[b]) for i, a in enumerate(names) for b in names[i + 1 :]]
    objects = report.to_dict()["objects"]
    return {
        "tree": str(path),
        "seed": seed,
        "inject": inject,
        "tree_status": report.tree_status,
        "final_offset_truth_mm": {o["name"]: o["final_offset_truth_mm"] for o in objects},
        "final_offset_mm": {o["name"]: o["final_offset_mm"] for o in objects},
        "moved_by_later_mm": {o["name"]: o["moved_by_later_mm"] for o in objects},
        "moved_by_later_truth_mm": {o["name"]: o["moved_by_later_truth_mm"] for o in objects},
        "pushes": {o["name"]: o["pushes"] for o in objects},
        "reasons": {o["name"]: o["reason"] for o in objects if o["reason"]},
        "min_gap_truth_mm": round(min(gaps) * 1000, 3) if gaps else None,
        "max_final_offset_truth_mm": max(o["final_offset_truth_mm"] for o in objects),
        "sim_seconds": report.to_dict()["sim_seconds"],
        "wall_seconds": round(time.perf_counter() - start, 1),
    }


def main(argv: list[str] | None = None) -> int:
    """Run and print."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tree", type=Path)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--inject", help="an injector's name (sim/injection registry), on every part")
    parser.add_argument("--inject-seed", type=int, default=100)
    parser.add_argument("--out", type=Path, help="append each run as a JSON line")
    args = parser.parse_args(argv)
    for seed in args.seeds:
        result = run_once(args.tree, seed, args.inject, args.inject_seed)
        line = json.dumps(result)
        print(line, flush=True)
        if args.out:
            with args.out.open("a") as out:
                out.write(line + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
