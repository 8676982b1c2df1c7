"""The calibration file: written and read back, and every bad field refused with one line naming it."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from bt_arrange.calibration import CameraCalibration, read_calibration, rpy_matrix, write_calibration
from bt_arrange.calibration.file import matrix_rpy
from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose
from bt_arrange.robot import CameraIntrinsics


def _calibration() -> CameraCalibration:
    rotation = rpy_matrix(math.radians(179.2), math.radians(-0.8), math.radians(-92.5))
    return CameraCalibration(
        intrinsics=CameraIntrinsics(1920, 1080, 1385.25, 1383.5, 963.75, 535.25, (-0.12, 0.06, 8e-4, -5e-4, 0.0)),
        camera_to_base=Pose.from_rotation([0.5123, -0.0087, 0.7151], rotation),
        reprojection_error_px=0.1234,
        views=20,
        cell="real",
        date="2026-12-01T10:00:00+00:00",
        skipped_views=2,
        hand_eye_residual_mm=0.21,
    )


def test_the_file_holds_the_contracts_keys_in_millimetres_and_degrees(tmp_path: Path) -> None:
    path = write_calibration(_calibration(), tmp_path / "camera.toml")
    text = path.read_text()
    for key in ("width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px", "distortion", "reprojection_error_px",
                "views", "date", "cell"):  # fmt: skip
        assert re.search(rf"^{key} = ", text, re.M), key
    assert "[camera_to_base]" in text
    for key in ("x_mm", "y_mm", "z_mm", "roll_deg", "pitch_deg", "yaw_deg"):
        assert re.search(rf"^{key} = ", text, re.M), key
    assert "x_mm = 512.3000" in text and "yaw_deg = -92.500000" in text


def test_a_written_calibration_reads_back_the_same(tmp_path: Path) -> None:
    original = _calibration()
    back = read_calibration(write_calibration(original, tmp_path / "camera.toml"))
    k, j = original.intrinsics, back.intrinsics
    assert (j.width_px, j.height_px) == (k.width_px, k.height_px)
    assert np.allclose([j.fx_px, j.fy_px, j.cx_px, j.cy_px], [k.fx_px, k.fy_px, k.cx_px, k.cy_px], atol=1e-6)
    assert np.allclose(j.distortion, k.distortion)
    assert np.allclose(back.camera_to_base.matrix, original.camera_to_base.matrix, atol=1e-7)
    assert (back.views, back.cell, back.date, back.skipped_views) == (20, "real", original.date, 2)
    assert back.reprojection_error_px == pytest.approx(0.1234)


def test_roll_pitch_yaw_round_trip() -> None:
    for angles in ((0.1, -0.2, 0.3), (math.pi - 0.01, 0.02, -1.6), (-2.0, 1.2, 3.0)):
        assert np.allclose(matrix_rpy(rpy_matrix(*angles)), angles)


def _text(tmp_path: Path) -> str:
    return write_calibration(_calibration(), tmp_path / "good.toml").read_text()


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("width_px = 1920", "width_px = 0", "width_px"),
        ("width_px = 1920", "width_px = 19.5", "width_px"),
        ("height_px = 1080", 'height_px = "1080"', "height_px"),
        ("fx_px = 1385.250000", "fx_px = -3", "fx_px"),
        ("fy_px = 1383.500000", "fy_px = nan", "fy_px"),
        ("cx_px = 963.750000", "cx_px = 2500", "cx_px"),
        ("cy_px = 535.250000", "cy_px = -20", "cy_px"),
        ("distortion = [", "distortion = [1, ", "distortion"),
        ("distortion = [-0.12", 'distortion = ["a"', "distortion[0]"),
        ("reprojection_error_px = 0.1234", "reprojection_error_px = -1", "reprojection_error_px"),
        ("views = 20", "views = 0", "views"),
        ("views = 20", "views = true", "views"),
        ('cell = "real"', "cell = 3", "cell"),
        ("x_mm = 512.3000", 'x_mm = "far"', "camera_to_base.x_mm"),
        ("x_mm = 512.3000", "x_mm = inf", "camera_to_base.x_mm"),
        ("x_mm = 512.3000", "", "camera_to_base.x_mm"),
        ("pitch_deg = -0.800000", "pitch_deg = 95", "camera_to_base.pitch_deg"),
        ("yaw_deg = -92.500000", "yaw_deg = -92.5\nw_deg = 1", "camera_to_base.w_deg"),
        ("views = 20", "views = 20\nlens = 3", "lens"),
        ("[camera_to_base]", "[camera]", "camera"),
        ("fx_px = 1385.250000", "", "fx_px"),
    ],
)
def test_every_bad_field_is_one_line_naming_it(tmp_path: Path, old: str, new: str, field: str) -> None:
    text = _text(tmp_path)
    assert old in text, old
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(old, new, 1))
    with pytest.raises(PlanError) as raised:
        read_calibration(bad)
    message = str(raised.value)
    assert "\n" not in message
    assert field in message, message


def test_a_missing_or_malformed_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(PlanError, match="cannot read the calibration file"):
        read_calibration(tmp_path / "none.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("fx_px = = 3\n")
    with pytest.raises(PlanError, match="is not valid TOML"):
        read_calibration(broken)
