"""The UR controller backed by physics (``bt_arrange_sim.ursim``), driven by the unmodified ``ur_rtde`` client.

One controller serves the module's tests (it starts in about a second); the tests that stop it
(a protective stop, SIGTERM) come last or start their own. Each controller serves on a loopback
address of its own (127.x.y.z): the fixed UR ports of 127.0.0.1 may be a developer's controller.
"""

from __future__ import annotations

import json
import math
import random
import socket
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from bt_arrange_sim.ursim import launch

rtde_control = pytest.importorskip("rtde_control", reason="ur-rtde is not installed")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur-rtde is not installed")

REPO = Path(__file__).resolve().parents[1]
SCENE = REPO / "trees" / "single_cube.py"
SEED = 1


def loopback_host() -> str:
    """A loopback address of this test run's own (every 127.x.y.z is the loopback on Linux)."""
    return f"127.{random.randint(1, 254)}.{random.randint(1, 254)}.{random.randint(2, 254)}"


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory):
    truth = tmp_path_factory.mktemp("ursim") / "truth.json"
    with launch(SCENE, SEED, truth, host=loopback_host()) as running:
        yield running


@pytest.fixture(scope="module")
def receive(sim):
    interface = rtde_receive.RTDEReceiveInterface(sim.host)
    yield interface
    interface.disconnect()


@pytest.fixture(scope="module")
def control(sim):
    interface = rtde_control.RTDEControlInterface(sim.host)
    yield interface
    if interface.isConnected():
        interface.disconnect()


def test_movej_reaches_the_joint_vector(control, receive):
    start = np.array(receive.getActualQ())
    target = start + np.array([0.15, -0.1, 0.1, 0.0, 0.0, -0.2])
    assert control.moveJ(target.tolist(), 1.0, 2.0)
    assert np.max(np.abs(np.array(receive.getActualQ()) - target)) < 1e-3
    assert control.isProgramRunning()


def test_servoj_tracks_targets_for_a_second_in_real_time(control, receive, sim):
    start = np.array(receive.getActualQ())
    world_start_s = receive.getTimestamp()
    wall_start_s = time.monotonic()
    target = start
    for i in range(125):
        period_start = control.initPeriod()
        target = start + np.array([0.1 * math.sin(math.pi * i / 125), 0, 0, 0, 0, 0])
        assert control.servoJ(target.tolist(), 0.5, 0.5, 0.008, 0.1, 300)
        control.waitPeriod(period_start)
    control.servoStop()
    # Stamped with the controller's clock, which keeps to the wall's.
    world_s, wall_s = receive.getTimestamp() - world_start_s, time.monotonic() - wall_start_s
    assert world_s == pytest.approx(wall_s, rel=0.2)
    assert np.max(np.abs(np.array(receive.getActualQ()) - target)) < 0.02
    assert sim.stats()["realtime_ratio"] > 0.8


def test_robotiq_socket_activates_closes_on_the_cube_and_opens(control, receive, sim):
    from bt_arrange.motion import gripper_down_pose
    from bt_arrange_sim.ursim.kinematics import BASE_LINK_TO_BASE, UrKinematics, matrix_to_pose

    gripper = socket.create_connection((sim.host, 63352), timeout=5)

    def ask(line: str) -> str:
        gripper.sendall(line.encode() + b"\n")
        return gripper.recv(1024).decode()

    def get(name: str) -> int:
        word, value = ask(f"GET {name}").split()
        assert word == name
        return int(value)

    def wait_for(name: str, wanted: set[int], timeout_s: float = 5.0) -> int:
        deadline = time.monotonic() + timeout_s
        while (value := get(name)) not in wanted and time.monotonic() < deadline:
            time.sleep(0.02)
        return value

    assert ask("SET ACT 0") == "ack"
    assert wait_for("STA", {0}) == 0
    assert ask("SET ACT 1") == "ack"
    assert get("STA") in (1, 3)
    assert wait_for("STA", {3}) == 3

    # Over the cube, the closing axis along one of its faces, then down to the cube's mid-height.
    x_m, y_m, _, yaw_rad = sim.truth()["red"]
    kinematics = UrKinematics()
    assert control.setTcp(matrix_to_pose(kinematics.flange_to_pads_tcp))
    above = matrix_to_pose(BASE_LINK_TO_BASE.T @ gripper_down_pose(x_m, y_m, 0.12, yaw_rad).matrix)
    grasp = matrix_to_pose(BASE_LINK_TO_BASE.T @ gripper_down_pose(x_m, y_m, 0.028, yaw_rad).matrix)
    assert control.moveJ_IK(above, 1.0, 2.0)
    assert control.moveL(grasp, 0.2, 1.0)

    assert ask("SET POS 255 SPE 128 FOR 100 GTO 1") == "ack"
    assert get("PRE") == 255
    assert wait_for("OBJ", {1, 2, 3}) == 2  # stopped on an object while closing
    assert 90 < get("POS") < 200  # the 5 cm cube between the pads

    assert ask("SET POS 0 SPE 255 FOR 100 GTO 1") == "ack"
    assert wait_for("OBJ", {1, 2, 3}) == 3
    assert get("POS") < 5
    assert control.moveL(above, 0.2, 1.0)
    gripper.close()


def test_camera_serves_its_intrinsics_and_frames(sim):
    import cv2

    info = json.load(urllib.request.urlopen(sim.camera_spec + "info", timeout=30))
    assert set(info) >= {"width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px", "distortion", "depth_unit_m"}
    assert len(info["distortion"]) == 5 and info["depth_unit_m"] == 0.0001
    with urllib.request.urlopen(sim.camera_spec + "color.png", timeout=30) as response:
        assert float(response.headers["X-Timestamp-S"]) > 0
        image = cv2.imdecode(np.frombuffer(response.read(), np.uint8), cv2.IMREAD_UNCHANGED)
    assert image.shape == (info["height_px"], info["width_px"], 3)
    query = "depth.png?x=640&y=320&w=320&h=240&binning=2"
    with urllib.request.urlopen(sim.camera_spec + query, timeout=30) as response:
        depth = cv2.imdecode(np.frombuffer(response.read(), np.uint8), cv2.IMREAD_UNCHANGED)
    assert depth.shape == (120, 160) and depth.dtype == np.uint16
    # The table lies 0.7 m below the camera.
    assert np.median(depth) * info["depth_unit_m"] == pytest.approx(0.7, abs=0.02)
    # A window that leaves the image is the client's error, said in one line.
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(sim.camera_spec + "color.png?x=1900&w=100", timeout=30)
    assert refused.value.code == 400 and b"leaves" in refused.value.read()


def test_a_protective_stop_stops_the_program_as_the_client_sees_it(control, receive, sim):
    start = np.array(receive.getActualQ())
    assert control.moveJ((start + 0.3).tolist(), 0.3, 0.5, True)  # async: the arm is moving
    time.sleep(0.2)
    assert sim.inject("protective_stop") == "ok"
    time.sleep(0.1)
    assert receive.isProtectiveStopped()
    assert not control.isProgramRunning()
    assert not control.moveJ(start.tolist(), 1.0, 1.0)  # refused: the program is not running
    q_stopped = np.array(receive.getActualQ())
    time.sleep(0.3)
    assert np.max(np.abs(np.array(receive.getActualQ()) - q_stopped)) < 1e-3  # halted
    # Cleared (as an operator would), the client uploads its program again and moves.
    assert sim.inject("clear") == "ok"
    time.sleep(0.05)
    assert not receive.isProtectiveStopped()
    assert control.reuploadScript()
    deadline = time.monotonic() + 5
    while not control.isProgramRunning() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert control.moveJ(start.tolist(), 1.0, 1.0)


def test_sigterm_writes_the_truth_and_exits_zero_with_one_stdout_line(tmp_path):
    truth_path = tmp_path / "truth.json"
    with launch("four_cubes", 3, truth_path, host=loopback_host()) as sim:
        names = set(sim.truth())
    assert sim.returncode == 0
    assert sim.stdout_after_ready == ""  # the ready line was the only one
    truth = json.loads(truth_path.read_text())
    assert set(truth) == names and len(names) == 4
    for x_m, y_m, z_m, yaw_rad in truth.values():
        assert all(math.isfinite(v) for v in (x_m, y_m, z_m, yaw_rad))
        assert 0.0 < z_m < 0.1
