"""The ur backend end to end: the unmodified ur_rtde client against the emulated controller (``bt_arrange_sim.ursim``).

The controller runs the pybullet cell in real time behind the ports a CB3 serves (RTDE, script,
dashboard, the Robotiq URCap's socket, a network camera) and keeps the truth of where the parts
are. Each test's controller listens on its own loopback address, so tests (and other runs on the
machine) do not meet on the fixed ports. Kept few and short: a four-cube run (~15 s of world
time), one one-cube cell for the safety behaviours, one for a dropped connection, and a calibration cell.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("rtde_control")
ursim = pytest.importorskip("bt_arrange_sim.ursim")

ROOT = Path(__file__).resolve().parents[2]
FOUR_CUBES = {"red": (0.45, 0.05), "green": (0.45, -0.05), "blue": (0.55, 0.05), "yellow": (0.55, -0.05)}
#: The world time into a run at which a fault is injected: the arm is on its way to the cube.
FAULT_AT_S = 1.0
#: A tree file with only create_root (no scene: a real cell's parts lie where they lie), the target of
#: trees/single_cube.py, whose scene the controller builds.
ONLY_ROOT = """from bt_arrange.trees import Target, arrangement


def create_root(threshold_mm: float = 1.0):
    return arrangement([Target("red", x_m=0.50, y_m=0.0)], threshold_mm=threshold_mm)
"""


def _cli(*args: str, env: dict[str, str] | None = None) -> tuple[int, str, str]:
    """``bt-arrange ARGS`` in a fresh process (``ur_cli.py``): its exit status, stdout and stderr."""
    command = [sys.executable, str(Path(__file__).with_name("ur_cli.py")), *args]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300, env={**os.environ, **(env or {})})
    return done.returncode, done.stdout, done.stderr


def _run(*args: str, env: dict[str, str] | None = None) -> tuple[int, dict, str]:
    """``bt-arrange run ARGS --json``: its exit status, its report and its stderr."""
    code, out, err = _cli("run", *args, "--json", env=env)
    lines = out.strip().splitlines()
    return code, json.loads(lines[-1]) if lines else {}, err


def _our_lines(stderr: str) -> list[str]:
    """What bt-arrange said on stderr (ur_rtde's C++ prints its own diagnostics there too, e.g. on a drop)."""
    return [line for line in stderr.splitlines() if line.startswith("bt-arrange:")]


def _cube_error(truth: dict, name: str) -> tuple[float, float]:
    """Distance (mm) and yaw error (deg, folded to the cube's quarter turn) of a cube from its target."""
    x, y, _, yaw = truth[name]
    tx, ty = FOUR_CUBES[name]
    folded = math.degrees(yaw) % 90.0
    return math.hypot(x - tx, y - ty) * 1000, min(folded, 90.0 - folded)


def _moved_mm(before: dict, after: dict) -> float:
    """How far any part moved between two truths (mm); a resting cube settles by well under a micrometre."""
    return max(math.dist(before[name][:3], after[name][:3]) * 1000 for name in before)


def test_four_cubes_through_the_ur_backend_end_within_a_millimetre_by_the_controllers_truth(tmp_path):
    with ursim.launch(ROOT / "trees/four_cubes.py", seed=0, host="127.0.77.1") as cell:
        code, report, _ = _run(
            str(ROOT / "trees/four_cubes.py"),
            *("--backend", "ur", "--robot", cell.host, "--camera", cell.camera_spec, "--speed-fraction", "1.0"),
        )
        truth = cell.truth()
    assert code == 0, report
    assert report["objects_within"] == 4 and report.get("ground_truth") is False
    for name in FOUR_CUBES:
        distance_mm, yaw_deg = _cube_error(truth, name)
        assert distance_mm < 1.0 and yaw_deg < 1.0, (name, distance_mm, yaw_deg)


@pytest.fixture(scope="module")
def one_cube_cell():
    with ursim.launch(ROOT / "trees/single_cube.py", seed=0, host="127.0.77.2") as cell:
        yield cell


@pytest.fixture
def only_root(tmp_path: Path) -> Path:
    path = tmp_path / "only_root.py"
    path.write_text(ONLY_ROOT)
    return path


def _cell_args(cell) -> tuple[str, ...]:
    return ("--backend", "ur", "--robot", cell.host, "--camera", cell.camera_spec, "--speed-fraction", "1.0")


def _run_with_fault(cell, tree: Path, fault: str) -> tuple[int, dict, str]:
    """A run of ``tree`` with ``fault`` injected mid-motion (``ur_cli.FaultBackend``); then the faults are cleared."""
    faults = f"{cell.host}:{cell.faults_port}"
    env = {"BT_UR_FAULT": fault, "BT_UR_FAULTS": faults, "BT_UR_FAULT_AT_S": str(FAULT_AT_S)}
    try:
        return _run(str(tree), *_cell_args(cell)[2:], "--backend", "ur-fault", env=env)
    finally:
        cell.inject("clear")


def test_the_safety_behaviours_against_the_controller(one_cube_cell, only_root):
    cell = one_cube_cell
    before = cell.truth()

    # A dry run plans from the robot's joints and moves nothing.
    code, report, err = _run(str(only_root), *_cell_args(cell), "--dry-run")
    assert code == 0 and report["dry_run"]["motions"] > 5 and report["dry_run"]["refused"] == 0
    assert "nothing was sent to the robot" in err
    assert _moved_mm(before, cell.truth()) < 0.01

    # A motion outside the workspace box is refused before it starts: one line, exit 1, nothing moved.
    code, report, err = _run(str(only_root), *_cell_args(cell)[2:], "--backend", "ur-small-box")
    assert code == 1 and len(_our_lines(err)) == 1
    assert "bt-arrange: safety stop: the joint move to TCP" in err
    assert "outside the workspace box (x 0.100..0.300" in err
    assert _moved_mm(before, cell.truth()) < 0.01

    # An emergency stop mid-motion: exit 1, one line naming it.
    code, report, err = _run_with_fault(cell, only_root, "emergency_stop")
    assert code == 1 and report["tree_status"] == "FAILURE", (report, err)
    assert _our_lines(err) == ["bt-arrange: safety stop: the robot is in an emergency stop"], err
    assert report["sim_seconds"] < FAULT_AT_S + 0.5  # the tree ended at the fault

    # Ctrl-C: the arm is stopped (servoStop) before the process exits.
    _ctrl_c_stops_the_arm(cell, only_root)

    # A tree file with only create_root runs to the end: the cube within 1 mm by the controller's truth.
    code, report, _ = _run(str(only_root), *_cell_args(cell))
    x, y, _, _ = cell.truth()["red"]
    assert code == 0 and math.hypot(x - 0.50, y) * 1000 < 1.0, report

    # A protective stop when a finger touches the part while the arm moves (the lift; in a real cell, a push).
    # Last: the cube stays in the pads.
    code, report, err = _run_with_fault(cell, only_root, "protective_stop on_contact")
    assert code == 1 and "bt-arrange: safety stop: the robot is in a protective stop" in err
    assert report["safety_stop"].startswith("the robot is in a protective stop")


def test_a_dropped_rtde_connection_ends_the_run_and_nothing_moves_afterwards(only_root):
    # A controller of its own: what ur_rtde does after a drop (it reconnects on a thread of its own) is
    # kept away from the other runs.
    with ursim.launch(ROOT / "trees/single_cube.py", seed=0, host="127.0.77.4") as cell:
        code, report, err = _run_with_fault(cell, only_root, "drop rtde")
        assert code == 1 and report["tree_status"] == "FAILURE", (report, err)
        assert _our_lines(err) == [err.strip().splitlines()[-1]], err
        # The receive or the control interface, whichever tells first.
        assert re.search(
            r"bt-arrange: safety stop: lost the (RTDE|control) connection to the robot at 127\.0\.77\.4", err
        )
        _assert_at_rest(cell)


def _assert_at_rest(cell) -> None:
    """The arm's joints do not move over 0.3 s."""
    import rtde_receive

    receive = rtde_receive.RTDEReceiveInterface(cell.host)
    try:
        first = receive.getActualQ()
        time.sleep(0.3)
        assert max(abs(a - b) for a, b in zip(first, receive.getActualQ(), strict=True)) < 1e-4
    finally:
        receive.disconnect()


def _ctrl_c_stops_the_arm(cell, only_root: Path) -> None:
    import rtde_receive

    command = [sys.executable, "-m", "bt_arrange.cli", "run", str(only_root), *_cell_args(cell)[:-2]]
    process = subprocess.Popen(command, env=dict(os.environ), stderr=subprocess.PIPE, text=True)
    receive = rtde_receive.RTDEReceiveInterface(cell.host)
    try:
        start = receive.getActualQ()
        deadline = time.monotonic() + 30.0
        # Interrupted once the arm has started its way to the cube (at the default, half speed).
        while max(abs(a - b) for a, b in zip(start, receive.getActualQ(), strict=True)) < 0.05:
            assert time.monotonic() < deadline and process.poll() is None
            time.sleep(0.02)
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=30)
        assert process.returncode == 130, err
    finally:
        receive.disconnect()
    _assert_at_rest(cell)


def test_calibrate_on_the_controller_writes_a_camera_file_the_next_run_uses(tmp_path):
    out = tmp_path / "camera.toml"
    with ursim.launch(ROOT / "trees/single_cube.py", seed=0, host="127.0.77.3", board=True) as cell:
        code, stdout, err = _cli("calibrate", "--backend", "ur", "--robot", cell.host, "--camera", cell.camera_spec,
                                 "--views", "6", "--speed-fraction", "1.0", "--out", str(out), "--json")  # fmt: skip
        assert stdout.strip(), err
        result = json.loads(stdout.strip().splitlines()[-1])
        assert code == 0 and out.is_file() and result["reprojection_error_px"] < 1.0, result
        tree = str(ROOT / "trees/single_cube.py")
        code, report, _ = _run(tree, *_cell_args(cell), "--dry-run", "--calibration", str(out))
    assert code == 0
    assert report["camera_margin_mm"] > 0.0  # the calibration's own error: the run read the file
