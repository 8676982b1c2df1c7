"""Reprint every deterministic figure of the README (and docs/dense.md's table), each beside its source.

    python scripts/figures.py            # everything: about 40 minutes on 2 cores with nothing else running
    python scripts/figures.py --quick    # without the experiment campaigns (Table 1, the real cell, records)
    python scripts/figures.py --only four_cubes,pick_error
    python scripts/figures.py --skip fresco,records
    python scripts/figures.py --list     # the figures' names, what each reprints, and whether it is a campaign

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
        f"pick and place, steered by ground truth: {placed['mean']:.3f} ± {placed['std']:.3f} mm, max "
        f"{placed['max']:.2f} mm, {data['grasp_failures']} grasp failures in {data['trials']}  [{source}]"
    ]


def cycle_time() -> list[str]:
    """The four-cube row's world time per cube against the lower bound for its waypoints."""
    source = "python benchmarks/throughput.py --json"
    data = _json("benchmarks/throughput.py", "--json")
    return [
        f"four-cube arrangement: {data['world_s_per_object']:.1f} s of world time per cube, "
        f"{data['bound_ratio']:.2f}x the lower bound for its waypoints ({data['bound_s_per_object']:.2f} s per cube)  "
        f"[{source}; keys world_s_per_object, bound_ratio]"
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


def irregular() -> list[str]:
    """The README's irregular parts: five outlines, three seeds, counted by ground truth here (and by the camera)."""
    source = "python benchmarks/irregular.py --seeds 0 1 2 --json"
    rows = _json("benchmarks/irregular.py", "--seeds", "0", "1", "2", "--json")
    within = sum(r["within_truth"] for r in rows)
    by_camera = sum(r["status"] == "within" for r in rows)
    worst_mm = max(r["pushed_truth_mm"] for r in rows)
    worst_deg = max(abs(r["yaw_error_truth_deg"]) for r in rows)
    regrasps = sum(r.get("regrasps_after_placing", 0) for r in rows)
    parts = len({r["part"] for r in rows})
    seeds = len({r["seed"] for r in rows})
    return [
        f"irregular parts, {parts} outlines, {seeds} seeds: {within} of {len(rows)} within "
        f"{rows[0]['threshold_mm']:g} mm and {rows[0]['yaw_threshold_deg']:g} deg by ground truth ({by_camera} by the "
        f"camera), worst {worst_mm:.2f} mm and {worst_deg:.2f} deg; {regrasps} regrasps after placing  [{source}]"
    ]


def _fresco(*extra: str) -> tuple[list[dict], str]:
    argv = ["benchmarks/fresco.py", "--seeds", "0", "1", "2", *extra]
    runs = [json.loads(line) for line in _run(*argv).splitlines() if line.startswith("{")]
    return runs, "python " + " ".join(argv)


def fresco() -> list[str]:
    """The README's frescoes: six pieces, 2 mm gaps, three seeds, plain and with Table 1's pick translation error."""
    lines = []
    for extra, label in (((), "a fresco"), (("--inject", "pick_translation"), "with the pick translation error")):
        runs, source = _fresco(*extra)
        pieces = sum(r["pieces"] for r in runs)
        within = sum(r["within"] for r in runs)
        by_camera = sum(r["within_by_camera"] for r in runs)
        worst = max(r["max_final_offset_truth_mm"] for r in runs)
        worst_deg = max(r["max_yaw_error_truth_deg"] for r in runs)
        gap = min(r["min_gap_truth_mm"] for r in runs)
        lines.append(
            f"{label}, {runs[0]['pieces']} pieces with {runs[0]['gap_mm']:g} mm gaps, {len(runs)} seeds: {within} of "
            f"{pieces} within {runs[0]['threshold_mm']:g} mm and {runs[0]['yaw_threshold_deg']:g} deg by ground truth "
            f"({by_camera} by the camera), worst {worst:.2f} mm and {worst_deg:.2f} deg; smallest gap at the end "
            f"{gap:.2f} mm{' (no two pieces touching)' if gap > 0 else ' (touching)'}  [{source}]"
        )
    return lines


#: The README's tight gaps (docs/irregular.md's table, its last row): 0.5 mm gaps at a 0.25 mm threshold.
TIGHT_GAPS = ("--gap-mm", "0.5", "--threshold-mm", "0.25", "--moved-limit-mm", "0.1")


def tight_gaps() -> list[str]:
    """The README's fresco at a 0.25 mm threshold with 0.5 mm gaps, three seeds, counted by ground truth."""
    runs, source = _fresco(*TIGHT_GAPS)
    within = sum(r["within"] for r in runs)
    by_camera = sum(r["within_by_camera"] for r in runs)
    worst = max(r["max_final_offset_truth_mm"] for r in runs)
    return [
        f"a fresco at a {runs[0]['threshold_mm']:g} mm threshold with {runs[0]['gap_mm']:g} mm gaps, {len(runs)} "
        f"seeds: {within} of {sum(r['pieces'] for r in runs)} within {runs[0]['threshold_mm']:g} mm and "
        f"{runs[0]['yaw_threshold_deg']:g} deg by ground truth ({by_camera} by the camera), worst {worst:.3f} mm  "
        f"[{source}]"
    ]


def outlines() -> list[str]:
    """The README's outline detection in the cell's camera."""
    source = "python benchmarks/outlines.py --poses 100 --cell --no-synthetic --json"
    data = _json("benchmarks/outlines.py", "--poses", "100", "--cell", "--no-synthetic", "--json")
    everything = data["results"]["cell"]["all"]
    return [
        f"outline detection in the cell's camera: {everything['xy_error_mm']['mean']:.3f} mm and "
        f"{everything['yaw_error_deg']['mean']:.3f} deg mean, {everything['misses']} misses in "
        f"{everything['detections']}  [{source}; the synthetic renders of --cell without --no-synthetic aside]"
    ]


def calibration() -> list[str]:
    """The README's real-cell calibration figures."""
    source = "python benchmarks/calibration.py --cell real --views 28 --json"
    data = _json("benchmarks/calibration.py", "--cell", "real", "--views", "28", "--json")
    measured = data["detection_calibrated"]
    return [
        f"calibration of the real cell's camera: reprojection {data['reprojection_error_px']:.3f} px, camera pose "
        f"{data['camera_to_base_error_mm']:.2f} mm and {data['camera_to_base_error_mrad']:.2f} mrad off the true one, "
        f"cubes measured {measured['mean_mm']:.2f} mm off (mean, max {measured['max_mm']:.2f}) over the usable area "
        f"({measured['found']} of {measured['cubes']} found)  [{source}]"
    ]


#: The code just before the depth estimator rendered windows instead of the whole frame (ab10168's parent).
BEFORE_WINDOWS = "d509651"


def records() -> list[str]:
    """The README's "399 of 400 trial records identical" (Table 1, against the code before windowed depth)."""
    source = f"python benchmarks/campaign_wall.py --against {BEFORE_WINDOWS} --trials 100 --json"
    data = _json("benchmarks/campaign_wall.py", "--against", BEFORE_WINDOWS, "--trials", "100", "--json")
    differing = f"; differing: {', '.join(data['differing_records'])}" if data["differing_records"] else ""
    added = f"; fields added since, not compared: {', '.join(data['added_fields'])}" if data.get("added_fields") else ""
    return [
        f"Table 1's trial records identical to those of {BEFORE_WINDOWS} (before the windowed depth estimator): "
        f"{data['identical_records']} of {data['records']}{differing}{added}  [{source}; its wall ratios are measured]"
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


def _trials(folder: Path) -> list[dict]:
    """A campaign's trial records that measured something (``trials.jsonl``, errored trials aside)."""
    records = [json.loads(line) for line in (folder / "trials.jsonl").read_text().splitlines() if line.strip()]
    return [r for r in records if r.get("status") != "error"]


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
            trials = _trials(Path(out))
        placed = " / ".join(f"{r['placed_mean_mm']:.2f}" for r in summary)
        pushed = " / ".join(f"{r['pushed_mean_mm']:.2f}" for r in summary)
        truth = " / ".join(f"{r['pushed_truth_mean_mm']:.2f}" for r in summary)
        pushes = " / ".join(f"{r['pushes_mean']:.2f}" for r in summary)
        within = sum(round(r["success_rate"] * r["trials"]) for r in summary)
        threshold_mm = float(extra[extra.index("--threshold-mm") + 1]) if "--threshold-mm" in extra else 1.0
        by_truth = sum(t["pushed_truth_mm"] is not None and t["pushed_truth_mm"] < threshold_mm for t in trials)
        lines.append(
            f"real cell ({label}): after placing {placed}; after pushing {pushed} (ground truth {truth}); "
            f"{pushes} pushes; {by_truth} of {len(trials)} within {threshold_mm:g} mm by ground truth ({within} of "
            f"{sum(r['trials'] for r in summary)} by the camera)  "
            f"[bt-arrange calibrate --cell real --views 28; bt-arrange {' '.join(argv)} --calibration camera.toml]"
        )
    calibration_dir.cleanup()
    return lines


FIGURES: dict[str, Callable[[], list[str]]] = {
    "cell": cell,
    "four_cubes": four_cubes,
    "cycle_time": cycle_time,
    "pick_error": pick_error,
    "perception": perception,
    "irregular": irregular,
    "fresco": fresco,
    "tight_gaps": tight_gaps,
    "outlines": outlines,
    "calibration": calibration,
    "plan_limits": plan_limits,
    "dense": dense,
    "table1": table1,
    "real_cell": real_cell,
    "records": records,
}
#: The figures that run whole experiment campaigns (minutes each): left out by ``--quick``, which prints
#: the command each runs instead.
CAMPAIGNS = {
    "table1": "bt-arrange experiment --trials 100 --workers 2",
    "real_cell": "bt-arrange calibrate --cell real --views 28 --out camera.toml, then bt-arrange experiment --cell "
    "real --rows system,translation,orientation --trials 30 --workers 2 --calibration camera.toml "
    "[--strategy diagonal --threshold-mm 0.5]",
    "records": f"python benchmarks/campaign_wall.py --against {BEFORE_WINDOWS} --trials 100 --json",
}


def _names(text: str, parser: argparse.ArgumentParser, option: str) -> list[str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    for name in names:
        if name not in FIGURES:
            parser.error(f"{option}: unknown figure {name!r}; choose from {', '.join(FIGURES)}")
    return names


def main(argv: list[str] | None = None) -> int:
    """Print the figures asked for."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    campaigns = ", ".join(CAMPAIGNS)
    parser.add_argument("--quick", action="store_true", help=f"leave out the experiment campaigns ({campaigns})")
    parser.add_argument("--only", help=f"comma-separated, of {', '.join(FIGURES)}")
    parser.add_argument("--skip", help="comma-separated figures to leave out")
    parser.add_argument("--list", action="store_true", help="list the figures and exit")
    args = parser.parse_args(argv)
    if args.list:
        for name, figure in FIGURES.items():
            doc = (figure.__doc__ or "").strip().splitlines()[0]
            print(f"{name:12s} {doc}{' (a campaign)' if name in CAMPAIGNS else ''}")
        return 0
    everything = [n for n in FIGURES if not (args.quick and n in CAMPAIGNS)]
    names = _names(args.only, parser, "--only") if args.only else everything
    skipped = set(_names(args.skip, parser, "--skip")) if args.skip else set()
    for name in names:
        if name in skipped:
            continue
        for line in FIGURES[name]():
            print(line, flush=True)
    if args.quick and not args.only:
        for name, command in CAMPAIGNS.items():
            if name not in skipped:
                print(f"{name}: a campaign, left out by --quick (python scripts/figures.py --only {name})  [{command}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
