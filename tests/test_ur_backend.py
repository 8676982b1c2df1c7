"""The ur backend's pieces against fakes: no robot, no controller.

The Robotiq socket client against a tiny in-test TCP server, the network camera against an in-test
HTTP server, the world's fault checks against a fake ur_rtde, and the framework's safety (workspace
box, speed fraction, a safety stop ending the run) on the testing kit's fake world.
"""

from __future__ import annotations

import http.server
import json
import math
import socket
import socketserver
import threading
import urllib.parse
from collections.abc import Iterator
from typing import Any

import cv2
import numpy as np
import py_trees
import pytest

from bt_arrange import backends, paper_cell, treefile
from bt_arrange.errors import BackendError
from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, CartesianLimits, JointLimits, MotionPlanner
from bt_arrange.motion.kinematics import gripper_down_pose
from bt_arrange.motion.safety import MotionSafety, SafetyStop, WorkspaceBox, WorkspaceStop
from bt_arrange.robot import PixelWindow
from bt_arrange.ur.backend import UrBackend
from bt_arrange.ur.camera import NetworkCamera, open_camera
from bt_arrange.ur.robotiq import (
    GripperLinkError,
    RobotiqGripper,
    RobotiqSocket,
    force_register,
    position_to_width_m,
    speed_register,
    width_to_position,
)
from bt_arrange.ur.world import DryRunWorld, UrWorld

# -- the Robotiq URCap's socket ---------------------------------------------------------------------


class FakeUrcap:
    """A tiny Robotiq URCap: SET ... answered ack, GET NAME answered NAME value; the fingers jump to POS."""

    def __init__(self) -> None:
        self.registers = {"ACT": 0, "STA": 0, "POS": 0, "OBJ": 3, "FLT": 0, "GTO": 0, "SPE": 0, "FOR": 0}
        self.lines: list[str] = []
        self.estop = False
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while True:
            try:
                connection, _ = self._server.accept()
            except OSError:
                return
            with connection, connection.makefile("rwb") as stream:
                for raw in stream:
                    line = raw.decode().strip()
                    self.lines.append(line)
                    if line == "DROP":
                        return
                    answer = self._answer(line)
                    # As the URCap does: a bare "ack" to a SET, a line to a GET.
                    stream.write((answer if answer == "ack" else answer + "\n").encode())
                    stream.flush()

    def _answer(self, line: str) -> str:
        words = line.split()
        if words[0] == "GET":
            return f"{words[1]} {'?' if self.estop else self.registers[words[1]]}"
        pairs = dict(zip(words[1::2], (int(v) for v in words[2::2]), strict=True))
        self.registers.update(pairs)
        if pairs.get("ACT") == 1:
            self.registers["STA"] = 3
        if pairs.get("GTO") == 1:
            self.registers["POS"] = self.registers["POS"]  # the fingers start moving: OBJ 0 until refreshed
            self.registers["OBJ"] = 0
        return "ack"

    def arrive(self, position: int, obj: int = 3) -> None:
        self.registers["POS"], self.registers["OBJ"] = position, obj

    def close(self) -> None:
        self._server.close()


@pytest.fixture
def urcap() -> Iterator[FakeUrcap]:
    server = FakeUrcap()
    yield server
    server.close()


def test_robotiq_registers_map_the_2f85s_ranges():
    assert width_to_position(0.085) == 0 and width_to_position(0.0) == 255
    assert position_to_width_m(0) == pytest.approx(0.085) and position_to_width_m(255) == 0.0
    assert position_to_width_m(width_to_position(0.05)) == pytest.approx(0.05, abs=0.0003)
    assert speed_register(0.02) == 0 and speed_register(0.15) == 255
    assert force_register(20.0) == 0 and force_register(235.0) == 255


def test_robotiq_gripper_activates_commands_and_reports_through_the_socket(urcap):
    gripper = RobotiqGripper(RobotiqSocket("127.0.0.1", urcap.port))
    gripper.activate()
    assert urcap.lines[:4] == ["GET STA", "SET ACT 0", "SET ACT 1", "GET STA"]
    gripper.open(0.085, 0.15)
    assert urcap.lines[-1] == f"SET POS 0 SPE 255 FOR {force_register(40.0)} GTO 1"
    gripper.close(40.0, 0.15)
    assert urcap.lines[-1] == f"SET POS 255 SPE 255 FOR {force_register(40.0)} GTO 1"
    gripper.refresh()
    assert gripper.is_moving()  # OBJ 0
    urcap.arrive(105, obj=2)  # stopped on a part: 85 * (1 - 105/255) = 50 mm
    gripper.refresh()
    assert not gripper.is_moving() and gripper.width() == pytest.approx(0.05, abs=0.0005)
    assert gripper.fault() == 0


def test_robotiq_gripper_refuses_out_of_range_commands_before_sending(urcap):
    gripper = RobotiqGripper(RobotiqSocket("127.0.0.1", urcap.port))
    sent = len(urcap.lines)
    with pytest.raises(ValueError, match="gripper width"):
        gripper.open(0.2)
    with pytest.raises(ValueError, match="grip force"):
        gripper.close(500.0)
    assert len(urcap.lines) == sent


def test_robotiq_socket_says_in_one_line_what_went_wrong(urcap):
    with pytest.raises(GripperLinkError, match="cannot reach the gripper's Robotiq URCap socket at 127.0.0.1:1"):
        RobotiqSocket("127.0.0.1", 1)
    link = RobotiqSocket("127.0.0.1", urcap.port)
    urcap.estop = True
    with pytest.raises(GripperLinkError, match="reads \\? \\(the controller is in an emergency stop\\)"):
        link.get("POS")
    urcap.estop = False
    link._socket.sendall(b"DROP\n")  # the server hangs up
    with pytest.raises(GripperLinkError, match="was closed|lost the gripper's socket"):
        link.request("GET POS")


# -- the network camera --------------------------------------------------------------------------------

INFO = {
    "width_px": 64,
    "height_px": 48,
    "fx_px": 50.0,
    "fy_px": 50.0,
    "cx_px": 31.5,
    "cy_px": 23.5,
    "distortion": [0.0, 0.0, 0.0, 0.0, 0.0],
    "depth_unit_m": 0.001,
    "model": "in-test camera",
}


class CameraHandler(http.server.BaseHTTPRequestHandler):
    """/info, /color.png and /depth.png of a 64x48 gradient, windows and binning as the contract says."""

    requests: list[str] = []

    def log_message(self, *args: Any) -> None:
        pass

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        url = urllib.parse.urlparse(self.path)
        type(self).requests.append(self.path)
        if url.path == "/info":
            self._send(json.dumps(INFO).encode(), "application/json")
            return
        query = {k: int(v[0]) for k, v in urllib.parse.parse_qs(url.query).items()}
        x, y = query.get("x", 0), query.get("y", 0)
        w, h, b = query.get("w", 64), query.get("h", 48), query.get("binning", 1)
        columns = np.arange(64, dtype=np.uint8)[None, :].repeat(48, axis=0)
        if url.path == "/color.png":
            rgb = np.dstack([columns, columns, np.full_like(columns, 200)])[y : y + h, x : x + w]
            image = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)  # a PNG holds RGB; OpenCV encodes from BGR
        elif url.path == "/depth.png":
            image = np.full((48, 64), 700, dtype=np.uint16)[y : y + h, x : x + w]
        else:
            self.send_error(404)
            return
        if b > 1:
            image = cv2.resize(image, (w // b, h // b), interpolation=cv2.INTER_AREA)
        self._send(cv2.imencode(".png", image)[1].tobytes(), "image/png")

    def _send(self, body: bytes, kind: str) -> None:
        self.send_response(200)
        self.send_header("Content-Type", kind)
        self.send_header("X-Timestamp-S", "12.5")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)


@pytest.fixture
def camera_url() -> Iterator[str]:
    server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), CameraHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()


def test_network_camera_reads_intrinsics_frames_windows_and_depth(camera_url):
    camera = open_camera(camera_url, paper_cell.camera_pose_world())
    assert isinstance(camera, NetworkCamera) and camera.model == "in-test camera"
    assert camera.intrinsics.fx_px == 50.0 and camera.intrinsics.width_px == 64
    frame = camera.capture()
    assert frame.rgb.shape == (48, 64, 3) and frame.rgb[0, 10].tolist() == [10, 10, 200]  # RGB, not BGR
    assert camera.last_timestamp_s == 12.5 and frame.depth_m is None
    window = PixelWindow(16, 8, 32, 16, binning=2)
    CameraHandler.requests.clear()
    windowed = camera.capture(with_depth=True, window=window)
    assert CameraHandler.requests[0] == "/color.png?x=16&y=8&w=32&h=16&binning=2"  # read out by the camera
    assert windowed.rgb.shape == (8, 16, 3) and windowed.intrinsics == camera.intrinsics.windowed(window)
    assert windowed.depth_m is not None and float(windowed.depth_m[0, 0]) == pytest.approx(0.7)


def test_a_camera_lost_mid_run_is_a_safety_stop_with_the_arm_braked():
    server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), CameraHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    camera = open_camera(f"http://127.0.0.1:{server.server_address[1]}/", paper_cell.camera_pose_world())
    server.shutdown()
    server.server_close()
    with pytest.raises(SafetyStop, match="cannot reach the camera at http://127.0.0.1:") as stopped:
        camera.capture()
    assert not stopped.value.arm_stopped


def test_camera_errors_are_one_line():
    with pytest.raises(BackendError, match="cannot reach the camera at http://127.0.0.1:1/"):
        open_camera("http://127.0.0.1:1/", paper_cell.camera_pose_world())
    with pytest.raises(BackendError, match="OpenCV cannot open the camera"):
        open_camera("/nonexistent/video9", paper_cell.camera_pose_world())


# -- the workspace box and the speed fraction -------------------------------------------------------


def _planner(safety: MotionSafety) -> MotionPlanner:
    return MotionPlanner(ArmKinematics(), JointLimits(), CartesianLimits(), 0.008, safety=safety)


def test_speed_fraction_time_scales_every_motion():
    home = DEFAULT_HOME_Q
    target = gripper_down_pose(0.5, 0.1, 0.1, 0.0)
    full, half = _planner(MotionSafety()), _planner(MotionSafety(speed_fraction=0.5))
    for plan in (
        lambda p: p.move_to_pose(home, target),
        lambda p: p.move_line(home, gripper_down_pose(0.25, 0, 0.3, -math.pi / 2)),
    ):
        fast, slow = plan(full), plan(half)
        # The same path at half the velocity, a quarter of the acceleration, an eighth of the jerk: twice as long.
        assert slow.duration_s == pytest.approx(2 * fast.duration_s, rel=0.03)
    limits = MotionSafety(speed_fraction=0.5).joint_limits(JointLimits())
    assert limits.velocity_rad_s[0] == pytest.approx(1.0) and limits.jerk_rad_s3[0] == pytest.approx(12.5)
    with pytest.raises(ValueError, match="speed fraction 1.5 must lie in"):
        MotionSafety(speed_fraction=1.5)


def test_every_motion_is_checked_against_the_workspace_box_before_it_starts():
    box = WorkspaceBox(x_m=(0.1, 0.9), y_m=(-0.5, 0.5), z_m=(0.05, 0.65))
    planner = _planner(MotionSafety(workspace=box))
    planner.move_to_pose(DEFAULT_HOME_Q, gripper_down_pose(0.5, 0.1, 0.1, 0.0))  # inside: planned
    with pytest.raises(WorkspaceStop) as stopped:
        planner.move_line(DEFAULT_HOME_Q, gripper_down_pose(0.25, 0.0, 0.03, -math.pi / 2))
    message = stopped.value.reason
    assert message.startswith("the line to TCP (0.250, 0.000, 0.030) m would take the TCP to")
    assert "outside the workspace box (x 0.100..0.900, y -0.500..0.500, z 0.050..0.650 m)" in message
    assert "\n" not in message and not stopped.value.arm_stopped
    with pytest.raises(WorkspaceStop, match="the joint move to TCP \\(0.500, -0.600, 0.100\\) m"):
        planner.move_to_pose(DEFAULT_HOME_Q, gripper_down_pose(0.5, -0.6, 0.1, 0.0))


# -- a safety stop ends the run --------------------------------------------------------------------


class StopAfter(py_trees.behaviour.Behaviour):
    """Runs forever; the world raises a safety stop after a few steps."""

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.RUNNING


def test_a_safety_stop_from_the_world_ends_the_tree_with_a_failure_and_one_line():
    from bt_arrange.runner import Runner
    from bt_arrange.testing import make_context

    context = make_context()
    steps: list[int] = []

    def step() -> None:
        steps.append(1)
        if len(steps) == 5:
            raise SafetyStop("the robot is in a protective stop (a collision or a safety limit)")

    result = Runner(StopAfter("forever"), context, step).run()
    assert result.status == py_trees.common.Status.FAILURE
    assert result.safety_stop == "the robot is in a protective stop (a collision or a safety limit)"
    assert len(steps) == 5  # not stepped after the stop


# -- the world's fault checks against a fake ur_rtde ---------------------------------------------------


class FakeRtde:
    """RTDEReceiveInterface and RTDEControlInterface in one: what the world reads and sends."""

    def __init__(self) -> None:
        self.q = list(DEFAULT_HOME_Q)
        self.protective = self.emergency = False
        self.connected = self.running = True
        self.servo: list[list[float]] = []
        self.calls: list[str] = []
        self.time_s = 100.0

    def isConnected(self) -> bool:  # noqa: N802 - ur_rtde's names
        return self.connected

    def isProtectiveStopped(self) -> bool:  # noqa: N802
        return self.protective

    def isEmergencyStopped(self) -> bool:  # noqa: N802
        return self.emergency

    def isProgramRunning(self) -> bool:  # noqa: N802
        return self.running

    def getActualQ(self) -> list[float]:  # noqa: N802
        return self.q

    def getActualQd(self) -> list[float]:  # noqa: N802
        return [0.0] * 6

    def getTimestamp(self) -> float:  # noqa: N802
        self.time_s += 0.008
        return self.time_s

    def initPeriod(self) -> float:  # noqa: N802
        return 0.0

    def waitPeriod(self, start: float) -> None:  # noqa: N802
        pass

    def servoJ(self, q: list[float], *args: float) -> bool:  # noqa: N802
        self.servo.append(q)
        return True

    def servoStop(self, *args: float) -> bool:  # noqa: N802
        self.calls.append("servoStop")
        return True

    def stopScript(self) -> None:  # noqa: N802
        self.calls.append("stopScript")

    def disconnect(self) -> None:
        self.calls.append("disconnect")


class FakeGripper:
    def refresh(self) -> None:
        pass

    def fault(self) -> int:
        return 0

    def close_link(self) -> None:
        pass


@pytest.mark.parametrize(
    ("fault", "reason"),
    [
        ("protective", "the robot is in a protective stop"),
        ("emergency", "the robot is in an emergency stop"),
        ("running", "the robot's control program stopped"),
        ("connected", "lost the RTDE connection to the robot at cell"),
    ],
)
def test_the_world_ends_the_tree_on_each_stop_and_sends_nothing_afterwards(fault, reason):
    rtde = FakeRtde()
    world = UrWorld("cell", rtde, rtde, FakeGripper(), camera=None)
    world.arm.command(np.asarray(DEFAULT_HOME_Q))
    world.step()
    setattr(rtde, fault, fault in ("protective", "emergency"))
    with pytest.raises(SafetyStop, match=reason):
        world.step()
    assert "servoStop" in rtde.calls
    sent = len(rtde.servo)
    with pytest.raises(SafetyStop):
        world.arm.command(np.asarray(DEFAULT_HOME_Q))
    with pytest.raises(SafetyStop):
        world.step()
    assert len(rtde.servo) == sent
    world.close()
    assert rtde.calls[-2:] == ["disconnect", "disconnect"]  # (stopScript only to a program still running)


def test_a_robot_already_stopped_is_a_setup_error_before_the_tree_starts():
    rtde = FakeRtde()
    rtde.protective = True
    with pytest.raises(BackendError, match="the robot at cell cannot be commanded: the robot is in a protective stop"):
        UrWorld("cell", rtde, rtde, FakeGripper(), camera=None)


def test_the_dry_run_world_never_commands_the_robot():
    rtde = FakeRtde()
    world = DryRunWorld("cell", rtde, camera=None, start_width_m=0.085, held_width_m=0.05)
    assert np.allclose(world.robot.arm.joint_positions(), DEFAULT_HOME_Q)
    world.robot.arm.command(np.zeros(6))
    world.robot.gripper.close(40.0, 0.15)
    for _ in range(40):
        world.step()
    assert world.robot.gripper.width() == pytest.approx(0.05) and not world.robot.gripper.is_moving()
    assert rtde.servo == [] and np.allclose(world.robot.arm.joint_positions(), 0.0)


# -- the backend -----------------------------------------------------------------------------------


def test_the_ur_backend_declares_what_it_can_do_and_needs_no_scene(tmp_path):
    backend = UrBackend()
    assert isinstance(backend, backends.Backend)
    assert isinstance(backend, backends.ConnectingBackend) and isinstance(backend, backends.DryRunBackend)
    assert isinstance(backend, backends.CalibratingBackend) and isinstance(backend, backends.SafetyBackend)
    assert not isinstance(backend, backends.ScatteringBackend) and not isinstance(backend, backends.InjectingBackend)
    tree = tmp_path / "only_root.py"
    tree.write_text("import py_trees\n\ndef create_root():\n    return py_trees.behaviours.Success('done')\n")
    module = treefile.load(tree)
    assert treefile.scene(module, 0, backend=backend) == []
    with pytest.raises(BackendError, match="backend 'ur' needs --robot HOST"):
        backend.open_run(treefile.build_root(module))
    with pytest.raises(BackendError, match="cannot inject errors"):
        backends.check_inject(backend, "translation")
    with pytest.raises(BackendError, match="backend 'sim' cannot reach a real cell"):
        backends.require(backends.load("sim"), backends.ConnectingBackend, "reach a real cell")


def test_cli_refuses_robot_options_on_the_simulator_and_an_unreachable_robot_in_one_line(capsys, tmp_path):
    from bt_arrange.cli import main

    assert main(["run", "trees/four_cubes.py", "--robot", "127.0.0.1"]) == 2
    assert "backend 'sim' cannot reach a real cell (--robot, --camera)" in capsys.readouterr().err
    assert main(["run", "trees/four_cubes.py", "--backend", "ur", "--dry-run"]) == 2
    assert "backend 'ur' needs --robot HOST" in capsys.readouterr().err
    assert main(["info", "--backend", "ur", "--robot", "127.0.0.9", "--camera", "http://127.0.0.1:1/"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot reach the robot's controller at 127.0.0.9" in err
