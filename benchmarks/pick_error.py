"""A 2 cm picking error, injected and corrected: the README's "a 2 cm pick error injected" row.

    python benchmarks/pick_error.py [--json]

The single cube of ``trees/single_cube.py`` (seed 0) is moved 2 cm, at 45 degrees to its faces,
after it was detected and before the grasp (the paper's picking error; the same run as
``tests/integration/test_tree_files.py``'s test, which checks it). Prints the offset after placing
and after pushing, by the camera and by ground truth (the simulator's, for evaluation only), and
the pushes. Deterministic: the same figures on every machine with the same libraries.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from bt_arrange import treefile
from bt_arrange_sim.pybullet.runs import SimulatedRun

TREE = Path(__file__).resolve().parents[1] / "trees" / "single_cube.py"
DISPLACEMENT_M = 0.02


def run(seed: int = 0) -> dict:
    """One run with the error injected; its figures."""
    module = treefile.load(TREE)
    root = treefile.build_root(module)
    with SimulatedRun(root, treefile.scene(module, seed=seed)) as session:

        def bump_after_detection(transition) -> None:  # noqa: ANN001
            if transition.behaviour == "detect red" and transition.new == "SUCCESS":
                # 45 degrees to the faces: 14 mm along each, so the pads still come down beside it.
                direction = session.cell.part_planar_truth("red")[2] + math.pi / 4
                session.cell.displace_part(
                    "red", DISPLACEMENT_M * np.cos(direction), DISPLACEMENT_M * np.sin(direction)
                )

        session.transition_hooks.append(bump_after_detection)
        report = session.run()
    (red,) = report.objects
    return {
        "seed": seed,
        "placed_mm": red.placed_offset_mm,
        "placed_truth_mm": red.placed_offset_truth_mm,
        "pushes": red.pushes,
        "pushed_mm": red.final_offset_mm,
        "pushed_truth_mm": red.final_offset_truth_mm,
        "status": red.status,
    }


def main(argv: list[str] | None = None) -> int:
    """Run and print."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = run(args.seed)
    if args.json:
        print(json.dumps(result))
    else:
        print(
            f"a 2 cm pick error injected: placed {result['placed_mm']:.1f} mm off (truth "
            f"{result['placed_truth_mm']:.1f}), {result['pushes']} push(es), {result['pushed_mm']:.2f} mm by the "
            f"camera, {result['pushed_truth_mm']:.2f} mm by ground truth ({result['status']})"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
