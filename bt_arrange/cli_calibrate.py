"""``bt-arrange calibrate``: the top camera calibrated in a cell, written to one file."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from bt_arrange import backends
from bt_arrange.backends import CalibratingBackend, TrueCameraRun, require
from bt_arrange.cli_common import EXIT_NOT_WITHIN, EXIT_OK, connect_backend
from bt_arrange.errors import BtArrangeError, RecordError


def _calibrate(args: argparse.Namespace) -> int:
    from bt_arrange.calibration import matrix_rpy, write_calibration

    backend = backends.load(args.backend)
    connect_backend(backend, args)
    open_calibration = require(backend, CalibratingBackend, "calibrate").open_calibration
    out = Path(args.out)
    if out.parent and not out.parent.is_dir():
        raise BtArrangeError(f"--out {out}: the folder {out.parent} does not exist")
    with open_calibration(
        views=args.views,
        gui=args.gui,
        record_dir=args.record,
        time_limit_s=args.time_limit_s,
        **({"cell": args.cell, "run_seed": args.seed} if args.cell != "ideal" else {}),
        **_speed_option(backend, args.speed_fraction),
    ) as run:
        if args.live:
            from bt_arrange.display import LiveView

            view = LiveView(sys.stderr if args.json else sys.stdout)
            run.tick_hooks.append(lambda tree_root: view.update(tree_root, run.elapsed_s()))
        outcome = run.run()
        if args.live:
            view.close()
        # A simulator knows its true camera (evaluation only): a run that declares it (``TrueCameraRun``).
        truth = run.true_camera() if isinstance(run, TrueCameraRun) else None
    skipped = f"{outcome.unreachable} unreachable, {outcome.not_seen} with the board not seen"
    calibration = outcome.calibration
    if calibration is None:
        # The arm has moved: not a usage error (2) but work that fell short, like a part not within (1).
        print(f"bt-arrange: error: calibration failed: {outcome.reason} ({outcome.poses} poses: {skipped})",
              file=sys.stderr)  # fmt: skip
        return EXIT_NOT_WITHIN
    fault: RecordError | None = None
    try:
        write_calibration(calibration, out)
    except RecordError as error:
        # The calibration finished, its file did not: what was found is printed all the same, then the one line.
        fault = error
    k, pose = calibration.intrinsics, calibration.camera_to_base
    result: dict[str, Any] = {
        "out": str(out),
        "views": calibration.views,
        "poses": outcome.poses,
        "unreachable": outcome.unreachable,
        "not_seen": outcome.not_seen,
        "reprojection_error_px": round(calibration.reprojection_error_px, 4),
        "hand_eye_residual_mm": round(calibration.hand_eye_residual_mm or 0.0, 4),
        "fx_px": round(k.fx_px, 3),
        "fy_px": round(k.fy_px, 3),
        "cx_px": round(k.cx_px, 3),
        "cy_px": round(k.cy_px, 3),
        "distortion": [round(v, 6) for v in k.distortion],
        "camera_to_base_mm": [round(float(v) * 1000, 3) for v in pose.position_m],
        "camera_to_base_rpy_deg": [round(math.degrees(a), 4) for a in matrix_rpy(pose.rotation)],
    }
    if truth is not None:
        true_k, true_pose = truth
        relative = true_pose.inverse() @ pose
        angle = math.acos(max(-1.0, min(1.0, (float(relative.rotation.trace()) - 1.0) / 2.0)))
        result["truth"] = {
            "position_error_mm": round(float(np.linalg.norm(relative.position_m)) * 1000, 4),
            "rotation_error_mrad": round(angle * 1000, 4),
            "fx_error_px": round(k.fx_px - true_k.fx_px, 4),
            "fy_error_px": round(k.fy_px - true_k.fy_px, 4),
            "cx_error_px": round(k.cx_px - true_k.cx_px, 4),
            "cy_error_px": round(k.cy_px - true_k.cy_px, 4),
        }
    if args.json:
        print(json.dumps(result))
        if fault is not None:
            raise fault
        return EXIT_OK
    print(f"{calibration.views} views of {outcome.poses} poses ({skipped})")
    print(f"intrinsics: fx {k.fx_px:.2f}, fy {k.fy_px:.2f}, cx {k.cx_px:.2f}, cy {k.cy_px:.2f} px; "
          f"distortion {', '.join(f'{v:.5f}' for v in k.distortion)}")  # fmt: skip
    x, y, z = result["camera_to_base_mm"]
    roll, pitch, yaw = result["camera_to_base_rpy_deg"]
    print(f"camera to base: ({x:.2f}, {y:.2f}, {z:.2f}) mm, roll {roll:.3f}, pitch {pitch:.3f}, yaw {yaw:.3f} deg")
    print(
        f"reprojection error {calibration.reprojection_error_px:.3f} px; "
        f"hand-eye residual {calibration.hand_eye_residual_mm or 0.0:.3f} mm"
    )
    if truth is not None:
        t = result["truth"]
        print(
            f"against the simulator's true camera (evaluation only): {t['position_error_mm']:.3f} mm, "
            f"{t['rotation_error_mrad']:.3f} mrad; fx {t['fx_error_px']:+.2f}, fy {t['fy_error_px']:+.2f}, "
            f"cx {t['cx_error_px']:+.2f}, cy {t['cy_error_px']:+.2f} px"
        )
    if fault is not None:
        print(f"{out} was not written (the line on stderr says why)")
        raise fault
    print(f"wrote {out}")
    return EXIT_OK


def _speed_option(backend: Any, speed_fraction: float | None) -> dict[str, Any]:
    """``speed_fraction`` for ``open_calibration`` when given; refused by a backend without the capability."""
    if speed_fraction is None:
        return {}
    require(backend, backends.SafetyBackend, "calibrate at a speed fraction (--speed-fraction)")
    return {"speed_fraction": speed_fraction}
