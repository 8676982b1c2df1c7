"""The real cell in a world: its camera and arm are off the nominal calibration, the ideal cell's are not."""

from __future__ import annotations

import numpy as np

from bt_arrange.motion import ArmKinematics
from bt_arrange.perception import CubeDetector
from bt_arrange_sim.cell import HOME_Q, CellConfig, WorkCell


def _camera_error_mm(config: CellConfig) -> float:
    with WorkCell(config) as cell:
        cell.add_cube("red", 0.58, 0.18, yaw_rad=0.2)
        cell.settle(0.2)
        detection = CubeDetector().detect(cell.camera.capture(), "red")
        assert detection.found and detection.pose_world is not None
        x, y, _ = cell.cube_planar_truth("red")
        return float(np.hypot(detection.pose_world.x_m - x, detection.pose_world.y_m - y) * 1000)


def test_the_real_cameras_calibration_error_shows_in_its_measurements_the_ideal_ones_does_not() -> None:
    ideal, real = _camera_error_mm(CellConfig.ideal()), _camera_error_mm(CellConfig.real())
    assert ideal < 0.2
    assert 0.1 < real < 2.0, "the real camera's systematic error: a fraction of a millimetre"
    assert real > ideal


def test_the_real_arm_stands_off_where_the_nominal_model_puts_it() -> None:
    nominal = ArmKinematics().forward(HOME_Q).position_m
    for config, low_mm, high_mm in ((CellConfig.ideal(), 0.0, 0.01), (CellConfig.real(), 0.05, 5.0)):
        with WorkCell(config) as cell:
            error_mm = float(np.linalg.norm(cell.arm.tcp_pose().position_m - nominal) * 1000)
        assert low_mm <= error_mm <= high_mm, (config.errors.enabled, error_mm)
