"""Parts that touch where they start: each scene of ``tests/touching_scenes.py`` run headless.

    python benchmarks/touching.py [--scenes "two red cubes" ...]

Per scene, one JSON line: each part's status and final offset by ground truth (the simulator's,
evaluation only), how many pushes aside the tree made (``Separate``, from the run's transitions),
and the run's world and wall time. The last line sums up: parts within of parts, scenes whose
every part ended within.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from touching_scenes import SCENES, scene  # noqa: E402

from bt_arrange_sim.pybullet.runs import SimulatedRun  # noqa: E402


def run(name: str, folder: Path) -> dict[str, object]:
    """One scene's outcome as a JSON-ready dict."""
    from bt_arrange.behaviours import Separate

    root, starts = scene(name, folder)
    separations: list[str] = []
    began = time.perf_counter()
    with SimulatedRun(root, starts) as simulated:
        report = simulated.run()
    wall_s = time.perf_counter() - began
    separations = [
        node.feedback_message for node in root.iterate() if isinstance(node, Separate) and node.pushed_mm is not None
    ]
    parts = {
        o.name: {"status": o.status, "truth_mm": o.final_offset_truth_mm, "reason": o.reason} for o in report.objects
    }
    return {
        "scene": name,
        "within": sum(o.status == "within" for o in report.objects),
        "parts": len(report.objects),
        "separations": sum(o.separations for o in report.objects),
        "separated_by": separations,
        "world_s": round(report.sim_seconds, 1),
        "wall_s": round(wall_s, 1),
        "objects": parts,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="*", default=list(SCENES))
    args = parser.parse_args(argv)
    within = parts = whole = 0
    with tempfile.TemporaryDirectory() as folder:
        for name in args.scenes:
            outcome = run(name, Path(folder))
            print(json.dumps(outcome), flush=True)
            within += int(outcome["within"])  # type: ignore[call-overload]
            parts += int(outcome["parts"])  # type: ignore[call-overload]
            whole += outcome["within"] == outcome["parts"]
    print(json.dumps({"parts_within": within, "parts": parts, "scenes_all_within": whole, "scenes": len(args.scenes)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
