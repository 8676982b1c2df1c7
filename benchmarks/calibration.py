"""Calibration benchmark: the full ChArUco calibration in a cell, judged against the simulator's truth.

    python benchmarks/calibration.py --cell real --views 28 [--out camera.toml] [--json]

1. Runs ``bt-arrange calibrate``'s procedure (``SimBackend.open_calibration``) and reports the RMS
   reprojection error, the hand-eye residual and the camera-to-base error against the true camera
   (position in mm, rotation in mrad), and the intrinsics' errors.
2. Puts cubes on a grid over the usable area (the trials' and the scatter's, ``realcell.WORKSPACE_*``)
   with random yaws, four at a time, and measures each with the detector on a full frame: once with
   the camera's nominal values (what the cell's software knows before calibration) and once through
   the calibration (``CalibratedCamera``). Errors are planar distances to ground truth, in mm.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from bt_arrange.calibration import CalibratedCamera, write_calibration
from bt_arrange.perception import PartDetector
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.pybullet.backend import SimBackend
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.realcell import WORKSPACE_X_M, WORKSPACE_Y_M, parse_cell

COLOURS = ("red", "yellow", "green", "blue")


def detection_errors_mm(cell_name: str, calibration: object, grid: int = 6, seed: int = 0) -> dict[str, list[float]]:
    """Cube detection errors (mm) over a grid of the usable area: nominal camera and calibrated camera."""
    errors = parse_cell(cell_name)
    config = CellConfig(errors=errors) if errors.enabled else CellConfig()
    rng = np.random.default_rng(seed)
    xs = np.linspace(WORKSPACE_X_M[0] + 0.02, WORKSPACE_X_M[1] - 0.02, grid)
    ys = np.linspace(WORKSPACE_Y_M[0] + 0.02, WORKSPACE_Y_M[1] - 0.02, grid)
    points = [(float(x), float(y)) for x in xs for y in ys]
    detector = PartDetector()
    out: dict[str, list[float]] = {"nominal": [], "calibrated": []}
    with WorkCell(config) as cell:
        calibrated = CalibratedCamera(cell.camera, calibration)  # type: ignore[arg-type]
        for start in range(0, len(points), len(COLOURS)):
            batch = points[start : start + len(COLOURS)]
            for colour, (x, y) in zip(COLOURS, batch, strict=False):
                cell.add_cube(colour, x, y, yaw_rad=float(rng.uniform(-math.pi / 4, math.pi / 4)))
            cell.settle(0.3)
            frames = {"nominal": cell.camera.capture(), "calibrated": calibrated.capture()}
            for colour, _ in zip(COLOURS, batch, strict=False):
                tx, ty, _ = cell.part_planar_truth(colour)
                for name, frame in frames.items():
                    found = detector.detect(frame, colour)
                    if found.pose_world is None:
                        out[name].append(float("nan"))
                        continue
                    out[name].append(math.hypot(found.pose_world.x_m - tx, found.pose_world.y_m - ty) * 1000)
                cell.remove_part(colour)
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cell", default="real")
    parser.add_argument("--views", type=int, default=28)
    parser.add_argument("--grid", type=int, default=6, help="cubes per side of the grid (default 6: 36 cubes)")
    parser.add_argument("--out", type=Path, help="write the calibration file here too")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)

    with SimBackend().open_calibration(views=args.views, cell=args.cell) as run:
        outcome = run.run()
        true_k, true_pose = run.true_camera()
    calibration = outcome.calibration
    if calibration is None:
        print(f"calibration failed: {outcome.reason}", file=sys.stderr)
        return 1
    if args.out is not None:
        write_calibration(calibration, args.out)
    k, pose = calibration.intrinsics, calibration.camera_to_base
    relative = true_pose.inverse() @ pose
    rotation_mrad = math.acos(max(-1.0, min(1.0, (float(np.trace(relative.rotation)) - 1) / 2))) * 1000
    detection = detection_errors_mm(args.cell, calibration, grid=args.grid)

    def summary(values: list[float]) -> dict[str, float]:
        v = np.asarray(values, dtype=float)
        found = v[np.isfinite(v)]
        return {
            "mean_mm": round(float(found.mean()), 4) if len(found) else float("nan"),
            "max_mm": round(float(found.max()), 4) if len(found) else float("nan"),
            "found": int(len(found)),
            "cubes": int(len(v)),
        }

    result = {
        "cell": args.cell,
        "poses": outcome.poses,
        "views": calibration.views,
        "unreachable": outcome.unreachable,
        "not_seen": outcome.not_seen,
        "reprojection_error_px": round(calibration.reprojection_error_px, 4),
        "hand_eye_residual_mm": round(calibration.hand_eye_residual_mm or 0.0, 4),
        "camera_to_base_error_mm": round(float(np.linalg.norm(relative.position_m)) * 1000, 4),
        "camera_to_base_error_mrad": round(rotation_mrad, 4),
        "intrinsics_error_px": {
            name: round(getattr(k, name) - getattr(true_k, name), 4) for name in ("fx_px", "fy_px", "cx_px", "cy_px")
        },
        "distortion": [round(v, 6) for v in k.distortion],
        "true_distortion": [round(v, 6) for v in true_k.distortion],
        "detection_nominal": summary(detection["nominal"]),
        "detection_calibrated": summary(detection["calibrated"]),
        "sim_seconds": round(outcome.report.sim_seconds, 1),
        "wall_seconds": round(outcome.report.wall_seconds, 1),
    }
    print(json.dumps(result) if args.json else json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
