"""The puzzle solver alone: the simulator's breaks, turned, shuffled and noised, put back, over seeds.

    python benchmarks/puzzle_solve.py [--pieces 4 6 9 12] [--seeds 0 1 2 3 4] [--gaps-mm 2 1]
                                      [--noise-mm 0.05] [--camera] [--out runs.jsonl]

No cell (and by default no camera): each slab (the sizes of ``benchmarks/puzzle.py``) is broken as the scene
breaks it (``bt_arrange_sim.puzzles.measured_break``: ``buildable_break``, every piece turned and
moved at random, the labels shuffled, each vertex moved ``--noise-mm`` in a random direction), and
``bt_arrange.puzzle.solve`` gets the outlines alone. ``--camera``: the outlines are measured instead
by ``measure_unknown_outlines`` on one synthetic frame (``render_frame``, anti-aliased, 2 grey
levels of noise) of the pieces laid out turned at random on a grid in the camera's view.
Solved right: every piece's solved centroid within 0.3 mm and its turn within 0.5 deg of the truth
under one of the slab's symmetric turns.
Reported per run as a JSON line (and appended to ``--out`` as it ends): solved right, the worst
place and turn errors, the residual and the runner-up's, and the solve's process (CPU) time; the
last lines sum each piece count and gap up.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
from pathlib import Path

import numpy as np

from bt_arrange.perception import PartDetector, measure_unknown_outlines
from bt_arrange.perception.synthetic import SyntheticPrism, render_frame
from bt_arrange.puzzle import MeasuredPiece, PuzzleError, PuzzleSpec, solve
from bt_arrange_sim.puzzles import MeasuredBreak, buildable_break, measured_break

#: Per piece count: the slab's length and width (mm), as ``benchmarks/puzzle.py``'s; 20 mm high.
SIZES_MM = {2: (120, 80), 4: (140, 100), 6: (160, 120), 9: (180, 130), 12: (180, 140)}
#: Solved right: every centroid within this of the truth, every turn within ``RIGHT_TURN_DEG``.
RIGHT_PLACE_MM, RIGHT_TURN_DEG = 0.3, 0.5
#: ``--camera``: where the pieces lie in the synthetic camera's view (x, y in metres), one each.
SPOTS_M = [(x, y) for x in (0.32, 0.44, 0.56, 0.68) for y in (-0.3, -0.1, 0.1, 0.3)]


def camera_break(spec: PuzzleSpec, seed: int) -> tuple[MeasuredBreak, list[str]]:
    """The break's pieces laid out turned at random, measured on one synthetic frame; the problems reported.

    Each measured outline is matched to the piece laid nearest (evaluation only) for its truth.
    """
    pieces = buildable_break(spec, seed)
    rng = np.random.default_rng([seed, 11])
    spots = [SPOTS_M[k] for k in rng.permutation(len(SPOTS_M))[: len(pieces)]]
    yaws = rng.uniform(-math.pi, math.pi, size=len(pieces))
    parts = [
        SyntheticPrism("red", x, y, float(yaw), p.prism) for p, (x, y), yaw in zip(pieces, spots, yaws, strict=True)
    ]
    frame = render_frame(parts, supersample=8, noise_sigma=2.0, seed=seed)
    outlines, problems = measure_unknown_outlines(PartDetector(), frame, "red", spec.height_m)
    labels, measured, truths, turns = [], [], [], []
    for k, outline in enumerate(outlines, start=1):
        nearest = min(range(len(parts)), key=lambda i: math.hypot(*(np.array(spots[i]) - outline.centroid_m)))
        labels.append(f"slab {k}")
        measured.append(outline.outline_m)
        truths.append(np.asarray(pieces[nearest].slab_outline_m, dtype=float))
        turns.append(float(yaws[nearest]) - pieces[nearest].yaw_rad + spec.yaw_rad)
    return MeasuredBreak(tuple(labels), tuple(measured), tuple(truths), tuple(turns)), problems


def run_once(pieces: int, seed: int, gap_mm: float, noise_mm: float, camera: bool = False) -> dict:
    """One break solved: the JSON line's fields."""
    length, width = SIZES_MM[pieces]
    spec = PuzzleSpec("slab", (length / 1000, width / 1000, 0.02), pieces, gap_mm / 1000, "ochre", 0.5, 0.0, 0.0)
    result: dict = {"pieces": pieces, "gap_mm": gap_mm, "seed": seed}
    if camera:
        broken, problems = camera_break(spec, seed)
        result["source"] = "camera"
        if len(broken.labels) != pieces:
            return {**result, "solved_right": False, "error": f"{len(broken.labels)} measured: {'; '.join(problems)}"}
    else:
        broken = measured_break(spec, seed, noise_mm / 1000)
        result.update(source="noise", noise_mm=noise_mm)
    measured = [MeasuredPiece(label, outline) for label, outline in zip(broken.labels, broken.outlines, strict=True)]
    try:
        assembly = solve(measured, spec.size_m, spec.gap_m)
    except PuzzleError as error:
        return {**result, "solved_right": False, "error": str(error)}
    place_m, turn_rad = broken.errors(assembly.placements, spec.symmetry_turns_rad)
    place_mm, turn_deg = place_m * 1000, math.degrees(turn_rad)
    runner_up = assembly.runner_up_residual_m
    return {
        **result,
        "solved_right": place_mm <= RIGHT_PLACE_MM and turn_deg <= RIGHT_TURN_DEG,
        "worst_place_mm": round(place_mm, 4),
        "worst_turn_deg": round(turn_deg, 4),
        "residual_mm": round(assembly.residual_m * 1000, 5),
        "runner_up_residual_mm": None if runner_up is None else round(runner_up * 1000, 5),
        "solve_cpu_s": round(assembly.solve_s, 3),
    }


def summary(pieces: int, gap_mm: float, runs: list[dict]) -> str:
    """One line: how many solved right, the worst error, the solve's CPU time."""
    right = sum(r["solved_right"] for r in runs)
    solved = [r for r in runs if "solve_cpu_s" in r]
    times = [r["solve_cpu_s"] for r in solved]
    worst = max((r["worst_place_mm"] for r in solved), default=math.nan)
    misses = [str(r["seed"]) for r in runs if not r["solved_right"]]
    return (
        f"{pieces} pieces, gap {gap_mm:g} mm: solved right {right} of {len(runs)}"
        f"{' (missed seeds ' + ', '.join(misses) + ')' if misses else ''}; worst centroid {worst:.3f} mm; "
        f"solve CPU median {statistics.median(times) if times else math.nan:.2f} s, "
        f"max {max(times, default=math.nan):.2f} s"
    )


def main(argv: list[str] | None = None) -> int:
    """Every piece count and gap over the seeds: a JSON line per run, a summary line per count and gap."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pieces", type=int, nargs="+", default=[4, 6, 9, 12], choices=sorted(SIZES_MM))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--gaps-mm", type=float, nargs="+", default=[2.0, 1.0])
    parser.add_argument("--noise-mm", type=float, default=0.05)
    parser.add_argument("--camera", action="store_true", help="outlines measured on a synthetic frame")
    parser.add_argument("--out", type=Path, help="append each run as a JSON line")
    args = parser.parse_args(argv)
    lines = []
    for pieces in args.pieces:
        for gap_mm in args.gaps_mm:
            runs = []
            for seed in args.seeds:
                runs.append(run_once(pieces, seed, gap_mm, args.noise_mm, args.camera))
                print(json.dumps(runs[-1]), flush=True)
                if args.out:  # appended as it goes: an interrupted campaign keeps what it measured
                    with args.out.open("a") as out:
                        out.write(json.dumps(runs[-1]) + "\n")
            lines.append(summary(pieces, gap_mm, runs))
    for line in lines:
        print(line, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
