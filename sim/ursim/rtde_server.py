"""RTDE, protocol version 2, on port 30004: recipes, start and pause, data packages both ways.

Every package is a header (``>HB``: the whole package's size, its type) and a payload. A client
asks for the protocol version (``V``), the controller's version (``v``), sets up an output recipe
(``O``: a frequency and names; the reply is a recipe id and each field's type, ``NOT_FOUND`` for an
unknown name) and input recipes (``I``: names; ``IN_USE`` for a register another client writes),
then starts (``S``) the outputs and sends data packages (``U``: a recipe id, then the values) to
write inputs. Outputs go out at the recipe's frequency (at most the controller's 125 Hz), each
one period's snapshot, stamped with the controller's world time. Several clients at once, each
on its own thread (a reader) plus a writer once started.
"""

from __future__ import annotations

import os
import socket
import struct
import sys
import threading
from typing import TYPE_CHECKING, Any

from bt_arrange_sim.ursim.fields import (
    IN_USE,
    INPUT_FIELDS,
    NOT_FOUND,
    OUTPUT_FIELDS,
    flatten,
    recipe_struct,
    unflatten,
)
from bt_arrange_sim.ursim.servers import ClientRegistry, TcpServer

if TYPE_CHECKING:
    from bt_arrange_sim.ursim.controller import Controller, Snapshot

PROTOCOL_VERSION = 2
#: The controller's version (``v``): a CB3 on Polyscope 3.15 (ur_rtde then uses 125 Hz and CB3 scripts).
CONTROLLER_VERSION = (3, 15, 7, 106331)
CONTROLLER_FREQUENCY_HZ = 125.0

REQUEST_PROTOCOL_VERSION = ord("V")
GET_URCONTROL_VERSION = ord("v")
TEXT_MESSAGE = ord("M")
DATA_PACKAGE = ord("U")
SETUP_OUTPUTS = ord("O")
SETUP_INPUTS = ord("I")
START = ord("S")
PAUSE = ord("P")
HEADER = struct.Struct(">HB")

_ZEROS6 = [0.0] * 6


def output_getter(name: str) -> Any:
    """How to read the output field ``name`` (a known one) off a snapshot: a function of the snapshot."""
    getter = _GETTERS.get(name)
    if getter is not None:
        return getter
    field, _, number = name.rpartition("_")
    if field in ("output_int_register", "output_double_register", "input_int_register", "input_double_register"):
        registers, index = field.removesuffix("_register"), int(number)  # the snapshot's list of them
        return lambda s: getattr(s, registers)[index]
    if name.startswith(("output_bit_register_", "input_bit_register_")):
        attribute, bit = ("output_bits" if name.startswith("output") else "input_bits"), int(number)
        return lambda s: bool(getattr(s, attribute) >> bit & 1)
    # What this controller has no model of (currents, voltages, I/O): zeros.
    constant = {"VECTOR6D": _ZEROS6, "VECTOR3D": [0.0] * 3, "VECTOR6INT32": [0] * 6, "VECTOR6UINT32": [0] * 6}.get(
        OUTPUT_FIELDS[name], False if OUTPUT_FIELDS[name] == "BOOL" else 0
    )
    return lambda s: constant


def output_value(name: str, snapshot: Snapshot) -> Any:
    """The value of the output field ``name`` in ``snapshot`` (a list for a vector)."""
    return output_getter(name)(snapshot)


_GETTERS: dict[str, Any] = {
    "timestamp": lambda s: s.time_s,
    "target_q": lambda s: s.target_q,
    "target_qd": lambda s: s.target_qd,
    "target_qdd": lambda s: s.target_qdd,
    "actual_q": lambda s: s.actual_q,
    "actual_qd": lambda s: s.actual_qd,
    "actual_TCP_pose": lambda s: s.actual_tcp_pose,
    "actual_TCP_speed": lambda s: s.actual_tcp_speed,
    "target_TCP_pose": lambda s: s.target_tcp_pose,
    "target_TCP_speed": lambda s: s.actual_tcp_speed,
    "joint_temperatures": lambda s: [30.0] * 6,
    "actual_execution_time": lambda s: 0.5,
    "robot_mode": lambda s: s.robot_mode,
    "joint_mode": lambda s: s.joint_mode,
    "safety_mode": lambda s: s.safety_mode,
    "actual_tool_accelerometer": lambda s: [0.0, 0.0, -9.81],
    "speed_scaling": lambda s: s.speed_scaling,
    "target_speed_fraction": lambda s: 1.0,
    "actual_main_voltage": lambda s: 48.0,
    "actual_robot_voltage": lambda s: 48.0 if s.robot_mode != 3 else 0.0,
    "actual_joint_voltage": lambda s: [48.0] * 6 if s.robot_mode != 3 else _ZEROS6,
    "runtime_state": lambda s: s.runtime_state,
    "elbow_position": lambda s: s.elbow_position,
    "robot_status_bits": lambda s: s.robot_status_bits,
    "safety_status_bits": lambda s: s.safety_status_bits,
    "tool_mode": lambda s: s.robot_mode,
    "tool_temperature": lambda s: 30.0,
    "output_bit_registers0_to_31": lambda s: s.output_bits & 0xFFFFFFFF,
    "output_bit_registers32_to_63": lambda s: (s.output_bits >> 32) & 0xFFFFFFFF,
    "input_bit_registers0_to_31": lambda s: s.input_bits & 0xFFFFFFFF,
    "input_bit_registers32_to_63": lambda s: (s.input_bits >> 32) & 0xFFFFFFFF,
    "payload": lambda s: s.payload_kg,
    "payload_cog": lambda s: s.payload_cog_m,
    "tcp_offset": lambda s: s.tcp_offset,
}


class InputOwners:
    """Which connection writes each input field: a register two clients would write is ``IN_USE``."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._owners: dict[str, int] = {}

    def claim(self, names: list[str], connection_id: int) -> list[str]:
        """The names among ``names`` another live connection writes (none claimed then), else claim them all."""
        with self._lock:
            taken = [n for n in names if self._owners.get(n, connection_id) != connection_id]
            if not taken:
                for name in names:
                    self._owners[name] = connection_id
            return taken

    def release(self, connection_id: int) -> None:
        """A connection closed: its fields are free."""
        with self._lock:
            self._owners = {n: c for n, c in self._owners.items() if c != connection_id}


class RtdeServer(TcpServer):
    """The RTDE port; one ``RtdeConnection`` per client."""

    name = "rtde"

    def __init__(self, controller: Controller, host: str, port: int, clients: ClientRegistry) -> None:
        super().__init__(host, port, clients)
        self.controller = controller
        self.input_owners = InputOwners()
        self._next_id = 0

    def handle(self, connection: socket.socket) -> None:
        """Serve one client until it leaves."""
        self._next_id += 1
        RtdeConnection(self, connection, self._next_id).serve()


class RtdeConnection:
    """One RTDE client: its recipes, its reader loop and, once started, its writer thread."""

    def __init__(self, server: RtdeServer, connection: socket.socket, connection_id: int) -> None:
        self.server = server
        self.controller = server.controller
        self.socket = connection
        self.id = connection_id
        self._send_lock = threading.Lock()
        self._output: tuple[list[Any], list[str], float] | None = None  # getters, types, frequency
        self._inputs: dict[int, tuple[list[str], list[str], struct.Struct]] = {}
        self._started = threading.Event()
        self._closed = threading.Event()
        self._writer: threading.Thread | None = None

    def serve(self) -> None:
        """Read packages until the client closes; answer each."""
        _debug(f"rtde {self.id}: connected")
        try:
            while True:
                header = _read_exactly(self.socket, HEADER.size)
                if header is None:
                    return
                size, kind = HEADER.unpack(header)
                if size < HEADER.size:
                    return  # a broken stream: a real controller drops such a client too
                payload = _read_exactly(self.socket, size - HEADER.size)
                if payload is None:
                    return
                self._handle(kind, payload)
        except OSError:
            return
        finally:
            _debug(f"rtde {self.id}: closed")
            self._closed.set()
            self._started.clear()
            self.server.input_owners.release(self.id)

    def _send(self, kind: int, payload: bytes) -> None:
        with self._send_lock:
            self.socket.sendall(HEADER.pack(HEADER.size + len(payload), kind) + payload)

    def _handle(self, kind: int, payload: bytes) -> None:
        _debug(f"rtde {self.id}: package {chr(kind)!r} of {len(payload)} bytes" if kind != DATA_PACKAGE else "")
        if kind == REQUEST_PROTOCOL_VERSION:
            (version,) = struct.unpack(">H", payload[:2]) if len(payload) >= 2 else (0,)
            self._send(REQUEST_PROTOCOL_VERSION, struct.pack(">B", 1 if version == PROTOCOL_VERSION else 0))
        elif kind == GET_URCONTROL_VERSION:
            self._send(GET_URCONTROL_VERSION, struct.pack(">IIII", *CONTROLLER_VERSION))
        elif kind == TEXT_MESSAGE:
            print(f"ursim: RTDE client message: {payload[1:].decode('utf-8', 'replace')!r}", file=sys.stderr)
        elif kind == SETUP_OUTPUTS:
            self._setup_outputs(payload)
        elif kind == SETUP_INPUTS:
            self._setup_inputs(payload)
        elif kind == START:
            ok = self._output is not None
            # The reply first: a client reads exactly one package for it, and a data package then would
            # leave it believing the start failed.
            self._send(START, struct.pack(">B", int(ok)))
            if ok:
                self._started.set()
                if self._writer is None:
                    self._writer = threading.Thread(target=self._write_outputs, name="rtde-writer", daemon=True)
                    self._writer.start()
        elif kind == PAUSE:
            self._started.clear()
            self._send(PAUSE, struct.pack(">B", 1))
        elif kind == DATA_PACKAGE:
            self._write_inputs(payload)
        else:
            print(f"ursim: RTDE package of unknown type {kind} ignored", file=sys.stderr)

    def _setup_outputs(self, payload: bytes) -> None:
        if len(payload) < 8:
            self._send(SETUP_OUTPUTS, struct.pack(">B", 0))
            return
        (frequency,) = struct.unpack(">d", payload[:8])
        names = _names(payload[8:])
        types = [OUTPUT_FIELDS.get(n, NOT_FOUND) for n in names]
        ok = bool(names) and NOT_FOUND not in types and frequency > 0
        if ok:
            self._output = ([output_getter(n) for n in names], types, min(frequency, CONTROLLER_FREQUENCY_HZ))
        recipe_id = 1 if ok else 0
        self._send(SETUP_OUTPUTS, struct.pack(">B", recipe_id) + ",".join(types).encode())

    def _setup_inputs(self, payload: bytes) -> None:
        names = _names(payload)
        types = [INPUT_FIELDS.get(n, NOT_FOUND) for n in names]
        if names and NOT_FOUND not in types:
            taken = self.server.input_owners.claim(names, self.id)
            if taken:
                types = [IN_USE if n in taken else t for n, t in zip(names, types, strict=True)]
        ok = bool(names) and NOT_FOUND not in types and IN_USE not in types
        recipe_id = 0
        if ok:
            recipe_id = len(self._inputs) + 1
            self._inputs[recipe_id] = (names, types, recipe_struct(types))
        self._send(SETUP_INPUTS, struct.pack(">B", recipe_id) + ",".join(types).encode())

    def _write_inputs(self, payload: bytes) -> None:
        if not payload:
            return
        recipe = self._inputs.get(payload[0])
        if recipe is None:
            return  # an unknown recipe id: a real controller ignores the package
        names, types, layout = recipe
        if len(payload) != layout.size:
            print(f"ursim: RTDE data package of {len(payload)} bytes for a {layout.size}-byte recipe", file=sys.stderr)
            return
        values = unflatten(layout.unpack(payload)[1:], types)
        self.controller.registers.write_inputs(names, values)

    def _write_outputs(self) -> None:
        """Send one data package every ``125 / frequency`` control periods while started, until the client leaves."""
        assert self._output is not None
        index = self.controller.snapshot.period_index
        try:
            while not self._closed.is_set() and not self.controller.stopped:
                if not self._started.wait(timeout=0.1):
                    continue
                getters, types, frequency = self._output
                periods = max(1, round(CONTROLLER_FREQUENCY_HZ / frequency))
                layout = recipe_struct(types)
                snapshot = self.controller.wait_for_period(index + periods - 1)
                if snapshot.period_index < index + periods:
                    continue  # the physics did not step (stopping): nothing new to send
                index = snapshot.period_index
                values = [getter(snapshot) for getter in getters]
                self._send(DATA_PACKAGE, layout.pack(1, *flatten(values, types)))
        except OSError:
            return


def _debug(message: str) -> None:
    """A protocol trace on stderr when ``URSIM_DEBUG`` is set."""
    if message and os.environ.get("URSIM_DEBUG"):
        print(f"ursim: {message}", file=sys.stderr)


def _names(payload: bytes) -> list[str]:
    """A recipe's names: comma-separated, a trailing comma allowed."""
    return [n.strip() for n in payload.decode("utf-8", "replace").split(",") if n.strip()]


def _read_exactly(connection: socket.socket, count: int) -> bytes | None:
    """``count`` bytes, or None when the client closed the connection first."""
    data = bytearray()
    while len(data) < count:
        chunk = connection.recv(count - len(data))
        if not chunk:
            return None
        data.extend(chunk)
    return bytes(data)
