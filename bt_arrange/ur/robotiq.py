"""The Robotiq 2F-85 through the Robotiq URCap's socket on the UR controller (port 63352): a ``Gripper``.

The URCap serves ASCII lines: ``SET POS 128 SPE 255 FOR 100 GTO 1`` is answered ``ack``, ``GET POS``
is answered ``POS 128``. Variables: ``ACT`` (activate), ``GTO`` (go to the requested position),
``POS``/``SPE``/``FOR`` (position, speed, force, 0-255), ``STA`` (0 reset, 1 activating, 3 active),
``OBJ`` (0 moving, 1 and 2 an object caught while opening or closing, 3 at the requested position),
``FLT`` (fault code, 0 none). During an emergency stop the values read ``?``.

``RobotiqSocket`` speaks the protocol (one request, one answer line, with a timeout); ``RobotiqGripper``
is the ``bt_arrange.robot.Gripper`` on top of it: it maps widths, speeds and forces to the 0-255
registers, never blocks (a command is one round trip; ``refresh()``, called once per control period by
the world, reads the position and the object status that ``width()`` and ``is_moving()`` then return).
"""

from __future__ import annotations

import socket
import time

from bt_arrange.errors import BackendError
from bt_arrange.ranges import checked_grip_force_n, checked_gripper_speed_m_s, checked_gripper_width_m
from bt_arrange.robot import GRIPPER_FORCE_RANGE_N, GRIPPER_MAX_WIDTH_M, GRIPPER_SPEED_RANGE_M_S

#: The Robotiq URCap's socket on the UR controller.
ROBOTIQ_PORT = 63352
#: How long one request may wait for its answer (s): a loopback or a lab network answers in milliseconds.
REQUEST_TIMEOUT_S = 1.0
#: How long activation may take (s): the 2F-85 opens and closes once to find its stroke.
ACTIVATION_TIMEOUT_S = 10.0
#: ``STA`` of an activated gripper, and ``OBJ`` of fingers still moving.
STATUS_ACTIVE = 3
OBJECT_MOVING = 0
#: ``OBJ`` after a motion that reached its requested position without meeting anything.
OBJECT_AT_POSITION = 3
#: The register range of POS, SPE and FOR.
REGISTER_MAX = 255
#: A command counts as moving for at least this many refreshes (the URCap updates ``OBJ`` on its own cycle).
COMMAND_SETTLE_REFRESHES = 2


class GripperLinkError(BackendError):
    """The gripper's socket failed (closed, timed out) or answered what the protocol does not allow."""


class RobotiqSocket:
    """One connection to the Robotiq URCap's socket: ``set(POS=.., SPE=..)`` and ``get("POS")``."""

    def __init__(self, host: str, port: int = ROBOTIQ_PORT, timeout_s: float = REQUEST_TIMEOUT_S) -> None:
        self.address = f"{host}:{port}"
        try:
            self._socket = socket.create_connection((host, port), timeout=timeout_s)
        except OSError as error:
            raise GripperLinkError(
                f"cannot reach the gripper's Robotiq URCap socket at {self.address}: {error.strerror or error}"
            ) from error
        self._socket.settimeout(timeout_s)
        self._buffer = b""

    def request(self, line: str) -> str:
        """Send ``line`` and return the answer (without its newline); a ``GripperLinkError`` if none comes.

        The URCap answers a ``SET`` with a bare ``ack`` (no newline) and a ``GET`` with a line.
        """
        expects_ack = line.startswith("SET ")
        try:
            self._socket.sendall(line.encode("ascii") + b"\n")
            while True:
                # A newline that trailed an earlier ``ack`` may arrive late: it belongs to no answer.
                self._buffer = self._buffer.lstrip(b"\r\n")
                if expects_ack and self._buffer.startswith(b"ack"):
                    self._buffer = self._buffer[3:]
                    return "ack"
                if b"\n" in self._buffer and not (expects_ack and b"ack".startswith(self._buffer[:3])):
                    answer, _, self._buffer = self._buffer.partition(b"\n")
                    return answer.decode("ascii", errors="replace").strip()
                chunk = self._socket.recv(1024)
                if not chunk:
                    raise GripperLinkError(f"the gripper's socket at {self.address} was closed")
                self._buffer += chunk
        except OSError as error:
            raise GripperLinkError(
                f"lost the gripper's socket at {self.address} ({error.strerror or type(error).__name__})"
            ) from error

    def set(self, **registers: int) -> None:
        """``SET NAME value ...`` in the order given; the URCap must answer ``ack``."""
        line = "SET " + " ".join(f"{name} {int(value)}" for name, value in registers.items())
        answer = self.request(line)
        if answer != "ack":
            raise GripperLinkError(f"the gripper answered {answer!r} to {line!r} (expected ack)")

    def get(self, name: str) -> int:
        """``GET NAME``: the register's value; a ``GripperLinkError`` when it reads ``?`` (an emergency stop)."""
        answer = self.request(f"GET {name}")
        key, _, value = answer.partition(" ")
        if key != name:
            raise GripperLinkError(f"the gripper answered {answer!r} to GET {name}")
        if value.strip() == "?":
            raise GripperLinkError(f"the gripper's {name} reads ? (the controller is in an emergency stop)")
        try:
            return int(value)
        except ValueError:
            raise GripperLinkError(f"the gripper answered {answer!r} to GET {name}: not a number") from None

    def close(self) -> None:
        """Close the connection."""
        try:
            self._socket.close()
        except OSError:
            pass


def width_to_position(width_m: float, closed_position: int = REGISTER_MAX) -> int:
    """The POS register for an opening: 0 is the full stroke, ``closed_position`` the pads touching."""
    fraction = 1.0 - width_m / GRIPPER_MAX_WIDTH_M
    return max(0, min(REGISTER_MAX, round(fraction * closed_position)))


def position_to_width_m(position: int, closed_position: int = REGISTER_MAX) -> float:
    """The opening (m) a POS register stands for (the inverse of ``width_to_position``)."""
    return max(0.0, GRIPPER_MAX_WIDTH_M * (1.0 - position / closed_position))


def speed_register(speed_m_s: float) -> int:
    """SPE for a finger speed: 0 is the 2F-85's slowest (20 mm/s), 255 its fastest (150 mm/s)."""
    low, high = GRIPPER_SPEED_RANGE_M_S
    return max(0, min(REGISTER_MAX, round((speed_m_s - low) / (high - low) * REGISTER_MAX)))


def force_register(force_n: float) -> int:
    """FOR for a grip force: 0 is the 2F-85's least (20 N), 255 its most (235 N)."""
    low, high = GRIPPER_FORCE_RANGE_N
    return max(0, min(REGISTER_MAX, round((force_n - low) / (high - low) * REGISTER_MAX)))


class RobotiqGripper:
    """A 2F-85 on the URCap's socket as a ``bt_arrange.robot.Gripper`` (widths in metres between the pads).

    ``closed_position`` is the POS register at which the pads touch (255 by the protocol's scale; a
    real 2F-85's is measured when it is commissioned, docs/real-cell.md). ``default_speed_m_s`` and
    ``open_force_n`` are used when a command gives no speed, and for opening.
    """

    def __init__(
        self,
        link: RobotiqSocket,
        *,
        closed_position: int = REGISTER_MAX,
        default_speed_m_s: float = 0.15,
        open_force_n: float = 40.0,
    ) -> None:
        self._link = link
        self._closed_position = closed_position
        self._default_speed_m_s = default_speed_m_s
        self._open_force_n = open_force_n
        self._position = 0
        self._object = OBJECT_AT_POSITION
        self._target_position = 0
        self._refreshes_since_command = COMMAND_SETTLE_REFRESHES

    @property
    def max_width_m(self) -> float:
        """The 2F-85's stroke (m)."""
        return GRIPPER_MAX_WIDTH_M

    def activate(self, timeout_s: float = ACTIVATION_TIMEOUT_S) -> None:
        """Activate the gripper unless it is active: ``ACT 0``, ``ACT 1``, then wait for ``STA 3``."""
        if self._link.get("STA") != STATUS_ACTIVE:
            self._link.set(ACT=0)
            self._link.set(ACT=1)
            deadline = time.monotonic() + timeout_s
            while self._link.get("STA") != STATUS_ACTIVE:
                if time.monotonic() > deadline:
                    raise GripperLinkError(f"the gripper at {self._link.address} did not activate in {timeout_s:g} s")
                time.sleep(0.05)
        self.refresh()

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Move the pads to ``width_m`` apart; returns after the URCap's ``ack``."""
        checked_gripper_width_m(width_m)
        speed = checked_gripper_speed_m_s(self._default_speed_m_s if speed_m_s is None else speed_m_s)
        self._go(width_to_position(width_m, self._closed_position), speed, self._open_force_n)

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Close until the pads squeeze with at most ``force_n``; returns after the URCap's ``ack``."""
        checked_grip_force_n(force_n)
        speed = checked_gripper_speed_m_s(self._default_speed_m_s if speed_m_s is None else speed_m_s)
        self._go(REGISTER_MAX, speed, force_n)

    def _go(self, position: int, speed_m_s: float, force_n: float) -> None:
        self._link.set(POS=position, SPE=speed_register(speed_m_s), FOR=force_register(force_n), GTO=1)
        self._target_position = position
        self._refreshes_since_command = 0

    def refresh(self) -> None:
        """Read the position and the object status once (the world calls it once per control period)."""
        self._position = self._link.get("POS")
        self._object = self._link.get("OBJ")
        self._refreshes_since_command += 1

    def fault(self) -> int:
        """The gripper's fault code (``FLT``; 0: none)."""
        return self._link.get("FLT")

    def width(self) -> float:
        """The opening (m) read at the last refresh."""
        return position_to_width_m(self._position, self._closed_position)

    def is_moving(self) -> bool:
        """True while the URCap reports the fingers moving, and just after a command that has somewhere to go."""
        if self._object == OBJECT_MOVING:
            return True
        # The URCap may still report the last motion's status just after a command: the fingers count as
        # moving until it had time to say otherwise, unless they already stand where they were sent.
        fresh = self._refreshes_since_command < COMMAND_SETTLE_REFRESHES
        return fresh and abs(self._position - self._target_position) > 1

    def close_link(self) -> None:
        """Close the socket."""
        self._link.close()
