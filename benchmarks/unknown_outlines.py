"""Unknown-outline benchmark: a fracture's pieces scattered, their top faces measured without a model.

    python benchmarks/unknown_outlines.py --fractures 4 --scenes 3 --seed 0 [--no-cell] [--json]

Each scene scatters the 6 pieces of one fracture (``fracture((0.20, 0.15, 0.02), 6, 0.002, seed)``)
on a grid of places, each moved a little and turned at random, all red; one frame is measured by
``measure_unknown_outlines`` and every measured vertex is matched to the nearest true vertex of its
piece. Sources: ``antialiased`` and ``aliased`` synthetic frames (``bt_arrange.perception.synthetic``,
exact truth), ``noisy`` (0.8 px blur, 2 grey levels of noise), and the pybullet ``cell`` (TinyRenderer,
pixel centres only; truth from the simulator's bodies after settling). On an aliased frame a side
whose slope in the image is a simple fraction ``p / q`` (a row or column, a diagonal, 1 in 2) repeats
its staircase every ``q`` pixels and is known to about ``1 / (2 q)`` px only: the tail of the
``aliased`` and ``cell`` figures. ``cell_off_axis`` is the cell with every side kept 1.5 degrees or
more off the image's rows and columns: it shows that rows and columns are not the only such slopes.
Figures: vertex error in mm (mean, 95th percentile, worst), the share within 0.1 mm, pieces measured
and those whose vertex count is not the truth's (with the reasons for any not measured), the CPU time
per frame (median, ms; this machine, 2 cores, shared with other work).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

from bt_arrange.objects import ObjectType
from bt_arrange.perception import PartDetector, measure_unknown_outlines
from bt_arrange.perception.synthetic import SyntheticPrism, render_frame
from bt_arrange.shapes.base import footprint_m
from bt_arrange.shapes.fracture import Piece, fracture

SLAB_M = (0.20, 0.15, 0.02)
TOP_Z_M = 0.02
PLACES = [(0.38, -0.25), (0.38, 0.0), (0.38, 0.25), (0.62, -0.25), (0.62, 0.0), (0.62, 0.25)]
RENDERS = {
    "antialiased": {"supersample": 8},
    "aliased": {"supersample": 1},
    "noisy": {"supersample": 8, "noise_sigma": 2.0, "blur_sigma_px": 0.8},
}
AXIS_CLEARANCE_DEG = 1.5


def _yaw(rng: np.random.Generator, piece: Piece, off_axis: bool, camera_yaw_deg: float = 0.0) -> float:
    """A random yaw; ``off_axis``: one that keeps every side ``AXIS_CLEARANCE_DEG`` off the image's rows and columns."""
    sides = np.roll(piece.prism.outline_m, -1, axis=0) - piece.prism.outline_m
    angles = np.degrees(np.arctan2(sides[:, 1], sides[:, 0])) - camera_yaw_deg
    while True:
        yaw = float(rng.uniform(-math.pi, math.pi))
        off = (angles + math.degrees(yaw)) % 90.0
        if not off_axis or np.all(np.minimum(off, 90.0 - off) >= AXIS_CLEARANCE_DEG):
            return yaw


def _scatter(
    rng: np.random.Generator, pieces: list[Piece], off_axis: bool = False, camera_yaw_deg: float = 0.0
) -> list[tuple[float, float, float]]:
    return [
        (
            x + float(rng.uniform(-0.01, 0.01)),
            y + float(rng.uniform(-0.02, 0.02)),
            _yaw(rng, piece, off_axis, camera_yaw_deg),
        )
        for piece, (x, y) in zip(pieces, PLACES, strict=True)
    ]


def _score(source: str, frame, truth: list[np.ndarray]) -> dict:
    start = time.process_time()
    outlines, problems = measure_unknown_outlines(PartDetector(), frame, "red", TOP_Z_M)
    ms = (time.process_time() - start) * 1000
    errors: list[float] = []
    wrong_count = 0
    for outline in outlines:
        true = min(truth, key=lambda t: float(np.hypot(*(t.mean(axis=0) - outline.centroid_m))))
        distances = np.hypot(*(outline.outline_m[:, None, :] - true[None, :, :]).transpose(2, 0, 1))
        errors.extend((1000 * distances.min(axis=1)).tolist())
        wrong_count += int(len(outline.outline_m) != len(true))
    return {
        "source": source,
        "ms": ms,
        "errors_mm": errors,
        "measured": len(outlines),
        "pieces": len(truth),
        "wrong_count": wrong_count,
        "problems": problems,
    }


def synthetic(fractures: list[list[Piece]], scenes: int, seed: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    results = []
    for pieces in fractures:
        for _ in range(scenes):
            poses = _scatter(rng, pieces)
            parts = [SyntheticPrism("red", x, y, yaw, p.prism) for p, (x, y, yaw) in zip(pieces, poses, strict=True)]
            truth = [footprint_m(p.prism, x, y, yaw) for p, (x, y, yaw) in zip(pieces, poses, strict=True)]
            for source, options in RENDERS.items():
                frame = render_frame(parts, seed=int(rng.integers(2**31)), **options)  # type: ignore[arg-type]
                results.append(_score(source, frame, truth))
    return results


def cell(fractures: list[list[Piece]], scenes: int, seed: int) -> list[dict]:
    from bt_arrange_sim.pybullet.cell import WorkCell

    rng = np.random.default_rng(seed + 1)
    results = []
    for off_axis, source in ((False, "cell"), (True, "cell_off_axis")):
        for pieces in fractures:
            for _ in range(scenes):
                with WorkCell() as world:
                    rotation = world.camera.pose_world.rotation  # image x (right) in the world
                    camera_yaw_deg = math.degrees(math.atan2(rotation[1, 0], rotation[0, 0]))
                    poses = _scatter(rng, pieces, off_axis, camera_yaw_deg)
                    for piece, (x, y, yaw) in zip(pieces, poses, strict=True):
                        kind = ObjectType(f"piece {piece.index}", shape=piece.prism)
                        world.add_object(kind, "red", x, y, yaw, name=str(piece.index))
                    world.settle(0.3)
                    frame = world.camera.capture()
                    truth = []
                    for piece in pieces:
                        pose = world.part_pose_truth(str(piece.index))
                        truth.append(footprint_m(piece.prism, pose.x_m, pose.y_m, pose.yaw_rad))
                results.append(_score(source, frame, truth))
    return results


def summarise(results: list[dict]) -> dict:
    """Per source: vertices, pieces measured, vertex error (mm) mean / p95 / max, frames' median CPU time."""
    table = {}
    for source in dict.fromkeys(r["source"] for r in results):
        rows = [r for r in results if r["source"] == source]
        errors = np.asarray([e for r in rows for e in r["errors_mm"]])
        table[source] = {
            "frames": len(rows),
            "pieces": sum(r["pieces"] for r in rows),
            "measured": sum(r["measured"] for r in rows),
            "wrong_vertex_count": sum(r["wrong_count"] for r in rows),
            "vertices": int(len(errors)),
            "vertex_error_mm": {
                "mean": round(float(errors.mean()), 4) if len(errors) else None,
                "p95": round(float(np.percentile(errors, 95)), 4) if len(errors) else None,
                "max": round(float(errors.max()), 4) if len(errors) else None,
            },
            "share_within_0.1_mm": round(float(np.mean(errors < 0.1)), 4) if len(errors) else None,
            "ms_per_frame_median": round(float(np.median([r["ms"] for r in rows])), 1),
            "problems": sorted({p for r in rows for p in r["problems"]}),
        }
    return table


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fractures", type=int, default=4, help="fractures (seeds 0..n-1)")
    parser.add_argument("--scenes", type=int, default=3, help="scatters per fracture and source")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-cell", action="store_true", help="synthetic frames only")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    fractures = [fracture(SLAB_M, 6, 0.002, seed) for seed in range(args.fractures)]
    results = synthetic(fractures, args.scenes, args.seed)
    if not args.no_cell:
        results += cell(fractures, args.scenes, args.seed)
    table = summarise(results)
    machine = "this machine, 2 cores, shared"
    if args.json:
        print(json.dumps({"machine": machine, "sources": table}, indent=2))
        return 0
    print(f"unknown outlines: {args.fractures} fractures x {args.scenes} scenes of 6 pieces ({machine})")
    columns = ("pieces", "measured", "counts off", "mean mm", "p95 mm", "max mm", "<0.1 mm", "ms")
    print(f"{'source':<14} " + " ".join(f"{c:>10}" for c in columns))
    for source, row in table.items():
        error = row["vertex_error_mm"]
        values = (row["pieces"], row["measured"], row["wrong_vertex_count"], error["mean"], error["p95"], error["max"])
        values += (row["share_within_0.1_mm"], row["ms_per_frame_median"])
        print(f"{source:<14} " + " ".join(f"{v!s:>10}" for v in values))
        for problem in row["problems"]:
            print(f"    {problem}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
