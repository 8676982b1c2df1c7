"""Reprint every deterministic figure of the README (and docs/dense.md's table), each beside its source.

    python scripts/figures.py            # everything: about 10 minutes on 2 cores with nothing else running
    python scripts/figures.py --quick    # without the two experiment campaigns (Table 1, the real cell): ~2 min
    python scripts/figures.py --only four_cubes,pick_error

Each figure is printed by the benchmark or command named beside it in the README; this script
runs them (each in its own process, as a reader would) and prints the README's wording with the
figures measured now, so a reader can check them. Wall times, speeds and rendering shares depend
on the machine and are left out: they are measured, not reproduced (``benchmarks/throughput.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _run(*argv: str) -> str:
    """Run a command of this checkout (python benchmarks/..., bt-arrange ...) and return its stdout."""
    command = [sys.executable, *argv] if argv[0].endswith(".py") else [sys.executable, "-m", "bt_arrange.cli", *argv]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, env=os.environ.copy(), check=False)
    if done.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}): {done.stderr.strip()[-400:]}")
    return done.stdout


def _json(*argv: str) -> dict:
    return json.loads(_run(*argv).strip().splitlines()[-1])


def cell() -> list[str]:
    """The README's pick-and-place row."""
    source = "python benchmarks/cell.py --trials 50 --seed 0 --json"
    data = _json("benchmarks/cell.py", "--trials", "50", "--seed", "0", "--json")
    placed = data["placed_error_mm"]
    return [
        f"pick and place, steered by ground truth: {placed['mean']:.2f} ± {placed['std']:.2f} mm, max "
        f"{placed['max']:.2f} mm, {data['grasp_failures']} grasp failures in {data['trials']}  [{source}]"
    ]


def four_cubes() -> list[str]:
    """The README's four-cube row."""
    source = "bt-arrange run trees/four_cubes.py --seed 0"
    data = _json("run", "trees/four_cubes.py", "--seed", "0", "--json")
    objects = data["objects"]
    camera = [o["final_offset_mm"] for o in objects]
    truth = [o["final_offset_truth_mm"] for o in objects]
    yaw = max(abs(o["final_yaw_error_deg"]) for o in objects)
    pushes = sum(o["pushes"] for o in objects)
    world_s = data["sim_seconds"]
    return [
        f"four-cube arrangement, {data['objects_within']} of {len(objects)} within {data['threshold_mm']:g} mm: "
        f"{min(camera):.2f}-{max(camera):.2f} mm by camera, {min(truth):.2f}-{max(truth):.2f} mm by ground truth, "
        f"yaw within {yaw:.2f} deg, {pushes} pushes; {world_s:.1f} s of world time ({world_s / len(objects):.1f} s "
        f"per cube)  [{source}]"
    ]


def pick_error() -> list[str]:
    """The README's 2 cm pick error row."""
    source = "python benchmarks/pick_error.py"
    data = _json("benchmarks/pick_error.py", "--json")
    return [
        f"a 2 cm pick error injected: placed {data['placed_mm']:.1f} mm off, {data['pushes']} push(es), "
        f"{data['pushed_mm']:.2f} mm by the camera ({data['pushed_truth_mm']:.2f} mm ground truth)  [{source}]"
    ]


def perception() -> list[str]:
    """The README's cube detection row."""
    source = "python benchmarks/perception.py --poses 100 --seed 0 --json"
    data = _json("benchmarks/perception.py", "--poses", "100", "--seed", "0", "--json")
    xy, yaw = data["xy_error_mm"], data["yaw_error_deg"]
    return [
        f"cube detection in rendered scenes: xy {xy['mean']:.3f} mm mean, {xy['p95']:.3f} mm p95; yaw "
        f"{yaw['mean']:.3f} deg; {data['misses']} misses in {data['detections']}  [{source}]"
    ]


def plan_limits() -> list[str]:
    """docs/plans.md's colours, usable area and part limits."""
    return [*_run("scripts/plan_limits.py").rstrip().splitlines(), "  [python scripts/plan_limits.py]"]


DENSE_RUNS = (
    ("2 x 2 block, 2 mm gaps", "benchmarks/dense_trees/block_2mm.toml", ("0", "1", "2"), None),
    ("same, a pick translation error", "benchmarks/dense_trees/block_2mm.toml", ("0", "1", "2"), "pick_translation"),
    ("row of four distinct colours, 2 mm gaps", "trees/dense_row.py", ("0", "1", "2"), None),
    ("row of five identical green cubes, 2 mm gaps", "trees/dense_row_identical.py", ("0", "1", "2"), None),
    ("3 x 3 grid of nine identical green cubes", "benchmarks/dense_trees/grid_3x3_3mm_identical.py", ("0",), None),
)


def dense() -> list[str]:
    """docs/dense.md's tables."""
    lines = ["docs/dense.md: worst final offset per seed (truth); smallest gap at the end; most moved by a later step"]
    for label, tree, seeds, inject in DENSE_RUNS:
        argv = ["benchmarks/dense.py", tree, "--seeds", *seeds, *(["--inject", inject] if inject else [])]
        runs = [json.loads(line) for line in _run(*argv).splitlines() if line.startswith("{")]
        worst = ", ".join(f"{r['max_final_offset_truth_mm']:.2f}" for r in runs)
        gaps = [r["min_gap_truth_mm"] for r in runs]
        moved = max(max((v or 0.0) for v in r["moved_by_later_truth_mm"].values()) for r in runs)
        world = [r["sim_seconds"] for r in runs]
        lines.append(
            f"  {label}: {worst} mm; {min(gaps):.2f} to {max(gaps):.2f} mm; {moved:.4f} mm; "
            f"{min(world):.1f} to {max(world):.1f} s of world time  [python {' '.join(argv)}]"
        )
    return lines


def _summary(folder: Path) -> list[dict]:
    return json.loads((folder / "summary.json").read_text())


def table1() -> list[str]:
    """The README's Table 1 row."""
    source = "bt-arrange experiment --trials 100 --workers 2"
    with tempfile.TemporaryDirectory() as out:
        _run("experiment", "--trials", "100", "--workers", "2", "--out", out)
        rows = _summary(Path(out))
    within = sum(round(r["success_rate"] * r["trials"]) for r in rows)
    total = sum(r["trials"] for r in rows)
    parts = [f"{r['row']} {r['placed_mean_mm']:.2f} / {r['pushed_mean_mm']:.2f}" for r in rows]
    squared = next((r["squared_trials"] for r in rows if r["row"] == "orientation"), 0)
    return [
        f"Table 1, after placing / after pushing (mm, camera), 100 trials per row: {'; '.join(parts)}; "
        f"{squared} of 100 orientation trials squared in the grasp; {within} of {total} within 1 mm  [{source}]"
    ]


def real_cell() -> list[str]:
    """The README's real cell row."""
    rows = "system,translation,orientation"
    lines = []
    calibration_dir = tempfile.TemporaryDirectory()
    camera = str(Path(calibration_dir.name) / "camera.toml")
    # The real cell's camera is calibrated first, as a real cell's is (docs/calibration.md).
    _run("calibrate", "--cell", "real", "--views", "28", "--out", camera)
    for extra, label in (((), "paper strategy, 1 mm"), (("--strategy", "diagonal", "--threshold-mm", "0.5"), "ours")):
        with tempfile.TemporaryDirectory() as out:
            argv = ("experiment", "--cell", "real", "--rows", rows, "--trials", "30", "--workers", "2", *extra)
            _run(*argv, "--calibration", camera, "--out", out)
            summary = _summary(Path(out))
        placed = " / ".join(f"{r['placed_mean_mm']:.2f}" for r in summary)
        pushed = " / ".join(f"{r['pushed_mean_mm']:.2f}" for r in summary)
        truth = " / ".join(f"{r['pushed_truth_mean_mm']:.2f}" for r in summary)
        pushes = " / ".join(f"{r['pushes_mean']:.2f}" for r in summary)
        within = sum(round(r["success_rate"] * r["trials"]) for r in summary)
        lines.append(
            f"real cell ({label}): after placing {placed}; after pushing {pushed} (ground truth {truth}); "
            f"{pushes} pushes; {within} of {sum(r['trials'] for r in summary)} within  "
            f"[bt-arrange calibrate --cell real --views 28; bt-arrange {' '.join(argv)} --calibration camera.toml]"
        )
    calibration_dir.cleanup()
    return lines


FIGURES: dict[str, Callable[[], list[str]]] = {
    "cell": cell,
    "four_cubes": four_cubes,
    "pick_error": pick_error,
    "perception": perception,
    "plan_limits": plan_limits,
    "dense": dense,
    "table1": table1,
    "real_cell": real_cell,
}
CAMPAIGNS = ("table1", "real_cell")


def main(argv: list[str] | None = None) -> int:
    """Print the figures asked for."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="leave out the experiment campaigns")
    parser.add_argument("--only", help=f"comma-separated, of {', '.join(FIGURES)}")
    args = parser.parse_args(argv)
    names = args.only.split(",") if args.only else [n for n in FIGURES if not (args.quick and n in CAMPAIGNS)]
    for name in names:
        if name not in FIGURES:
            parser.error(f"unknown figure {name!r}; choose from {', '.join(FIGURES)}")
        for line in FIGURES[name]():
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
