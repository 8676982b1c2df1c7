"""How long a fresco plan takes to judge, over slabs of every shape the plan file allows.

    python benchmarks/fresco_limits.py [--quick] [--json]

A ``[fresco.NAME]`` is judged as a run judges it before anything moves: ``plans.load`` (the
fracture's draws, every piece's checks, the layout's search over placing orders), the tree
(``Plan.create_root``) and the plan check (``check_plan``). This sweeps slabs from 40 to 600 mm
long and 40 to 400 mm wide, 3 to 12 pieces, two fracture seeds, at a 2 mm gap (threshold 1 mm)
and at 0.5 mm (threshold 0.25 mm), and prints each plan's CPU seconds and outcome as it goes (a
line each), then the hardest: the figure the file limits bound (any plan within the file's limits
judged in under 2 s). ``--quick`` takes a sixth of the grid.

Times are CPU seconds of this process (``time.process_time``); the machine and its load average
are printed with them.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

from bt_arrange import plans
from bt_arrange.errors import PlanError
from bt_arrange.plan.check import check_plan

LENGTHS_MM = (40, 80, 120, 160, 200, 300, 400, 600)
WIDTHS_MM = (40, 60, 80, 120, 160, 250, 400)
PIECES = (3, 4, 6, 8, 10, 12)
SEEDS = (0, 1)
#: (gap_mm, threshold_mm): the default gap, and the finest a plan may ask.
GAPS = ((2.0, 1.0), (0.5, 0.25))

PLAN = """threshold_mm = {threshold}
yaw_threshold_deg = {threshold}
[colours.ochre]
rgb = [0.8, 0.55, 0.2]
[fresco.tile]
size_mm = [{length}, {width}, 20]
pieces = {pieces}
gap_mm = {gap}
seed = {seed}
colour = "ochre"
x_mm = 500
y_mm = 0
"""


def machine() -> str:
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average {load}"


def judge(folder: Path, **slab: float) -> dict:
    """One plan judged: its CPU seconds and its outcome (accepted, or the refusal's line)."""
    path = folder / "fresco.toml"
    path.write_text(PLAN.format(**slab))
    start = time.process_time()
    try:
        plan = plans.load(path)
        root = plan.create_root()
        check_plan(plan.targets, threshold_mm=plan.threshold_mm, colours=plan.colours.names, settings=root.settings)
        outcome = "accepted"
    except PlanError as error:
        lines = str(error).splitlines()
        outcome = "refused: " + lines[0].split(": [fresco.tile]: ", 1)[-1][:100]
        outcome += "" if len(lines) == 1 else " (MORE LINES)"
    return {**slab, "cpu_s": round(time.process_time() - start, 3), "outcome": outcome}


def grid(quick: bool) -> list[dict]:
    slabs = [
        {"length": length, "width": width, "pieces": pieces, "seed": seed, "gap": gap, "threshold": threshold}
        for (length, width), pieces, seed, (gap, threshold) in itertools.product(
            [(length, width) for length in LENGTHS_MM for width in WIDTHS_MM if width <= length],
            PIECES,
            SEEDS,
            GAPS,
        )
    ]
    return slabs[::6] if quick else slabs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a sixth of the grid")
    parser.add_argument("--json", action="store_true", help="print one JSON object at the end, not a line a plan")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for slab in grid(args.quick):
            row = judge(Path(folder), **slab)
            rows.append(row)
            if not args.json:
                print(
                    f"{row['length']:>4} x {row['width']:>3} mm, {row['pieces']:>2} pieces, seed {row['seed']}, "
                    f"gap {row['gap']:g} mm: {row['cpu_s']:6.3f} s  {row['outcome']}",
                    flush=True,
                )
    hardest = max(rows, key=lambda row: row["cpu_s"])
    accepted = [row for row in rows if row["outcome"] == "accepted"]
    result = {
        "machine": machine(),
        "plans": len(rows),
        "accepted": len(accepted),
        "over_2_s": sum(row["cpu_s"] >= 2.0 for row in rows),
        "hardest": hardest,
        "hardest_accepted": max(accepted, key=lambda row: row["cpu_s"]) if accepted else None,
        "more_than_one_line": sum("MORE LINES" in row["outcome"] for row in rows),
    }
    if args.json:
        print(json.dumps({**result, "rows": rows}))
        return 0
    print(f"machine: {result['machine']}")
    print(
        f"{result['plans']} plans judged ({result['accepted']} accepted), {result['over_2_s']} took 2 s of CPU "
        f"or more, {result['more_than_one_line']} refused in more than one line"
    )
    for label in ("hardest", "hardest_accepted"):
        row = result[label]
        if row is not None:
            print(
                f"{label.replace('_', ' ')}: {row['length']} x {row['width']} mm in {row['pieces']} pieces, seed "
                f"{row['seed']}, gap {row['gap']:g} mm: {row['cpu_s']:.3f} s ({row['outcome']})"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
