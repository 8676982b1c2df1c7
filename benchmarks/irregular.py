"""Irregular parts arranged end to end (in progress): five outlines, each turned at its target.

    python benchmarks/irregular.py [--seeds 0 1 2] [--plan PLAN.toml] [--json]

Runs ``benchmarks/plans/irregular_parts.toml`` (a triangle, an L, a trapezoid, a pentagon and a
non-convex fragment) in the headless cell once per seed: found by the camera's outline
registration, picked at their grasps, placed, inspected and pushed. Prints per part, by the camera
and by ground truth (the simulator's, evaluation only), the offset after placing and after
pushing, the yaw error, the pushes and the regrasps (picked up again after placing), and how many
parts ended within the plan's thresholds (1 mm and 1 deg): by ground truth, counted here from the
true offset and yaw error, and by the camera (the run's own status). ``--json`` prints the rows
(``within_truth`` the first count's verdict, ``status`` the camera's) and ``s_per_part``, the run's
world time over its parts. ``--plan`` runs another plan of outlines (``benchmarks/plans/five_outlines.toml``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bt_arrange import treefile
from bt_arrange.report import ObjectOutcome
from bt_arrange_sim.pybullet.runs import SimulatedRun

PLAN = Path(__file__).resolve().parent / "plans" / "irregular_parts.toml"


def run(seed: int, plan: Path = PLAN) -> list[dict]:
    """One run of the plan; each part's outcome."""
    module = treefile.load(plan)
    root = treefile.build_root(module)
    with SimulatedRun(root, treefile.scene(module, seed=seed)) as session:
        report = session.run()
    threshold_mm, yaw_threshold_deg = report.threshold_mm, report.yaw_threshold_deg
    assert threshold_mm is not None

    def within_truth(o: ObjectOutcome) -> bool:
        """The part's true offset, and its true yaw error (when the plan has a yaw threshold), under the thresholds."""
        if o.final_offset_truth_mm is None or o.final_offset_truth_mm >= threshold_mm:
            return False
        yaw = o.final_yaw_error_truth_deg
        return yaw_threshold_deg is None or (yaw is not None and abs(yaw) < yaw_threshold_deg)

    return [
        {
            "seed": seed,
            "part": o.object_type,
            "placed_mm": o.placed_offset_mm,
            "pushed_mm": o.final_offset_mm,
            "pushed_truth_mm": o.final_offset_truth_mm,
            "yaw_error_truth_deg": o.final_yaw_error_truth_deg,
            "pushes": o.pushes,
            "regrasps_after_placing": o.regrasps_after_placing,
            "status": o.status,
            "within_truth": within_truth(o),
            "threshold_mm": threshold_mm,
            "yaw_threshold_deg": yaw_threshold_deg,
            "s_per_part": round(report.sim_seconds / len(report.objects), 2),
        }
        for o in report.objects
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--plan", type=Path, default=PLAN, help="a plan of outlines (default the five of the example)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = [row for seed in args.seeds for row in run(seed, args.plan)]
    if args.json:
        print(json.dumps(rows))
        return
    print("seed  part       placed  pushed  truth   yaw truth  pushes  regrasps  status")
    for r in rows:
        placed, pushed = (float("nan") if r[k] is None else r[k] for k in ("placed_mm", "pushed_mm"))
        print(
            f"{r['seed']:<5} {r['part']:<10} {placed:6.2f}  {pushed:6.2f}  {r['pushed_truth_mm']:6.2f}"
            f"  {r['yaw_error_truth_deg']:+8.2f}  {r['pushes']:6d}  {r['regrasps_after_placing']:8d}  {r['status']}"
        )
    print(summary(rows))


def summary(rows: list[dict]) -> str:
    """How many parts ended within the thresholds by ground truth and by the camera, and the worst true figures."""
    within = sum(r["within_truth"] for r in rows)
    by_camera = sum(r["status"] == "within" for r in rows)
    worst_mm = max((r["pushed_truth_mm"] for r in rows if r["pushed_truth_mm"] is not None), default=float("nan"))
    worst_deg = max((abs(r["yaw_error_truth_deg"]) for r in rows if r["yaw_error_truth_deg"] is not None), default=0.0)
    yaw = rows[0]["yaw_threshold_deg"] if rows else None
    limits = f"{rows[0]['threshold_mm']:g} mm" + (f" and {yaw:g} deg" if yaw is not None else "") if rows else ""
    seconds = {r["seed"]: r["s_per_part"] for r in rows}
    mean_s = sum(seconds.values()) / len(seconds) if seconds else float("nan")
    return (
        f"{within} of {len(rows)} parts within {limits} by ground truth ({by_camera} by the camera); worst "
        f"{worst_mm:.2f} mm and {worst_deg:.2f} deg by ground truth; {mean_s:.2f} s a part of world time "
        f"(per seed {seconds}); offsets in mm, yaw in deg"
    )


if __name__ == "__main__":
    main()
