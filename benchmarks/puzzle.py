"""Puzzles: a slab broken into pieces nobody describes, seen, solved and reassembled, over seeds.

    python benchmarks/puzzle.py [--pieces 4 6 9 12] [--seeds 0 1 2 3 4] [--gap-mm 2] [--picture] [--out runs.jsonl]

For each piece count a ``[puzzle.slab]`` plan (``SLABS``: a slab size per count, and a place for
the whole that leaves room on the table for its pieces) is run in the pybullet cell, once per seed:
the seed breaks the slab and scatters its pieces (``bt_arrange_sim.puzzles``). Reported per run:
whether the puzzle was solved right (every piece's solved target within 1 mm of its true home,
under one of the whole's symmetric turns), the solve's process time, and by ground truth (the
simulator's, evaluation only) each piece's final offset from its true home and yaw error, and the
smallest gap between two pieces at the end (0: touching), and the world time over the wall time
(the real-time factor). With ``--picture`` the slab is painted with the built-in
``picture = "fresco"`` instead of its ochre colour. Each run is printed (and appended to
``--out``) as a JSON line as it ends, so an interrupted campaign keeps what it measured; the last
lines sum each piece count up.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

import py_trees

from bt_arrange import treefile
from bt_arrange.plan.layout import Outline, gap_m
from bt_arrange.shapes import Prism
from bt_arrange_sim.pybullet.runs import SimulatedRun

#: Per piece count: the slab's size (mm) and where the whole goes (x, y in mm): room for the pieces around it.
SLABS = {
    2: ((120, 80, 20), (500, 0)),
    4: ((140, 100, 20), (500, 0)),
    6: ((160, 120, 20), (500, 0)),
    9: ((180, 130, 20), (500, 0)),
    # At (500, -220) 4 of 5 seeds found no room for 12 pieces (the scatter's sites keep the
    # pads' spacing of the largest piece): the whole goes near the table's -y corner instead.
    12: ((180, 140, 20), (360, -250)),
}
#: The issue's targets: within 1 mm and 1 deg of the true home by ground truth.
THRESHOLD_MM, YAW_THRESHOLD_DEG = 1.0, 1.0


def plan_text(pieces: int, gap_mm: float, picture: bool = False) -> str:
    """The plan of a puzzle of ``pieces`` (its threshold 0.8 mm and 0.8 deg, as the example's), ochre or painted."""
    (length, width, height), (x_mm, y_mm) = SLABS[pieces]
    colours = "" if picture else "[colours.ochre]\nrgb = [0.8, 0.55, 0.2]\n"
    paint = 'picture = "fresco"' if picture else 'colour = "ochre"'
    return f"""threshold_mm = 0.8
yaw_threshold_deg = 0.8
{colours}[puzzle.slab]
size_mm = [{length}, {width}, {height}]
pieces = {pieces}
gap_mm = {gap_mm:g}
{paint}
x_mm = {x_mm}
y_mm = {y_mm}
"""


def run_once(pieces: int, seed: int, gap_mm: float, picture: bool = False) -> dict:
    """One reassembly and its figures."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"puzzle_{pieces}.toml"
        path.write_text(plan_text(pieces, gap_mm, picture))
        module = treefile.load(path)
        root, scene = treefile.build_root(module), treefile.scene(module, seed)
    start, cpu_start = time.perf_counter(), time.process_time()
    with SimulatedRun(root, scene) as run:
        report = run.run()
        board = py_trees.blackboard.Blackboard
        solve_s = board.get("/slab/solve_s") if board.exists("/slab/solve_s") else None
        evaluation = run.puzzle_truth
        # Solved right: every solved target within 1 mm of its piece's true home (one turn of the whole for all).
        solved_error_mm = None
        for target in root.targets:
            home = evaluation.home(target, root.targets)
            if home is not None:
                error = math.hypot(home[0] - target.x_m, home[1] - target.y_m) * 1000
                solved_error_mm = max(solved_error_mm or 0.0, error)
        # The pieces as the simulator made them (true outlines, own frames), where they ended: their gaps.
        outlines = {}
        for piece in scene:
            x, y, yaw = run.cell.part_planar_truth(piece.name)
            shape = piece.object_type.shape
            assert isinstance(shape, Prism)
            convex = tuple(tuple((float(px), float(py)) for px, py in piece) for piece in shape.convex_pieces())
            outlines[piece.name] = Outline(x, y, yaw, convex)
    wall_s, cpu_s = time.perf_counter() - start, time.process_time() - cpu_start
    names = list(outlines)
    gaps = [gap_m(outlines[a], outlines[b]) for i, a in enumerate(names) for b in names[i + 1 :]]
    objects = report.to_dict()["objects"]
    finals = [o["final_offset_truth_mm"] for o in objects if o["final_offset_truth_mm"] is not None]
    yaws = [abs(o["final_yaw_error_truth_deg"]) for o in objects if o["final_yaw_error_truth_deg"] is not None]
    return {
        "pieces": pieces,
        "seed": seed,
        "gap_mm": gap_mm,
        "picture": "fresco" if picture else None,
        "tree_status": report.tree_status,
        "solved": len(names) == pieces,
        "solved_right": solved_error_mm is not None and solved_error_mm < 1.0 and len(names) == pieces,
        "solved_error_mm": None if solved_error_mm is None else round(solved_error_mm, 3),
        "solve_s": None if solve_s is None else round(float(solve_s), 3),
        "within": sum(
            o["final_offset_truth_mm"] is not None
            and o["final_offset_truth_mm"] < THRESHOLD_MM
            and abs(o["final_yaw_error_truth_deg"]) < YAW_THRESHOLD_DEG
            for o in objects
        ),
        "within_by_camera": sum(o["status"] == "within" for o in objects),
        "max_final_offset_truth_mm": max(finals) if finals else None,
        "max_yaw_error_truth_deg": max(yaws) if yaws else None,
        "min_gap_truth_mm": round(min(gaps) * 1000, 3) if gaps else None,
        "reasons": {o["name"]: o["reason"] for o in objects if o["reason"]},
        "sim_seconds": report.to_dict()["sim_seconds"],
        "wall_seconds": round(wall_s, 1),
        "cpu_seconds": round(cpu_s, 1),
        "real_time_factor": round(report.to_dict()["sim_seconds"] / wall_s, 2) if wall_s > 0 else None,
    }


def main(argv: list[str] | None = None) -> int:
    """Run every piece count over the seeds, a JSON line per run, a summary line per count."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pieces", type=int, nargs="+", default=[4, 6, 9, 12], choices=sorted(SLABS))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--gap-mm", type=float, default=2.0)
    parser.add_argument("--picture", action="store_true", help='paint the slab with picture = "fresco", not ochre')
    parser.add_argument("--out", type=Path, help="append each run as a JSON line")
    args = parser.parse_args(argv)
    for pieces in args.pieces:
        runs = []
        for seed in args.seeds:
            result = run_once(pieces, seed, args.gap_mm, args.picture)
            runs.append(result)
            line = json.dumps(result)
            print(line, flush=True)
            if args.out:
                with args.out.open("a") as out:
                    out.write(line + "\n")
        solve_times = [r["solve_s"] for r in runs if r["solve_s"] is not None]
        offsets = [r["max_final_offset_truth_mm"] for r in runs if r["max_final_offset_truth_mm"] is not None]
        painted = " (painted)" if args.picture else ""
        print(
            f"{pieces} pieces{painted}: solved right {sum(r['solved_right'] for r in runs)} of {len(runs)}; "
            f"{sum(r['within'] for r in runs)} of {pieces * len(runs)} pieces within {THRESHOLD_MM:g} mm and "
            f"{YAW_THRESHOLD_DEG:g} deg of their true homes by ground truth "
            f"({sum(r['within_by_camera'] for r in runs)} confirmed by the camera); worst "
            f"{max(offsets) if offsets else float('nan'):.2f} mm; solve "
            f"{max(solve_times) if solve_times else float('nan'):.2f} s at most (process time, this machine)",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
