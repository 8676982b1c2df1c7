"""The controller's wire protocols as a client sees them: the dashboard's replies, RTDE's setup, the Robotiq
socket, nonsense on every port, the faults port, and the RTDE watchdog and a push's protective stop.

Raw sockets where the point is the bytes; the unmodified ``ur_rtde`` client where the point is what
it makes of them.
"""

from __future__ import annotations

import socket
import struct
import time

import numpy as np
import pytest
from test_ursim import SCENE, SEED, loopback_host

from bt_arrange_sim.ursim import launch


@pytest.fixture(scope="module")
def sim():
    with launch(SCENE, SEED, host=loopback_host()) as running:
        yield running


def rtde_package(kind: str, payload: bytes = b"") -> bytes:
    return struct.pack(">HB", 3 + len(payload), ord(kind)) + payload


def read_package(connection: socket.socket) -> tuple[str, bytes]:
    header = connection.recv(3, socket.MSG_WAITALL)
    size, kind = struct.unpack(">HB", header)
    return chr(kind), connection.recv(size - 3, socket.MSG_WAITALL) if size > 3 else b""


def test_dashboard_greets_and_answers_as_a_cb3(sim):
    with socket.create_connection((sim.host, 29999), timeout=5) as dashboard:
        stream = dashboard.makefile("rw")
        assert stream.readline() == "Connected: Universal Robots Dashboard Server\n"

        def ask(command: str) -> str:
            stream.write(command + "\n")
            stream.flush()
            return stream.readline().rstrip("\n")

        assert ask("PolyscopeVersion").startswith("URSoftware 3.15.")
        assert ask("robotmode") == "Robotmode: RUNNING"
        assert ask("safetymode") == "Safetymode: NORMAL"
        assert ask("running") == "Program running: false"
        assert ask("programState").startswith("STOPPED")
        assert ask("unlock protective stop") == "Protective stop releasing"
        assert ask("close safety popup") == "closing safety popup"
        assert ask("stop") == "Stopped"
        assert ask("is in remote control") == "could not understand: 'is in remote control'"  # e-Series only
        assert ask("\x00\x01 nonsense") == "could not understand: '\x00\x01 nonsense'"
        assert ask("quit") == "Disconnected"
        assert stream.readline() == ""  # closed


def test_rtde_setup_types_not_found_and_data_at_the_requested_rate(sim):
    with socket.create_connection((sim.host, 30004), timeout=5) as rtde:
        rtde.sendall(rtde_package("V", struct.pack(">H", 2)))
        assert read_package(rtde) == ("V", b"\x01")
        rtde.sendall(rtde_package("v"))
        kind, payload = read_package(rtde)
        assert kind == "v" and struct.unpack(">IIII", payload)[:2] == (3, 15)
        names = b"timestamp,actual_q,robot_status_bits,output_int_register_0,joint_mode,no_such_field"
        rtde.sendall(rtde_package("O", struct.pack(">d", 25.0) + names))
        kind, payload = read_package(rtde)
        assert kind == "O" and payload[0] == 0  # refused: a name is unknown
        assert payload[1:].decode().split(",") == ["DOUBLE", "VECTOR6D", "UINT32", "INT32", "VECTOR6INT32", "NOT_FOUND"]
        names = names.rsplit(b",", 1)[0]
        rtde.sendall(rtde_package("O", struct.pack(">d", 25.0) + names))
        assert read_package(rtde)[1][0] == 1
        rtde.sendall(rtde_package("I", b"input_int_register_5,input_double_register_7"))
        kind, payload = read_package(rtde)
        assert (kind, payload) == ("I", b"\x01INT32,DOUBLE")
        rtde.sendall(rtde_package("U", struct.pack(">Bid", 1, 42, 2.5)))
        rtde.sendall(rtde_package("S"))
        assert read_package(rtde) == ("S", b"\x01")
        stamps = []
        layout = struct.Struct(">Bd6dIi6i")
        for _ in range(6):
            kind, payload = read_package(rtde)
            assert kind == "U" and len(payload) == layout.size
            stamps.append(layout.unpack(payload)[1])
        steps = np.diff(stamps)
        assert np.allclose(steps, 0.04, atol=1e-9)  # 25 Hz of the controller's 125 Hz clock
        rtde.sendall(rtde_package("P"))
        while read_package(rtde)[0] != "P":
            pass
        # A second client may not write the registers the first writes.
        with socket.create_connection((sim.host, 30004), timeout=5) as other:
            other.sendall(rtde_package("I", b"input_int_register_5"))
            assert read_package(other) == ("I", b"\x00IN_USE")


def test_robotiq_values_read_question_marks_during_an_emergency_stop(sim):
    with socket.create_connection((sim.host, 63352), timeout=5) as gripper:
        gripper.sendall(b"GET STA\nGET OBJ\n")
        time.sleep(0.05)
        answer = gripper.recv(1024).decode()
        assert [line.split()[0] for line in answer.splitlines()] == ["STA", "OBJ"]  # both in one read
        gripper.sendall(b"SET POS 999\n")
        assert gripper.recv(1024) == b"?\n"
        assert sim.inject("emergency_stop") == "ok"
        gripper.sendall(b"GET POS\n")
        assert gripper.recv(1024) == b"POS ?\n"
        assert sim.inject("clear") == "ok"
        gripper.sendall(b"GET POS\n")
        assert gripper.recv(1024).split()[0] == b"POS"


def test_nonsense_on_any_port_never_ends_the_controller(sim):
    for port in (29999, 30003, 30004, 63352, sim.faults_port):
        with socket.create_connection((sim.host, port), timeout=5) as connection:
            connection.sendall(bytes(range(256)) * 8)
    with socket.create_connection((sim.host, 30004), timeout=5) as rtde:
        rtde.sendall(b"\x00\x01V")  # a size smaller than its own header
    assert sim.inject("no_such_fault").startswith("error:")
    assert sim.stats()["world_time_s"] > 0
    assert sim.inject("drop all").startswith("ok")


rtde_control = pytest.importorskip("rtde_control", reason="ur-rtde is not installed")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur-rtde is not installed")


def test_the_rtde_watchdog_stops_the_program_when_the_client_falls_silent(sim):
    control = rtde_control.RTDEControlInterface(sim.host)
    try:
        assert control.setWatchdog(20.0)
        for _ in range(10):
            control.kickWatchdog()
            time.sleep(0.02)
        assert control.isProgramRunning()
        time.sleep(0.3)  # no kick for over 1/20 s
        assert not control.isProgramRunning()
    finally:
        control.disconnect()


def test_a_line_without_a_solution_is_a_runtime_error_that_stops_the_program(sim):
    control = rtde_control.RTDEControlInterface(sim.host)
    try:
        assert control.isProgramRunning()
        assert not control.moveL([2.0, 2.0, 2.0, 0.0, 3.14, 0.0], 0.2, 1.0)  # out of reach
        assert not control.isProgramRunning()
        assert control.reuploadScript()
        deadline = time.monotonic() + 5
        while not control.isProgramRunning() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert control.isProgramRunning()
    finally:
        control.disconnect()


def test_a_push_armed_with_on_contact_is_protective_stopped_when_a_finger_touches(sim):
    from bt_arrange.motion import gripper_down_pose
    from bt_arrange_sim.ursim.kinematics import BASE_LINK_TO_BASE, UrKinematics, matrix_to_pose

    control = rtde_control.RTDEControlInterface(sim.host)
    receive = rtde_receive.RTDEReceiveInterface(sim.host)
    try:
        x_m, y_m, _, yaw_rad = sim.truth()["red"]
        along = np.array([np.cos(yaw_rad), np.sin(yaw_rad)])  # a face's normal
        assert control.setTcp(matrix_to_pose(UrKinematics().flange_to_pads_tcp))

        def pose(at: np.ndarray, z_m: float) -> list[float]:
            return matrix_to_pose(BASE_LINK_TO_BASE.T @ gripper_down_pose(at[0], at[1], z_m, yaw_rad).matrix)

        beside = np.array([x_m, y_m]) - 0.06 * along
        assert control.moveJ_IK(pose(beside, 0.12), 1.0, 2.0)
        assert control.moveL(pose(beside, 0.03), 0.2, 1.0)
        assert sim.inject("protective_stop on_contact") == "ok"
        assert not control.moveL(pose(beside + 0.05 * along, 0.03), 0.05, 0.5)  # the push is stopped
        # The receive interface's connection reads the state on its own; a period later at most.
        deadline = time.monotonic() + 0.5
        while not receive.isProtectiveStopped() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert receive.isProtectiveStopped()
        assert not control.isProgramRunning()
    finally:
        sim.inject("clear")
        control.disconnect()
        receive.disconnect()
