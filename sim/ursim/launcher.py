"""``launch``: start the controller (``python -m bt_arrange_sim.ursim``) as a subprocess, for tests and benchmarks.

``with launch(tree, seed, truth_path) as sim:`` waits for its ready line, yields a ``UrSim`` (its
camera's URL, its faults port), and SIGTERMs it at the end (it writes its truth and exits 0).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import IO, Any

#: How long ``launch`` waits for the ``ready`` line (s): building a scene and starting takes a few seconds.
READY_TIMEOUT_S = 120.0
#: How long a SIGTERMed controller has to write its truth and exit (s).
EXIT_TIMEOUT_S = 30.0


class UrSim:
    """A running controller: its camera's URL, and its faults port (``inject``, ``truth``, ``stats``)."""

    def __init__(self, process: subprocess.Popen, camera_spec: str, host: str, faults_port: int) -> None:
        self.process = process
        self.camera_spec = camera_spec
        self.host = host
        self.faults_port = faults_port
        #: After exit: the process's return code and anything it printed on stdout after the ready line.
        self.returncode: int | None = None
        self.stdout_after_ready = ""

    def inject(self, line: str, timeout_s: float = 30.0) -> str:
        """Send one line to the faults port (``protective_stop``, ``drop rtde``...); its reply line."""
        with socket.create_connection((self.host, self.faults_port), timeout=timeout_s) as connection:
            connection.sendall(line.strip().encode() + b"\n")
            reply = b""
            while not reply.endswith(b"\n"):
                chunk = connection.recv(65536)
                if not chunk:
                    break
                reply += chunk
        return reply.decode().strip()

    def truth(self) -> dict[str, list[float]]:
        """Every part's true pose now: name to ``[x_m, y_m, z_m, yaw_rad]``."""
        return json.loads(self.inject("truth"))

    def stats(self) -> dict[str, float]:
        """The controller's achieved real-time ratio and world time."""
        return json.loads(self.inject("stats"))


@contextlib.contextmanager
def launch(
    tree_or_plan: str | os.PathLike[str] | None,
    seed: int = 0,
    truth_path: str | os.PathLike[str] | None = None,
    *,
    host: str = "127.0.0.1",
    camera_port: int = 8081,
    faults_port: int = 30099,
    cell: str = "ideal",
    board: bool = False,
    realtime_factor: float = 1.0,
    extra_args: Sequence[str] = (),
    stderr: IO[Any] | int | None = None,
    ready_timeout_s: float = READY_TIMEOUT_S,
) -> Iterator[UrSim]:
    """Start ``python -m bt_arrange_sim.ursim`` and yield it once ready; SIGTERM it and wait at the end.

    Raises ``RuntimeError`` (with what the process said) when it exits or stays silent before its
    ``ready`` line. ``stderr`` is where its log goes (inherited by default).
    """
    command = [sys.executable, "-m", "bt_arrange_sim.ursim"]
    if tree_or_plan is not None:
        command.append(str(tree_or_plan))
    command += ["--seed", str(seed), "--host", host, "--camera-port", str(camera_port)]
    command += ["--faults-port", str(faults_port), "--cell", cell, "--realtime-factor", str(realtime_factor)]
    if truth_path is not None:
        command += ["--truth", str(Path(truth_path))]
    if board:
        command.append("--board")
    command += list(extra_args)
    # The controller ends with this process (``--parent-pid``): none outlives a test killed mid-way.
    command += ["--parent-pid", str(os.getpid())]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr, text=True)
    try:
        line = _read_line(process, ready_timeout_s)
        if not line.startswith("ready camera="):
            raise RuntimeError(f"ursim did not start (exit code {process.poll()}): stdout {line!r}")
        sim = UrSim(process, line.strip().split("=", 1)[1], host, faults_port)
        yield sim
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
        try:
            rest, _ = process.communicate(timeout=EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            rest, _ = process.communicate()
        if "sim" in locals():
            sim.returncode = process.returncode
            sim.stdout_after_ready = rest or ""


def _read_line(process: subprocess.Popen, timeout_s: float) -> str:
    """The process's first stdout line, or '' when it ends or says nothing within ``timeout_s``."""
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.append(process.stdout.readline()), daemon=True)  # type: ignore[union-attr]
    reader.start()
    reader.join(timeout_s)
    return lines[0] if lines else ""
