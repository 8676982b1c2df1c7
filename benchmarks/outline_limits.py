"""What judging an outline costs, and how long the hardest plan file within the limits takes to load.

    python benchmarks/outline_limits.py [--json]

1. The self-crossing check (``bt_arrange.shapes.polygon.first_crossing``, a sweep line) against
   testing every pair of edges (the check before it was bounded), on simple polygons of n points: CPU
   seconds, and the sweep's time over n log2 n (flat if it grows as n log n) and the pairs' over n^2.
2. The grasp search of one type (``bt_arrange.shapes.antipodal``) on 32-point outlines, with the
   rough judgement of every centre at once and with the exact loop alone (the same grasps).
3. The checks of one round part (``round_part``: the most closing axes an outline of n points
   can offer, every one judged along the whole part) at 64, 128 and 256 points: CPU seconds of the
   grasp search and of the yaw check (``bt_arrange.shapes.yaw_feature``), and their time over n log2 n.
4. Plan files at the limits (``bt_arrange.filelimits``): one type of ``MAX_OUTLINE_POINTS`` points;
   as many such types as ``MAX_PLAN_OUTLINE_POINTS`` allows; ``MAX_OBJECT_TYPES`` types sharing
   ``MAX_PLAN_OUTLINE_POINTS``; all different, all accepted; and every shipped plan. CPU seconds of
   ``plans.load`` (read, checked, every type judged), the figure the limits are set by (under 2 s).

Times are CPU seconds of this process (``time.process_time``), so other jobs on the machine change
them less than wall time (not nothing: the machine and its load average are printed); the ratios
are measured in one run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bt_arrange import plans
from bt_arrange.filelimits import MAX_OBJECT_TYPES, MAX_OUTLINE_POINTS, MAX_PLAN_OUTLINE_POINTS
from bt_arrange.shapes import Prism, antipodal, yaw_feature
from bt_arrange.shapes.gripper import ROBOTIQ_2F85
from bt_arrange.shapes.polygon import first_crossing, segments_cross

ROOT = Path(__file__).resolve().parents[1]
#: The outlines on which the rough judgement is compared with the exact loop alone (which is slow).
COMPARED_POINTS = 32


def cpu_s(call, repeat: int = 1) -> float:  # noqa: ANN001 - any callable
    """The least CPU time of ``repeat`` calls."""
    best = math.inf
    for _ in range(repeat):
        start = time.process_time()
        call()
        best = min(best, time.process_time() - start)
    return best


def every_pair(points: np.ndarray) -> bool:
    """The check before it was bounded: every pair of edges that are not neighbours tested."""
    count = len(points)
    for i in range(count):
        for j in range(i + 1, count):
            if j == i + 1 or (i == 0 and j == count - 1):
                continue
            if segments_cross(points[i], points[(i + 1) % count], points[j], points[(j + 1) % count]):
                return True
    return False


def wavy(count: int, seed: int = 0, radius_mm: float = 35.0) -> np.ndarray:
    """A simple, non-convex outline of ``count`` points (metres): a circle with a random ripple."""
    rng = np.random.default_rng(seed)
    angles = np.linspace(0, 2 * math.pi, count, endpoint=False)
    lobes, depth = int(rng.integers(3, 8)), rng.uniform(2.0, 5.0)
    radii = (radius_mm + depth * np.sin(lobes * angles + rng.uniform(0, 2 * math.pi))) / 1000
    return np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])


def crossing_rows() -> list[dict]:
    rows = []
    for count in (64, 256, 1024, 4096, 16384):
        points = wavy(count)
        sweep = cpu_s(lambda p=points: first_crossing(p), repeat=3 if count <= 1024 else 1)
        pairs = cpu_s(lambda p=points: every_pair(p)) if count <= 1024 else None
        rows.append(
            {
                "points": count,
                "sweep_cpu_s": round(sweep, 4),
                "sweep_us_per_n_log_n": round(sweep / (count * math.log2(count)) * 1e6, 3),
                "every_pair_cpu_s": None if pairs is None else round(pairs, 3),
                "every_pair_ns_per_n2": None if pairs is None else round(pairs / count**2 * 1e9, 1),
            }
        )
    return rows


def grasp_rows() -> list[dict]:
    rows = []
    exact = antipodal._clearly_refused

    def none_refused(points, closing, along, centres, *rest):  # noqa: ANN001, ANN202
        return np.zeros(len(centres), dtype=bool)

    for seed in range(3):
        outline = wavy(COMPARED_POINTS, seed)
        fast = cpu_s(lambda o=outline: antipodal._search(o, 0.02, ROBOTIQ_2F85))
        antipodal._clearly_refused = none_refused
        try:
            slow = cpu_s(lambda o=outline: antipodal._search(o, 0.02, ROBOTIQ_2F85))
            alone = antipodal._search(outline, 0.02, ROBOTIQ_2F85)
        finally:
            antipodal._clearly_refused = exact
        same = antipodal._search(outline, 0.02, ROBOTIQ_2F85) == alone
        axes = len(antipodal._closing_axes(outline))
        rows.append({"outline": f"wavy {COMPARED_POINTS} points, seed {seed}", "axes": axes,
                     "grasps": len(alone), "cpu_s": round(fast, 3), "exact_loop_alone_cpu_s": round(slow, 3),
                     "same_grasps": same})  # fmt: skip
    return rows


def round_part(count: int, seed: int = 0) -> np.ndarray:
    """A part a plan may hold (metres): ``count`` points, every one a closing axis the grasp search tries.

    Two flats 24 mm long, 71 mm apart (where the pads hold it), joined by arcs of radius 37.5 mm
    with a ripple of up to 1 mm (so no turn is a symmetry), every turn along them under the 10 deg
    that make a corner: the hardest outline of ``count`` points for the type check (each edge's
    normal is another closing axis, judged along the whole part), and one it accepts (40 points or more).
    """
    rng = np.random.default_rng(seed)
    edge = math.asin(0.012 / 0.0375)
    phases = rng.uniform(0, 2 * math.pi, 4)

    def arc(middle: float, phase: np.ndarray, points: int) -> np.ndarray:
        angles = np.linspace(middle - (math.pi / 2 - edge), middle + (math.pi / 2 - edge), points + 2)[1:-1]
        fade = np.sin(angles) ** 2  # no ripple next to the flats
        radius = 0.0375 + (0.0006 * np.sin(3 * angles + phase[0]) + 0.0004 * np.sin(5 * angles + phase[1])) * fade
        return np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])

    across = 0.0375 * math.cos(edge)
    upper = (count - 4) // 2
    right, left = [[across, -0.012], [across, 0.012]], [[-across, 0.012], [-across, -0.012]]
    return np.vstack(
        [right, arc(math.pi / 2, phases[:2], upper), left, arc(3 * math.pi / 2, phases[2:], count - 4 - upper)]
    )


def accepted_parts(count: int, points: int) -> list[np.ndarray]:
    """``count`` different round parts of ``points`` points that the type check accepts."""
    parts, seed = [], 0
    while len(parts) < count:
        outline = round_part(points, seed)
        seed += 1
        if not Prism.from_outline(outline.tolist(), 0.02).problems(ROBOTIQ_2F85):
            parts.append(outline)
    return parts


def scaling_rows() -> list[dict]:
    rows = []
    for points in (64, 128, 256):
        shape = Prism.from_outline(round_part(points).tolist(), 0.02)
        antipodal.antipodal_grasps.cache_clear()
        grasp = cpu_s(lambda s=shape: antipodal._search(np.array(s.outline), 0.02, ROBOTIQ_2F85))
        yaw_feature._feature.cache_clear()
        yaw = cpu_s(lambda s=shape: (yaw_feature._feature.cache_clear(), s.yaw_problems()))
        scale = points * math.log2(points)
        rows.append({"points": points, "axes": len(antipodal._closing_axes(np.array(shape.outline))),
                     "grasp_cpu_s": round(grasp, 3), "grasp_ms_per_n_log_n": round(grasp / scale * 1000, 3),
                     "yaw_cpu_s": round(yaw, 3), "yaw_ms_per_n_log_n": round(yaw / scale * 1000, 3)})  # fmt: skip
    return rows


def plan_text(outlines: list[np.ndarray]) -> str:
    """Every outline a type; one target (every type is judged as the plan loads, used or not)."""
    lines = ["threshold_mm = 1.0"]
    for k, outline in enumerate(outlines):
        points = ", ".join(f"[{x * 1000:.3f}, {y * 1000:.3f}]" for x, y in outline)
        lines += [f"[objects.part{k}]", f"outline_mm = [{points}]", "height_mm = 20"]
    lines += ["[[targets]]", 'object = "part0"', 'colour = "red"', "x_mm = 500", "y_mm = 0", "yaw_deg = 90"]
    return "\n".join(lines) + "\n"


def load_cpu_s(text: str, folder: Path, name: str) -> tuple[float, str]:
    path = folder / name
    path.write_text(text)
    outcome = "loaded"

    def load() -> None:
        nonlocal outcome
        antipodal.antipodal_grasps.cache_clear()  # every type judged afresh
        yaw_feature._feature.cache_clear()
        try:
            plans.load(path)
        except plans.PlanError as error:
            outcome = f"refused: {str(error).split(': ', 2)[-1][:100]}"

    return cpu_s(load), outcome


def plan_rows() -> list[dict]:
    rows = []
    full = MAX_PLAN_OUTLINE_POINTS // MAX_OUTLINE_POINTS
    shared = MAX_PLAN_OUTLINE_POINTS // MAX_OBJECT_TYPES
    with tempfile.TemporaryDirectory() as folder:
        for label, outlines in (
            (f"1 type of {MAX_OUTLINE_POINTS} points", accepted_parts(1, MAX_OUTLINE_POINTS)),
            (f"{full} types of {MAX_OUTLINE_POINTS} points, all different", accepted_parts(full, MAX_OUTLINE_POINTS)),
            (f"{MAX_OBJECT_TYPES} types of {shared} points, all different", accepted_parts(MAX_OBJECT_TYPES, shared)),
        ):
            cpu, outcome = load_cpu_s(plan_text(outlines), Path(folder), "limits.toml")
            rows.append({"plan": label, "cpu_s": round(cpu, 3), "outcome": outcome})
    shipped = sorted((ROOT / "bt_arrange" / "examples").glob("*.toml"))
    for path in shipped:
        antipodal.antipodal_grasps.cache_clear()
        yaw_feature._feature.cache_clear()
        rows.append({"plan": f"shipped {path.name}", "cpu_s": round(cpu_s(lambda p=path: plans.load(p)), 3),
                     "outcome": "loaded"})  # fmt: skip
    return rows


def machine() -> str:
    """The processor, its cores and the load average as the run starts."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg()) if hasattr(os, "getloadavg") else "unknown"
    return f"{model}, {os.cpu_count()} cores, load average {load}, Python {platform.python_version()}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    result = {"machine": machine(), "crossing": crossing_rows(), "grasps": grasp_rows(), "scaling": scaling_rows(),
              "plans": plan_rows()}  # fmt: skip
    at_limits = [row for row in result["plans"] if not row["plan"].startswith("shipped")]
    result["hardest"] = max(at_limits, key=lambda row: row["cpu_s"])
    if args.json:
        print(json.dumps(result))
        return 0
    print(f"machine: {result['machine']}")
    print("self-crossing check: sweep line against every pair (CPU s)")
    for row in result["crossing"]:
        pairs = "-" if row["every_pair_cpu_s"] is None else f"{row['every_pair_cpu_s']:.3f} s"
        ratio = "" if row["every_pair_ns_per_n2"] is None else f" ({row['every_pair_ns_per_n2']} ns / n^2)"
        print(f"  {row['points']:>6} points: sweep {row['sweep_cpu_s']:.4f} s ({row['sweep_us_per_n_log_n']} us / "
              f"n log2 n), every pair {pairs}{ratio}")  # fmt: skip
    print("grasp search of one type (CPU s)")
    for row in result["grasps"]:
        alone = row["exact_loop_alone_cpu_s"]
        print(f"  {row['outline']}: {row['axes']} axes, {row['grasps']} grasps, {row['cpu_s']:.3f} s "
              f"(exact loop alone {alone:.3f} s; same grasps: {row['same_grasps']})")  # fmt: skip
    print("checks of one round part (CPU s)")
    for row in result["scaling"]:
        print(f"  {row['points']:>4} points, {row['axes']} axes: grasp search {row['grasp_cpu_s']:.3f} s "
              f"({row['grasp_ms_per_n_log_n']} ms / n log2 n), yaw check {row['yaw_cpu_s']:.3f} s "
              f"({row['yaw_ms_per_n_log_n']} ms / n log2 n)")  # fmt: skip
    print("plan files judged by plans.load (CPU s)")
    for row in result["plans"]:
        print(f"  {row['plan']}: {row['cpu_s']:.3f} s, {row['outcome']}")
    hardest = result["hardest"]
    print(f"the hardest plan within the limits: {hardest['plan']}, {hardest['cpu_s']:.3f} s of CPU to load "
          f"(the bound: 2 s), on {result['machine']}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
