"""The controller's text ports: the dashboard (29999), the script port (30003), the Robotiq URCap (63352), faults.

Each answers what a real CB3 on Polyscope 3.15 answers (the dashboard's reply strings are the
ones ``ur_rtde``'s ``DashboardClient`` checks), changes the controller's state on its physics
thread (``Controller.call``), and never lets one client's nonsense reach another client.
"""

from __future__ import annotations

import json
import re
import sys
from typing import TYPE_CHECKING

from bt_arrange_sim.ursim.controller import ROBOT_MODE_NAMES, SAFETY_MODE_NAMES
from bt_arrange_sim.ursim.servers import ClientRegistry, LineServer, TcpServer

if TYPE_CHECKING:
    import socket

    from bt_arrange_sim.ursim.controller import Controller

#: What ``PolyscopeVersion`` says: a CB3 (ur_rtde reads ``3.15.7.106331`` from it).
POLYSCOPE_VERSION = "URSoftware 3.15.7.106331 (Mar 04 2022)"
SERIAL_NUMBER = "2019300000"
ROBOT_MODEL = "UR5"
GREETING = "Connected: Universal Robots Dashboard Server"


class DashboardServer(LineServer):
    """Port 29999: one command a line, one reply line each."""

    name = "dashboard"
    greeting = GREETING

    def __init__(self, controller: Controller, host: str, port: int, clients: ClientRegistry) -> None:
        super().__init__(host, port, clients)
        self.controller = controller

    def reply(self, line: str) -> tuple[str | None, bool] | None:
        """The dashboard's answer to ``line`` (``quit`` also ends the session)."""
        command = line.strip()
        if not command:
            return None
        answer = self._answer(command)
        keep_open = command.lower() != "quit"
        return answer + "\n", keep_open

    def _answer(self, command: str) -> str:  # noqa: C901 - one branch per command
        controller = self.controller
        lower = command.lower()
        program_running = controller.snapshot.runtime_state == 2
        if command == "PolyscopeVersion":
            return POLYSCOPE_VERSION
        if lower == "get serial number":
            return SERIAL_NUMBER
        if lower == "get robot model":
            return ROBOT_MODEL
        if lower == "robotmode":
            return f"Robotmode: {ROBOT_MODE_NAMES.get(controller.robot_mode, str(controller.robot_mode))}"
        if lower in ("safetymode", "safetystatus"):
            word = "Safetymode" if lower == "safetymode" else "Safetystatus"
            return f"{word}: {SAFETY_MODE_NAMES.get(controller.safety_mode, str(controller.safety_mode))}"
        if lower == "programstate":
            return f"{'PLAYING' if program_running else 'STOPPED'} <unnamed>"
        if lower == "running":
            return f"Program running: {'true' if program_running else 'false'}"
        if lower == "play":
            # A program sent to the script port is not a loaded program: there is nothing to play.
            return "Failed to execute: play"
        if lower == "stop":
            controller.call(lambda: controller.stop_program("the dashboard's stop"))
            return "Stopped"
        if lower == "pause":
            return "Failed to execute: pause"
        if lower == "power on":
            controller.call(lambda: controller.set_power(True))
            return "Powering on"
        if lower == "power off":
            controller.call(lambda: controller.set_power(False))
            return "Powering off"
        if lower == "brake release":
            controller.call(controller.release_brakes)
            return "Brake releasing"
        if lower == "unlock protective stop":
            return str(controller.call(controller.unlock_protective_stop))
        if lower == "close safety popup":
            return "closing safety popup"
        if lower == "close popup":
            return "closing popup"
        if lower.startswith("popup "):
            return "showing popup"
        if lower == "restart safety":
            return "Restarting safety"
        if lower == "quit":
            return "Disconnected"
        if lower == "shutdown":
            return "Shutting down"
        if lower.startswith("load "):
            return f"File not found: {command[5:].strip()}"
        if lower == "get loaded program":
            return "No program loaded"
        if lower == "isprogramsaved":
            return "false <unnamed>"
        if lower.startswith("addtolog "):
            return "Added log message"
        if lower.startswith("setuserrole "):
            return f"Setting user role: {command.split(' ', 1)[1]}"
        return f"could not understand: '{command}'"


class ScriptServer(TcpServer):
    """Port 30003: URScript text. ``rtde_control`` starts the native program; nothing else is interpreted.

    A ``def NAME():`` ... ``end`` program (or ``sec``) is collected whole. The ``rtde_control``
    program starts ``program.ControlProgram`` with the register offset the client injected. Any other
    program replaces the running one, as on a real controller, and only its literal
    ``write_output_integer_register(n, v)`` calls take effect (``ur_rtde``'s custom script functions
    signal done that way). A one-line script replaces the running program too; ``stopj(a)`` and
    ``stopl(a)`` brake the arm, the rest is reported on stderr and ignored.
    """

    name = "script"
    PROGRAM_END = re.compile(r"^end[ \t]*$", re.MULTILINE)
    REGISTER_OFFSET = re.compile(r"#\s*int register offset\s*\n\s*(\d+)")
    OUTPUT_INT_WRITE = re.compile(r"write_output_integer_register\(\s*([0-9+\s]+?)\s*,\s*(-?\d+)\s*\)")
    STOP = re.compile(r"^(stopj|stopl)\(\s*([0-9.eE+-]+)")
    #: What a one-line script must look like to compile: a name, or a call of one with printable arguments.
    STATEMENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*\s*(\([ -~]*\))?$")
    #: The most a program may be (bytes): ur_rtde's is about 40 kB.
    MAX_PROGRAM_BYTES = 4_000_000

    def __init__(self, controller: Controller, host: str, port: int, clients: ClientRegistry) -> None:
        super().__init__(host, port, clients)
        self.controller = controller

    def handle(self, connection: socket.socket) -> None:
        """Collect programs and lines from the client until it leaves."""
        buffer = ""
        while True:
            chunk = connection.recv(65536)
            if not chunk:
                return
            buffer += chunk.decode("utf-8", "replace")
            buffer = self._consume(buffer)
            if len(buffer) > self.MAX_PROGRAM_BYTES:
                print("ursim: script port: an unterminated program of over 4 MB was dropped", file=sys.stderr)
                buffer = ""

    def _consume(self, buffer: str) -> str:
        """Run every whole program or line at the start of ``buffer``; what is left (an unfinished program)."""
        while True:
            text = buffer.lstrip()
            if not text:
                return ""
            if text.startswith(("def ", "sec ")):
                end = self.PROGRAM_END.search(text)
                if end is None:
                    return text
                self._run_program(text[: end.end()])
                buffer = text[end.end() :]
                continue
            if "\n" not in text:
                return text
            line, buffer = text.split("\n", 1)
            self._run_line(line.strip())

    def _run_program(self, program: str) -> None:
        header = program.split("\n", 1)[0].strip()
        name = header[4:].split("(", 1)[0].strip()
        controller = self.controller
        if name == "rtde_control":
            match = self.REGISTER_OFFSET.search(program)
            offset = int(match.group(1)) if match else 0
            controller.call(lambda: controller.start_program(offset))
            return
        print(
            f"ursim: program {name!r} is not interpreted: only its output register writes take effect", file=sys.stderr
        )
        writes = [
            (sum(int(t) for t in m.group(1).split("+") if t.strip()), int(m.group(2)))
            for m in self.OUTPUT_INT_WRITE.finditer(program)
        ]

        def run() -> None:
            if not header.startswith("sec "):
                controller.stop_program(f"program {name!r} replaced it")
            for index, value in writes:
                if 0 <= index < 48:
                    controller.registers.write_int(index, value)

        controller.call(run)

    def _run_line(self, line: str) -> None:
        if not line or line.startswith("#"):
            return
        if not self.STATEMENT.match(line):
            # It would not compile: a real controller reports the error and runs nothing, so the
            # running program goes on.
            print(f"ursim: script port: syntax error in {line[:60]!r}: ignored", file=sys.stderr)
            return
        controller = self.controller
        stop = self.STOP.match(line)

        def run() -> None:
            controller.stop_program(f"the script line {line[:60]!r} replaced it")
            if stop is not None:
                from bt_arrange_sim.ursim.motion import Stop

                controller.motion.start(Stop(float(stop.group(2)), controller.period_s))

        if stop is None:
            print(f"ursim: script line {line[:60]!r} is not interpreted (the running program stops)", file=sys.stderr)
        controller.call(run)


class GripperServer(LineServer):
    """Port 63352: the Robotiq URCap's socket (``SET ...`` answered ``ack``, ``GET VAR`` answered ``VAR n``)."""

    name = "gripper"

    def __init__(self, controller: Controller, host: str, port: int, clients: ClientRegistry) -> None:
        super().__init__(host, port, clients)
        self.gripper = controller.gripper

    def reply(self, line: str) -> tuple[str | None, bool] | None:
        """``ack`` (no newline, as the URCap sends it) or ``VAR value`` lines; ``?`` for what it cannot parse."""
        words = line.split()
        if not words:
            return None
        verb = words[0].upper()
        if verb == "SET" and len(words) >= 3 and len(words) % 2 == 1:
            try:
                assignments = [(words[i].upper(), int(words[i + 1])) for i in range(1, len(words), 2)]
            except ValueError:
                return "?\n", True
            return ("ack" if self.gripper.set(assignments) else "?\n"), True
        if verb == "GET" and len(words) == 2:
            return self.gripper.get(words[1].upper()) + "\n", True
        return "?\n", True


class FaultsServer(LineServer):
    """The tests' port: inject faults, drop clients, read the truth (one reply line each)."""

    name = "faults"
    DROPPABLE = ("rtde", "script", "dashboard", "gripper", "camera")

    def __init__(self, controller: Controller, host: str, port: int, clients: ClientRegistry) -> None:
        super().__init__(host, port, clients)
        self.controller = controller

    def reply(self, line: str) -> tuple[str | None, bool] | None:
        """``ok``, a JSON line (``truth``, ``stats``) or ``error: ...``."""
        words = line.split()
        if not words:
            return None
        controller = self.controller
        command = words[0].lower()
        argument = words[1].lower() if len(words) > 1 else ""
        if command == "protective_stop" and not argument:
            controller.call(lambda: controller.protective_stop("injected by the faults port"))
        elif command == "protective_stop" and argument == "on_contact":

            def arm() -> None:
                controller.protective_stop_on_contact = True

            controller.call(arm)
        elif command == "emergency_stop":
            controller.call(controller.emergency_stop)
        elif command == "drop" and (argument in self.DROPPABLE or argument == "all"):
            # "all" is every client port's, never this one's: the test that asked keeps its session.
            names = self.DROPPABLE if argument == "all" else (argument,)
            count = sum(self.clients.drop(name) for name in names)
            return f"ok {count}\n", True
        elif command == "truth":
            return json.dumps(controller.call(controller.part_truth)) + "\n", True
        elif command == "stats":
            stats = {
                "realtime_ratio": round(controller.realtime_ratio(), 4),
                "world_time_s": controller.snapshot.time_s,
            }
            return json.dumps(stats) + "\n", True
        elif command == "clear":
            controller.call(controller.clear_faults)
        else:
            return f"error: unknown fault {line.strip()!r}\n", True
        return "ok\n", True
