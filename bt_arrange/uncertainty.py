"""What the camera's own error is: the margin a part's measured offset must leave under the threshold.

A part counts as within only when its measured offset plus this margin is under the threshold
(``RepeatUntilWithin``, the report's status), so a part the camera measures just under the
threshold is pushed once more instead of being accepted where it may lie just over it.
The margin is what the camera's detections were measured to miss by, about 95 % of the time:

- **A calibrated camera** (``--calibration camera.toml``): twice the calibration's own RMS
  reprojection error, at the table's scale (the camera's height over the table over its focal
  length). In the real-cell model: 0.153 px RMS at 0.51 mm per pixel gives 0.16 mm, where the
  cube detections through that calibration were measured 0.119 mm off on average and 0.189 mm at
  most (docs/calibration.md).
- **The ideal simulated cell's camera**: ``IDEAL_CELL_CAMERA_MM``, the 95th percentile of the
  perception benchmarks in the cell (cubes 0.031 mm, the five outlines 0.037 mm: docs/perception.md).
- **Any other camera**: no margin (0 mm), reported as unknown.

The session writes it to the blackboard at ``CAMERA_MARGIN_KEY`` before the first tick.
"""

from __future__ import annotations

from typing import Any

#: Where the session puts the margin (mm) for the decorators that judge "within".
CAMERA_MARGIN_KEY = "/camera/margin_mm"
#: The ideal pybullet and MuJoCo cells' camera: the perception benchmarks' 95th percentile (mm),
#: ``python benchmarks/perception.py --poses 100 --seed 0`` (0.031) and
#: ``python benchmarks/outlines.py --poses 100 --seed 0 --cell`` (0.037), rounded up.
IDEAL_CELL_CAMERA_MM = 0.04
#: A normal error's about-95 % bound in RMS multiples.
RMS_TO_BOUND = 2.0


def calibration_margin_mm(calibration: Any) -> float:
    """The margin of a calibrated camera (mm): ``RMS_TO_BOUND`` x its RMS reprojection error at the table's scale."""
    height_m = abs(float(calibration.camera_to_base.z_m))
    mm_per_px = height_m * 1000 / float(calibration.intrinsics.fx_px)
    return RMS_TO_BOUND * float(calibration.reprojection_error_px) * mm_per_px


def camera_margin_mm(calibration: Any, world: Any) -> tuple[float, str]:
    """The run's margin (mm) and where it comes from, in words for the report."""
    if calibration is not None:
        margin = calibration_margin_mm(calibration)
        return margin, (
            f"{margin:.3f} mm: {RMS_TO_BOUND:g} x the calibration's {calibration.reprojection_error_px:.3f} px RMS"
        )
    measured = getattr(world, "camera_margin_mm", None)
    if measured is not None:
        return float(measured), f"{float(measured):.3f} mm: the ideal cell's camera, by the perception benchmarks"
    return 0.0, "unknown (0 mm): an uncalibrated camera of no measured error"
