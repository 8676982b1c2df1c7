"""Outline benchmark: register known outlines to rendered faces and compare with ground truth.

    python benchmarks/outlines.py --poses 100 --seed 0 --json [--cell] [--method edge_lines]

Five outlines: a scalene triangle, an L, an asymmetric trapezoid, a regular
pentagon (72-degree symmetry: its yaw is folded) and a non-convex fragment, each 20 mm tall.
Every pose puts one part at a random place over the visible table (whole in the image at any
yaw), yaw over the full circle, 45..100 % light, and renders it three ways with
``bt_arrange.perception.synthetic`` (ground truth exact): anti-aliased (8 x 8 samples per
pixel), aliased (pixel centres only, like pybullet's TinyRenderer) and noisy (4 grey levels of
noise after a 0.8 px blur). ``--cell`` also renders scenes in the pybullet cell's top camera
(TinyRenderer, 1920 x 1080): four of the five parts each, in different colours, as the cell's
bodies (``bt_arrange_sim.pybullet.objects.create_object``), about ``--poses`` of each outline in all; the
truth is the simulator's pose after the parts settle. ``ms_per_detection`` is the median CPU
time of one ``detect`` (the machine is shared). ``--method`` compares the fine registrations
(``edge_lines``, the default; ``corner_subpix``; ``contour_lines``; ``none``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace

import numpy as np

from bt_arrange.geometry import fold_yaw
from bt_arrange.objects import ObjectType
from bt_arrange.perception import CornerRefinement, DetectorConfig, PartDetector
from bt_arrange.perception.synthetic import (
    SyntheticPrism,
    render_frame,
    sim_intrinsics,
    top_down_camera_pose,
    visible_table_box,
)
from bt_arrange.shapes import Prism


def _mm(points: list[list[float]]) -> np.ndarray:
    return np.asarray(points, dtype=float) / 1000.0


def _regular(sides: int, radius_mm: float) -> list[list[float]]:
    return [
        [radius_mm * math.cos(2 * math.pi * k / sides), radius_mm * math.sin(2 * math.pi * k / sides)]
        for k in range(sides)
    ]


HEIGHT_M = 0.02
#: The benchmark's outlines (mm as written; the part's frame is the area centroid).
OUTLINES_MM: dict[str, list[list[float]]] = {
    "triangle": [[0, 0], [60, 0], [15, 45]],
    "ell": [[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]],
    "trapezoid": [[0, 0], [70, 0], [50, 35], [15, 35]],
    "pentagon": _regular(5, 30.0),
    "fragment": [[0, 0], [45, 4], [60, 30], [35, 28], [30, 50], [5, 40]],
}
PARTS = {
    name: ObjectType(name, shape=Prism.from_outline(_mm(points), HEIGHT_M)) for name, points in OUTLINES_MM.items()
}
RENDERS = {
    "antialiased": {"supersample": 8},
    "aliased": {"supersample": 1},
    "noisy": {"supersample": 8, "noise_sigma": 4.0, "blur_sigma_px": 0.8},
}
COLOURS = ("red", "green", "blue", "yellow")


def _error(detection, part: ObjectType, x_m: float, y_m: float, yaw_rad: float) -> dict:
    if not detection.found:
        return {"status": detection.status.value, "reason": detection.reason}
    pose = detection.pose_world
    return {
        "status": "found",
        "xy_error_mm": math.hypot(pose.x_m - x_m, pose.y_m - y_m) * 1000,
        "yaw_error_deg": abs(math.degrees(fold_yaw(pose.yaw_rad - yaw_rad, part.shape.symmetry_rad))),
    }


def synthetic(poses: int, seed: int, method: CornerRefinement) -> list[dict]:
    """``poses`` frames per outline and render, one part each; the per-detection errors."""
    rng = np.random.default_rng(seed)
    intrinsics, camera = sim_intrinsics(), top_down_camera_pose()
    results = []
    for name, part in PARTS.items():
        shape = part.shape
        assert isinstance(shape, Prism)
        x_min, x_max, y_min, y_max = visible_table_box(intrinsics, camera, HEIGHT_M, shape.sweep_radius_m + 0.005)
        detector = PartDetector(config=replace(DetectorConfig(), corner_refinement=method)).for_object(part)
        for index in range(poses):
            x, y = float(rng.uniform(x_min, x_max)), float(rng.uniform(y_min, y_max))
            yaw = float(rng.uniform(-math.pi, math.pi))
            colour = str(rng.choice(COLOURS))
            brightness = float(rng.uniform(0.45, 1.0))
            for render, options in RENDERS.items():
                frame = render_frame(
                    [SyntheticPrism(colour, x, y, yaw, shape, brightness)], seed=seed * 100003 + index, **options
                )
                start = time.process_time()
                detection = detector.detect(frame, colour)
                ms = (time.process_time() - start) * 1000
                results.append({"source": render, "outline": name, "ms": ms, **_error(detection, part, x, y, yaw)})
    return results


def cell(poses: int, seed: int, method: CornerRefinement) -> list[dict]:
    """Scenes in the pybullet cell's top camera: four of the five parts (one per colour) as the cell's bodies.

    Each part is ``create_object``'s exact prism (a 0.1 mm coloured top plate on near-white
    sides), settled on the table; the truth is the simulator's pose of the body after settling.
    """
    from bt_arrange_sim.config import CellConfig
    from bt_arrange_sim.pybullet.cell import WorkCell

    rng = np.random.default_rng(seed + 1)
    results = []
    config = replace(DetectorConfig(), corner_refinement=method)
    detectors = {name: PartDetector(config=config).for_object(part) for name, part in PARTS.items()}
    with WorkCell(CellConfig()) as world:
        view = world.config.camera.view()
        scenes = max(1, round(poses * len(PARTS) / len(COLOURS)))
        for _ in range(scenes):
            names = [str(n) for n in rng.permutation(list(PARTS))][: len(COLOURS)]
            placed: list[tuple[str, str, float, float]] = []
            for colour, name in zip(COLOURS, names, strict=True):
                shape = PARTS[name].shape
                assert isinstance(shape, Prism)
                while True:
                    x, y = float(rng.uniform(0.29, 0.71)), float(rng.uniform(-0.40, 0.40))
                    if math.hypot(x, y) > 0.8 or not view.sees_disc(x, y, shape.sweep_radius_m + 0.005, HEIGHT_M):
                        continue
                    if all(math.hypot(x - px, y - py) > 0.085 for _, _, px, py in placed):
                        break
                placed.append((colour, name, x, y))
                world.add_object(PARTS[name], colour, x, y, float(rng.uniform(-math.pi, math.pi)), name=name)
            world.settle(0.05)
            frame = world.camera.capture()
            for colour, name, *_ in placed:
                start = time.process_time()
                detection = detectors[name].detect(frame, colour)
                ms = (time.process_time() - start) * 1000
                x, y, yaw = world.part_planar_truth(name)
                error = _error(detection, PARTS[name], x, y, yaw)
                results.append({"source": "cell", "outline": name, "ms": ms, **error})
            for _, name, *_ in placed:
                world.remove_part(name)
    return results


def summarise(results: list[dict]) -> dict:
    """Per source (render) and outline: detections, misses, xy and yaw error mean / p95 / max."""

    def stats(values: list[float]) -> dict:
        if not values:
            return {"mean": None, "p95": None, "max": None}
        array = np.asarray(values)
        return {
            "mean": round(float(array.mean()), 4),
            "p95": round(float(np.percentile(array, 95)), 4),
            "max": round(float(array.max()), 4),
        }

    table: dict = {}
    for source in dict.fromkeys(r["source"] for r in results):
        rows = [r for r in results if r["source"] == source]
        entry: dict = {}
        for outline in [*dict.fromkeys(r["outline"] for r in rows), "all"]:
            mine = [r for r in rows if outline == "all" or r["outline"] == outline]
            found = [r for r in mine if r["status"] == "found"]
            entry[outline] = {
                "detections": len(mine),
                "misses": len(mine) - len(found),
                "xy_error_mm": stats([r["xy_error_mm"] for r in found]),
                "yaw_error_deg": stats([r["yaw_error_deg"] for r in found]),
                "ms_per_detection": round(float(np.median([r["ms"] for r in mine])), 1),
            }
            reasons = sorted({r["reason"] for r in mine if r["status"] != "found"})
            if reasons:
                entry[outline]["reasons"] = reasons[:5]
        table[source] = entry
    return table


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=40, help="poses per outline (default 40)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--cell", action="store_true", help="also render scenes in the pybullet cell")
    parser.add_argument("--no-synthetic", action="store_true", help="only the pybullet cell's frames")
    parser.add_argument(
        "--method", choices=[m.value for m in CornerRefinement], default="edge_lines", help="the fine registration"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.poses < 1:
        parser.error(f"--poses must be at least 1, got {args.poses}")
    method = CornerRefinement(args.method)
    results = [] if args.no_synthetic else synthetic(args.poses, args.seed, method)
    if args.cell:
        results += cell(args.poses, args.seed, method)
    summary = {
        "benchmark": "outlines",
        "truth": "detections compared with the renderer's ground truth",
        "method": method.value,
        "poses_per_outline": args.poses,
        "outlines": {name: points for name, points in OUTLINES_MM.items()},
        "results": summarise(results),
    }
    if args.json:
        print(json.dumps(summary))
        return 0
    print(f"method {method.value}, {args.poses} poses per outline, seed {args.seed}")
    for source, entry in summary["results"].items():
        for outline, row in entry.items():
            xy, yaw = row["xy_error_mm"], row["yaw_error_deg"]
            print(
                f"{source:12s} {outline:10s} {row['detections']:4d} det {row['misses']:3d} missed  "
                f"xy mean {xy['mean']} p95 {xy['p95']} max {xy['max']} mm  "
                f"yaw mean {yaw['mean']} p95 {yaw['p95']} max {yaw['max']} deg  {row['ms_per_detection']} ms"
            )
            for reason in row.get("reasons", []):
                print(f"    {reason}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
