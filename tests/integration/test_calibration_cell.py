"""A short calibration in the cells: the ideal cell's recovers its nominal camera, the real cell's its true one."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bt_arrange import cli
from bt_arrange.calibration import read_calibration
from bt_arrange_sim.config import CameraConfig


def test_calibrate_in_the_ideal_cell_recovers_the_nominal_camera(tmp_path, capsys) -> None:
    out = tmp_path / "camera.toml"
    code = cli.main(["calibrate", "--views", "10", "--out", str(out), "--json"])
    result = json.loads(capsys.readouterr().out)
    assert code == 0 and result["views"] == 10
    calibration = read_calibration(out)
    nominal = CameraConfig()
    k, expected = calibration.intrinsics, nominal.calibrated_intrinsics()
    assert calibration.reprojection_error_px < 0.3
    assert abs(k.fx_px / expected.fx_px - 1) < 0.003 and abs(k.fy_px / expected.fy_px - 1) < 0.003
    assert abs(k.cx_px - expected.cx_px) < 3.0 and abs(k.cy_px - expected.cy_px) < 3.0
    assert np.abs(k.distortion).max() < 0.01, "the ideal camera has no lens distortion"
    pose, true_pose = calibration.camera_to_base, nominal.pose_world()
    assert np.linalg.norm(pose.position_m[:2] - true_pose.position_m[:2]) < 0.001
    # The table sheet sets the camera's height, which trades with the focal length (TinyRenderer's
    # image gives fx about 0.1 % long): what the camera sees of the table, height over fx, is right.
    scale, nominal_scale = pose.position_m[2] / k.fx_px, true_pose.position_m[2] / expected.fx_px
    assert abs(scale / nominal_scale - 1) < 5e-4
    assert abs(pose.position_m[2] - true_pose.position_m[2]) < 0.002
    relative = true_pose.rotation.T @ pose.rotation
    assert math.acos(min(1.0, (np.trace(relative) - 1) / 2)) < 0.003
    assert result["truth"]["position_error_mm"] < 2.0  # the height, as above


def test_the_real_cells_short_calibration_finds_its_lens_and_pose(real_cell_calibration) -> None:
    calibration = read_calibration(real_cell_calibration)
    assert calibration.views >= 10 and calibration.cell == "real"
    assert calibration.reprojection_error_px < 0.3
    k1, k2 = calibration.intrinsics.distortion[:2]
    assert -0.14 < k1 < -0.10 and 0.03 < k2 < 0.09, "the lens's radial distortion (k1 -0.12, k2 0.06)"
    # The transition log of the procedure, as of any run: one move and one capture per view.
    folder = real_cell_calibration.parent
    records = [json.loads(line) for line in (folder / "transitions.jsonl").read_text().splitlines()]
    kinds = [record["kind"] for record in records]
    assert "CaptureSheet" in kinds and "CaptureBoard" in kinds and "SolveCalibration" in kinds
    # The sheet was seen and the working-plane views were enough: camera to base is on the table plane.
    solved = [r for r in records if r["kind"] == "SolveCalibration" and r["new"] == "SUCCESS"]
    assert solved and "on the table plane" in solved[-1]["feedback"], solved


def test_fewer_views_than_a_calibration_needs_is_one_line_before_anything_moves(tmp_path, capsys) -> None:
    with pytest.raises(SystemExit) as raised:
        cli.main(["calibrate", "--views", "5", "--out", str(tmp_path / "c.toml")])
    assert raised.value.code == 2
    err = capsys.readouterr().err
    assert "--views" in err and "6 or more" in err and err.count("\n") == 1
