"""The MuJoCo backend: the same trees, behaviours and perception in a second engine, headless.

Skipped only where the engine cannot run: no ``mujoco`` package, or no OSMesa for headless
rendering (``scripts/setup-system.sh`` installs Debian's ``libosmesa6``).
"""

from __future__ import annotations

import ctypes.util
import importlib.util
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import bt_arrange_sim.mujoco  # noqa: F401 - chooses OSMesa before mujoco is imported

if importlib.util.find_spec("mujoco") is None:
    pytest.skip("the MuJoCo backend needs the mujoco package: pip install -e '.[mujoco]'", allow_module_level=True)
if os.environ.get("MUJOCO_GL") == "osmesa" and ctypes.util.find_library("OSMesa") is None:
    pytest.skip("MuJoCo renders headless through OSMesa: apt-get install libosmesa6", allow_module_level=True)

from bt_arrange import cli  # noqa: E402
from bt_arrange.geometry import Pose  # noqa: E402
from bt_arrange.objects import CUBE, ObjectStart  # noqa: E402
from bt_arrange.perception import PartDetector  # noqa: E402
from bt_arrange.robot import PixelWindow  # noqa: E402
from bt_arrange.trees import Target, arrangement  # noqa: E402
from bt_arrange_sim.mujoco.cell import MujocoCell  # noqa: E402
from bt_arrange_sim.mujoco.runs import MujocoRun  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TREES = ROOT / "trees"


def test_the_single_cube_tree_ends_within_a_millimetre_by_ground_truth(capsys) -> None:
    code = cli.main(["run", str(TREES / "single_cube.py"), "--backend", "mujoco", "--seed", "0", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == cli.EXIT_OK, report
    (red,) = report["objects"]
    assert report["tree_status"] == "SUCCESS"
    assert red["status"] == "within"
    assert red["final_offset_truth_mm"] < 1.0 and abs(red["final_yaw_error_truth_deg"]) < 1.0
    # The camera and the engine's ground truth agree (the same pinhole rendered and measured).
    assert abs(red["final_offset_mm"] - red["final_offset_truth_mm"]) < 0.2
    assert report["sim_seconds"] < 60.0


def test_one_pick_with_an_injected_translation_error_is_pushed_back_within_a_millimetre() -> None:
    from bt_arrange_sim.injection import attach_all, make_injector

    target = Target("red", 0.52, 0.06, 0.2)
    start = ObjectStart("red", 0.42, -0.18, 0.3)
    with MujocoRun(arrangement([target], threshold_mm=1.0, max_pushes=10), [start]) as run:
        injector = make_injector("pick_translation")
        attach_all(run, "red", [injector], 7)
        report = run.run()
    (red,) = report.objects
    record = injector.record()
    assert record["fired"], record
    assert math.hypot(record["dx_mm"], record["dy_mm"]) > 1.0
    assert red.placed_offset_truth_mm is not None and red.placed_offset_truth_mm > 1.0  # the grasp was off
    assert red.pushes >= 1
    assert red.status == "within" and red.final_offset_truth_mm is not None and red.final_offset_truth_mm < 1.0


def test_the_camera_is_the_pybullet_cells_pinhole_and_its_windows_are_crops() -> None:
    with MujocoCell() as cell:
        cell.add_object(CUBE, "blue", 0.47, -0.09, 0.35)
        cell.settle(0.2)
        camera = cell.camera
        assert camera is not None
        from bt_arrange_sim.config import CameraConfig

        config = CameraConfig()
        assert camera.intrinsics.fy_px == pytest.approx(config.calibrated_intrinsics().fy_px)
        assert np.allclose(camera.pose_world.matrix, config.pose_world().matrix)
        full = camera.capture(with_depth=True)
        assert full.rgb.shape == (1080, 1920, 3) and full.depth_m is not None
        # Depth on the table, straight below the camera: its height.
        assert full.depth_m[540, 960] == pytest.approx(0.70, abs=1e-3)
        found = PartDetector().detect(full, "blue")
        truth = cell.part_pose_truth("blue")
        assert found.pose_world is not None
        assert math.hypot(found.pose_world.x_m - truth.x_m, found.pose_world.y_m - truth.y_m) < 2e-4
        window = PixelWindow(600, 500, 320, 240)
        part = camera.capture(window=window)
        crop = full.rgb[500:740, 600:920].astype(int)
        assert np.mean(np.abs(part.rgb.astype(int) - crop)) < 0.05  # the same pixels, a few edge samples aside
        binned = camera.capture(window=PixelWindow(0, 0, 1920, 1080, 4))
        found_binned = PartDetector().detect(binned, "blue")
        assert found_binned.pose_world is not None
        assert math.hypot(found_binned.pose_world.x_m - truth.x_m, found_binned.pose_world.y_m - truth.y_m) < 1e-3


def test_a_closed_gripper_holds_a_cube_by_friction_with_its_fingers_coupled() -> None:
    with MujocoCell() as cell:
        cell.add_object(CUBE, "red", 0.25, 0.0, 0.0)
        model, data = cell.model, cell.data
        # Put the open pads around the cube (set-up, not a task), close with 40 N, lift 10 cm.
        q_home = cell.arm.joint_positions()
        tcp = cell.arm.tcp_pose()
        assert tcp.x_m == pytest.approx(0.25, abs=1e-3)
        from bt_arrange.motion import ArmKinematics

        kinematics = ArmKinematics()
        down = Pose(np.array([0.25, 0.0, 0.025]), tcp.quaternion_xyzw)
        q_grasp = kinematics.inverse(down, q_home)
        cell.arm.reset(q_grasp)
        cell.settle(0.2)
        cell.gripper.close(40.0)
        cell.settle(1.0)
        assert cell.gripper.width() == pytest.approx(0.05, abs=1e-3)
        left, right = (cell.finger_opening_m(f) for f in cell.finger_joint_indices)
        assert abs(left - right) < 1e-4
        assert cell.part_in_gripper_truth("red")
        lifted = Pose(np.array([0.25, 0.0, 0.125]), tcp.quaternion_xyzw)
        q_lift = kinematics.inverse(lifted, q_grasp)
        peak = np.zeros(6)
        steps = np.linspace(0.0, 1.0, 125)
        for s in steps:
            velocity = (q_lift - q_grasp) / (len(steps) - 1) / cell.config.physics.control_period_s
            cell.arm.command(q_grasp + s * (q_lift - q_grasp), velocity)
            cell.step()
            peak = np.maximum(peak, np.abs(data.actuator_force[:6]))
        cell.arm.command(q_lift)  # at rest there: no velocity
        cell.settle(0.5)
        # The servos follow without reaching the URDF's efforts (they are not clamped: docs/mujoco.md).
        from bt_arrange_sim.mujoco.model import urdf_efforts

        efforts = urdf_efforts()
        assert np.all(peak < [efforts[name] for name in cell.ARM_JOINTS]), peak
        cube = cell.part_pose_truth("red")
        assert cube.z_m == pytest.approx(0.125, abs=1e-3)
        assert model.nu == 8 and data.ncon > 0


def test_an_experiment_on_both_engines_writes_a_folder_each_and_a_side_by_side_summary(tmp_path: Path, capsys) -> None:
    out = tmp_path / "both"
    argv = ["experiment", "--backend", "sim,mujoco", "--rows", "system", "--trials", "1", "--out", str(out)]
    code = cli.main(argv)
    printed = capsys.readouterr().out
    assert code == cli.EXIT_OK, printed
    records = {}
    for engine in ("sim", "mujoco"):
        (record,) = [json.loads(line) for line in (out / engine / "trials.jsonl").read_text().splitlines()]
        records[engine] = record
        assert record["status"] == "within" and record["pushed_truth_mm"] < 1.0
    assert records["mujoco"]["engine"] == "mujoco" and "engine" not in records["sim"]  # sim's records as before
    assert records["mujoco"]["target"] == records["sim"]["target"]  # the same trial in both engines
    (line,) = json.loads((out / "engines.json").read_text())
    assert line["row"] == "system" and set(line["engines"]) == {"sim", "mujoco"}
    table = (out / "engines.md").read_text()
    assert "| 1) System accuracy | sim | 1 |" in table and "|  | mujoco | 1 |" in table
    assert "## side by side" in printed and table.splitlines()[0] in printed


def test_a_non_convex_prism_is_its_convex_pieces_and_rests_where_it_was_put() -> None:
    from bt_arrange.objects import ObjectType
    from bt_arrange.shapes import Prism
    from bt_arrange_sim.parts import mass_of

    ell = ObjectType(
        "ell", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)
    )
    with MujocoCell() as cell:
        cell.add_object(ell, "green", 0.5, 0.1, 0.4)
        cell.settle(0.5)
        pose = cell.part_pose_truth("green")
        x, y, yaw = cell.part_planar_truth("green")
        assert math.hypot(x - 0.5, y - 0.1) < 1e-4 and yaw == pytest.approx(0.4, abs=1e-3)
        assert pose.z_m == pytest.approx(0.01, abs=1e-4)  # no mesh margin: it rests at its true height
        body = cell.parts["green"]
        assert cell.model.body_mass[body] == pytest.approx(mass_of(ell), rel=1e-6)
        pieces = [
            g for g in range(cell.model.ngeom) if cell.model.geom_bodyid[g] == body and cell.model.geom_contype[g]
        ]
        assert len(pieces) == len(ell.shape.convex_pieces()) == 2
        frame = cell.camera.capture()
        assert frame.rgb.shape == (1080, 1920, 3)


def test_a_run_in_a_fresh_process_prints_only_its_report_headless() -> None:
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    argv = [sys.executable, "-m", "bt_arrange.cli", "run", str(TREES / "single_cube.xml"), "--backend", "mujoco"]
    result = subprocess.run([*argv, "--json"], capture_output=True, text=True, timeout=300, env=env, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # no GL warning, no teardown message: OSMesa chosen before mujoco loads
    assert json.loads(result.stdout)["objects"][0]["status"] == "within"


#: A landing from a run (the tower, seed 0, bumped 2 mm: ``blue`` placed again on ``green`` after its
#: regrasp, 4 ms after the pads let it go): qpos (x, y, z, w, qx, qy, qz) and qvel of each cube.
#: Blue falls 0.8 mm tilted by 0.018 deg; one vertex of its face touches first.
TOWER_LANDING = {
    "red": (
        [0.4999983827259703, -9.918623775820808e-07, 0.024991256594797173, 6.894758517042263e-06,
         -6.219242298676074e-07, -1.9891036259592457e-07, -0.9999999999760182],
        [0.0] * 6,
    ),
    "green": (
        [0.5001761724448427, 5.587209892606255e-05, 0.0749868839682935, 0.6087565227691897, 1.3706492838941746e-06,
         4.537068189114742e-07, 0.7933571049558201],
        [0.0] * 6,
    ),
    "blue": (
        [0.5002050146271679, 0.0001311537177286891, 0.1257803260802762, 0.5000042329709785, 0.000139881230026081,
         7.260573660527554e-05, 0.8660229455232417],
        [-0.00016556445750273116, -1.9954634525734113e-05, -0.019770534423822744, 0.0005633221676872613,
         -0.0004953143875813269, -0.00011700822454432718],
    ),
}  # fmt: skip


def _land(physics) -> float:
    """Replay ``TOWER_LANDING`` for 0.6 s, the arm turned away: how far (mm) the lower cubes' centres moved."""
    import mujoco

    from bt_arrange_sim.config import CellConfig
    from bt_arrange_sim.mujoco.model import PartSpec, build_spec

    parts = [PartSpec(name, CUBE, (0.5, 0.5, 0.5), Pose.from_planar(0.3, 0.1 * k, 0.0, 0.025)) for k, name in
             enumerate(TOWER_LANDING)]  # fmt: skip
    model = build_spec(CellConfig(), physics, parts).compile()
    data = mujoco.MjData(model)
    data.qpos[0] = 3.0  # the shoulder turned away from the tower
    for name, (qpos, qvel) in TOWER_LANDING.items():
        joint = model.joint(f"{name}_free")
        data.qpos[joint.qposadr[0] : joint.qposadr[0] + 7] = qpos
        data.qvel[joint.dofadr[0] : joint.dofadr[0] + 6] = qvel
    mujoco.mj_forward(model, data)
    before = {name: data.body(name).xpos.copy() for name in ("red", "green")}
    for _ in range(300):
        mujoco.mj_step(model, data)
    return max(1000 * float(np.linalg.norm(data.body(name).xpos - p)) for name, p in before.items())


def test_a_cube_landing_tilted_on_another_moves_the_ones_below_less_than_a_tenth_of_a_millimetre() -> None:
    from bt_arrange_sim.mujoco.model import MujocoPhysics

    # Two parts meet at four time steps' time constant: the landing spreads over the whole face.
    assert _land(MujocoPhysics()) < 0.05
    # At two (the pads' and the table's), the first vertex to touch takes the whole fall: green slides.
    assert _land(MujocoPhysics(part_solref_time_constant_s=0.004)) > 0.1


def test_the_pads_friction_changes_only_the_pads_pairs_not_the_pairs_between_parts() -> None:
    with MujocoCell() as cell:
        cell.add_parts([ObjectStart("red", 0.4, -0.1, 0.0), ObjectStart("green", 0.4, 0.1, 0.0)])
        model = cell.model
        fingers = set(cell._finger_body.values())
        between = [p for p in range(model.npair) if int(model.geom_bodyid[model.pair_geom1[p]]) not in fingers]
        assert len(between) == 1  # one box each
        pad = [p for p in range(model.npair) if p not in between]
        cell.set_pad_friction("red", 0.9)
        assert model.pair_friction[between[0], 0] == pytest.approx(0.25)
        red = cell.parts["red"]
        assert {
            round(float(model.pair_friction[p, 0]), 6) for p in pad if model.geom_bodyid[model.pair_geom2[p]] == red
        } == {0.45}
