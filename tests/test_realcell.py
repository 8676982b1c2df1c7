"""The real cell's error model without a world: presets, the TOML file, the perturbed URDF."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from bt_arrange.errors import PlanError
from bt_arrange.motion import ArmKinematics, default_urdf_path
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES
from bt_arrange_sim import perturbed_robot, realcell
from bt_arrange_sim.config import CellConfig


def test_the_ideal_cell_is_todays_cell_with_every_term_off() -> None:
    assert CellConfig.ideal() == CellConfig()
    assert not CellConfig().errors.enabled
    assert perturbed_robot.write_perturbed_urdf(realcell.ideal()) is None


def test_the_real_cell_turns_every_term_on_and_each_can_be_switched_off() -> None:
    errors = realcell.real()
    for term in ("kinematics", "joints", "camera", "imaging", "gripper", "objects", "friction"):
        assert getattr(errors, term).enabled, term
    off = dataclasses.replace(errors, camera=dataclasses.replace(errors.camera, enabled=False))
    assert off.camera_draw()["dcx"] == 0.0 and errors.camera_draw()["dcx"] != 0.0


def test_fixed_draws_follow_the_cell_seed_and_per_run_draws_the_run_seed() -> None:
    a, b = realcell.real(0), realcell.real(1)
    assert a.camera_draw() == realcell.real(0).camera_draw()
    assert a.camera_draw() != b.camera_draw()
    assert a.with_run_seed(5).camera_draw() == a.camera_draw(), "the camera is the cell's, not the run's"
    assert a.with_run_seed(5).cube_edge_error_m() != a.with_run_seed(6).cube_edge_error_m()


def test_the_perturbed_urdf_moves_the_tcp_millimetres_and_the_hand_eye_fit_absorbs_the_mean() -> None:
    errors = realcell.real()
    path = perturbed_robot.write_perturbed_urdf(errors)
    assert path is not None and path.exists()
    q = np.array([0.2, -1.6, 1.7, -1.7, -1.57, 0.2])
    raw_mm = np.linalg.norm(ArmKinematics(path).forward(q).position_m - ArmKinematics().forward(q).position_m) * 1000
    assert 0.2 < raw_mm < 10.0
    raw = perturbed_robot.tcp_error_over_workspace_mm(
        dataclasses.replace(errors, kinematics=dataclasses.replace(errors.kinematics, hand_eye_absorbs_mean=False))
    )
    fitted = perturbed_robot.tcp_error_over_workspace_mm(errors)
    assert np.linalg.norm(fitted, axis=1).mean() < np.linalg.norm(raw, axis=1).mean()
    assert np.ptp(fitted[:, 0]) > 0.05, "what remains varies over the workspace"


def test_a_zero_perturbation_leaves_the_urdf_kinematics_alone() -> None:
    text = perturbed_robot.perturbed_urdf_text(
        default_urdf_path().read_text(), ARM_JOINT_NAMES, FINGER_JOINT_NAMES, np.zeros(6), np.zeros(6), 0.0
    )
    path = Path(__file__).parent / "_zero.urdf"
    try:
        path.write_text(text)
        q = np.array([0.3, -1.2, 1.1, -1.4, -1.5, 0.7])
        assert np.allclose(ArmKinematics(path).forward(q).matrix, ArmKinematics().forward(q).matrix, atol=1e-9)
    finally:
        path.unlink(missing_ok=True)


def test_the_users_toml_starts_from_a_preset_and_changes_only_what_it_names(tmp_path: Path) -> None:
    mine = tmp_path / "mine.toml"
    mine.write_text('preset = "real"\ncell_seed = 4\n[friction]\nenabled = false\n[camera]\nrotation_sigma_deg = 2\n')
    errors = realcell.load_toml(mine)
    assert errors.cell_seed == 4
    assert not errors.friction.enabled
    assert errors.camera.rotation_sigma_deg == 2.0
    assert errors.gripper == realcell.real().gripper
    assert CellConfig.from_toml(mine).errors == errors
    assert CellConfig.named(str(mine)).errors == errors


@pytest.mark.parametrize(
    ("data", "fragment"),
    [
        ({"colour": 1}, "unknown key 'colour'"),
        ({"camera": {"fov": 1}}, "unknown key camera.fov"),
        ({"camera": 3}, "[camera] must be a table"),
        ({"joints": {"joint_sigma_mrad": "a lot"}}, "must be a finite number"),
        ({"joints": {"joint_sigma_mrad": -1}}, "must not be negative"),
        ({"gripper": {"coupling_erp": 0}}, "coupling_erp must lie in (0, 1]"),
        ({"cell_seed": -1}, "cell_seed = -1 must be a whole number"),
        ({"preset": "lab"}, "preset 'lab' is not one of"),
    ],
)
def test_a_bad_mapping_names_the_key(data: dict, fragment: str) -> None:
    with pytest.raises(PlanError) as error:
        realcell.from_mapping(data)
    assert fragment in str(error.value)
    assert "\n" not in str(error.value)


def test_the_friction_field_is_smooth_and_within_its_spread() -> None:
    errors = realcell.real()
    values = [errors.friction_scale(x, y) for x in np.linspace(0.3, 0.7, 9) for y in np.linspace(-0.3, 0.3, 9)]
    spread = errors.friction.spread
    assert min(values) >= 1 - spread - 1e-9 and max(values) <= 1 + spread + 1e-9
    assert max(values) - min(values) > 0.05
    assert realcell.ideal().friction_scale(0.5, 0.0) == 1.0


def test_grasp_offsets_are_drawn_per_run_and_only_when_the_term_is_on() -> None:
    real = realcell.real()
    assert real.gripper.grasp_offset_sigma_mm > 0 and real.gripper.coupling_erp == 0.8, "stiff: no cube is lost"
    first, again, other = (realcell.real().with_run_seed(s).grasp_offset_rng() for s in (4, 4, 5))
    assert first is not None and again is not None and other is not None
    assert first.normal() == again.normal() != other.normal()
    assert realcell.ideal().grasp_offset_rng() is None
    off = dataclasses.replace(real, gripper=dataclasses.replace(real.gripper, grasp_offset_sigma_mm=0.0))
    assert off.grasp_offset_rng() is None
