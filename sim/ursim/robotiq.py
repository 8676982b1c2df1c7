"""The Robotiq 2F-85 behind the Robotiq URCap's socket: its registers and their meaning, on the cell's gripper.

The socket (port 63352) speaks ASCII lines: ``SET VAR n [VAR n ...]`` answered ``ack``, ``GET VAR``
answered ``VAR n``. The variables are the gripper's: ACT (activate), GTO (go to the requested
position), POS/SPE/FOR (requested position, speed and force, 0-255), and the status it reports:
STA (0 reset, 1 activating, 3 active), PRE (the requested position echoed), OBJ (0 moving, 1 or 2
stopped on an object while opening or closing, 3 at the requested position), FLT (fault), POS (the
fingers' actual position). During an emergency stop every value reads ``?``.

POS 0 is fully open (the 2F-85's 85 mm), 255 closed; SPE and FOR map linearly onto the gripper's
speed and force ranges (``ROBOTIQ_2F85``). The cell's own gripper (``SimGripper``) moves the fingers,
so a part is held by the pads' friction alone. Socket threads change the requested values under
the lock; the physics thread applies them (``tick``).
"""

from __future__ import annotations

import threading

from bt_arrange.shapes.gripper import ROBOTIQ_2F85

#: The device's full scale of each 0-255 register.
FULL_SCALE = 255
#: The time activation takes (s of world time): the real gripper opens and closes once to find its stroke.
ACTIVATION_S = 1.5
#: A finger travel (m) within this of the requested opening counts as arrived.
ARRIVED_M = 0.0008
#: The fingers are taken to have stopped once the gripper says they no longer move for this many periods.
STOPPED_PERIODS = 4

#: Variables a client may set, and their allowed ranges.
SETTABLE = {"ACT": 1, "GTO": 1, "POS": 255, "SPE": 255, "FOR": 255, "ATR": 1, "ARD": 1, "MOD": 3, "ARR": 1}
READABLE = ("ACT", "GTO", "POS", "SPE", "FOR", "STA", "PRE", "OBJ", "FLT", "ATR", "ARD", "MOD")


def opening_m(position: int) -> float:
    """The opening between the pads for a device position (0 open .. 255 closed)."""
    return ROBOTIQ_2F85.stroke_m * (1.0 - position / FULL_SCALE)


def device_position(width_m: float) -> int:
    """The device position (0-255) of an opening."""
    return max(0, min(FULL_SCALE, round((1.0 - width_m / ROBOTIQ_2F85.stroke_m) * FULL_SCALE)))


def speed_m_s(speed: int) -> float:
    """A device speed (0-255) in m/s, on the 2F-85's range."""
    low, high = ROBOTIQ_2F85.speed_range_m_s
    return low + (high - low) * speed / FULL_SCALE


def force_n(force: int) -> float:
    """A device force (0-255) in N, on the 2F-85's range."""
    low, high = ROBOTIQ_2F85.force_range_n
    return low + (high - low) * force / FULL_SCALE


class RobotiqGripper:
    """The 2F-85's registers and motion on the cell's ``SimGripper``."""

    def __init__(self, gripper: object, period_s: float) -> None:
        self._gripper = gripper
        self._period_s = period_s
        self._lock = threading.Lock()
        self.values = {name: 0 for name in SETTABLE}
        self.values.update({"STA": 0, "PRE": 0, "OBJ": 0, "FLT": 0})
        self.values["POS"] = 0
        self._actual_position = device_position(gripper.width())  # type: ignore[attr-defined]
        #: What a SET asked the physics thread to do: open the fingers for the activation, start a move.
        self._activate = False
        self._new_goal = False
        self._activation_left_s = 0.0
        self._goal: tuple[int, int, int] | None = None
        self._closing = False
        self._still_periods = 0
        self.emergency_stopped = False

    # -- the socket's side (any thread) ------------------------------------------------------

    def set(self, assignments: list[tuple[str, int]]) -> bool:
        """A ``SET`` line's assignments; False when one is not a variable or out of range."""
        for name, value in assignments:
            if name not in SETTABLE or not 0 <= value <= SETTABLE[name]:
                return False
        with self._lock:
            values = self.values
            for name, value in assignments:
                values[name] = value
            # The registers answer at once (a client that polls STA, or PRE then OBJ, sees the new
            # state); the fingers move from the next control period (``tick``).
            if values["ACT"] == 0:
                values["STA"] = 0
                values["OBJ"] = 0
                self._goal = None
            elif values["STA"] == 0:
                values["STA"] = 1
                self._activation_left_s = ACTIVATION_S
                self._activate = True
            elif values["STA"] == 3 and values["GTO"] == 1:
                values["PRE"] = values["POS"]
                values["OBJ"] = 0
                self._new_goal = True
        return True

    def get(self, name: str) -> str:
        """A ``GET`` line's answer: ``NAME value``, ``NAME ?`` during an emergency stop."""
        with self._lock:
            if self.emergency_stopped:
                return f"{name} ?"
            if name == "POS":
                return f"POS {self._actual_position}"
            return f"{name} {self.values[name]}"

    # -- the physics thread's side -------------------------------------------------------------

    def tick(self) -> None:
        """Apply what the socket asked for, and update the status registers (once per control period)."""
        gripper = self._gripper
        with self._lock:
            if self.emergency_stopped:
                return
            values = self.values
            if self._activate:
                self._activate = False
                gripper.open(ROBOTIQ_2F85.stroke_m)  # type: ignore[attr-defined]
            if self._new_goal:
                self._new_goal = False
                self._start_goal(values)
            if values["STA"] == 1:
                self._activation_left_s -= self._period_s
                if self._activation_left_s <= 0:
                    values["STA"] = 3
                    values["OBJ"] = 3
        width = gripper.width()  # type: ignore[attr-defined]
        moving = gripper.is_moving()  # type: ignore[attr-defined]
        with self._lock:
            self._actual_position = device_position(width)
            if self._goal is not None and self.values["STA"] == 3:
                self._update_object_status(width, moving)

    def _start_goal(self, values: dict[str, int]) -> None:
        """GTO 1 on an active gripper: move to POS at SPE, closing with at most FOR."""
        goal = (values["POS"], values["SPE"], values["FOR"])
        self._goal = goal
        self._still_periods = 0
        target_m = opening_m(goal[0])
        gripper = self._gripper
        if target_m < gripper.width() - ARRIVED_M:  # type: ignore[attr-defined]
            self._closing = True
            gripper.close(force_n(goal[2]), speed_m_s(goal[1]))  # type: ignore[attr-defined]
        else:
            self._closing = False
            gripper.open(target_m, speed_m_s(goal[1]))  # type: ignore[attr-defined]

    def _update_object_status(self, width_m: float, moving: bool) -> None:
        """OBJ from where the fingers are: arrived (3), stopped short on an object (2 closing, 1 opening)."""
        if self.values["OBJ"] != 0 or self._goal is None:
            return
        target_m = opening_m(self._goal[0])
        if self._closing and width_m <= target_m + ARRIVED_M:
            # Nothing between the pads: hold the requested opening instead of squeezing on.
            self._gripper.open(max(target_m, 0.0), speed_m_s(self._goal[1]))  # type: ignore[attr-defined]
            self.values["OBJ"] = 3
            return
        if not self._closing and abs(width_m - target_m) <= ARRIVED_M:
            self.values["OBJ"] = 3
            return
        self._still_periods = 0 if moving else self._still_periods + 1
        if self._still_periods >= STOPPED_PERIODS:
            self.values["OBJ"] = 2 if self._closing else 1

    def emergency_stop(self, stopped: bool) -> None:
        """An emergency stop cuts the gripper's power: its values read ``?`` until it is released."""
        with self._lock:
            self.emergency_stopped = stopped
