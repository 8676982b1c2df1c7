"""The controller's general-purpose registers, shared by the RTDE clients and the program.

RTDE clients write the input registers (from their own threads), the program reads them and
writes the output registers (on the physics thread), and every RTDE client reads both. A lock
keeps each read or write whole; nothing here touches pybullet.
"""

from __future__ import annotations

import threading

from bt_arrange_sim.ursim.fields import REGISTER_COUNT


class RegisterBank:
    """48 integer, 48 double and 128 bit registers each way, plus the inputs' other fields (speed slider...)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.input_int = [0] * REGISTER_COUNT
        self.input_double = [0.0] * REGISTER_COUNT
        self.input_bits = 0
        self.output_int = [0] * REGISTER_COUNT
        self.output_double = [0.0] * REGISTER_COUNT
        self.output_bits = 0
        #: The other input fields a client wrote (speed slider, digital outputs...), by name.
        self.other_inputs: dict[str, object] = {}
        #: How many times a client wrote ``input_int_register_N``, per N (the RTDE watchdog's heartbeat).
        self.int_writes = [0] * REGISTER_COUNT

    def write_inputs(self, names: list[str], values: list[object]) -> None:
        """A client's data package: each named input field set to its value."""
        with self._lock:
            for name, value in zip(names, values, strict=True):
                if name.startswith("input_int_register_"):
                    index = int(name.rsplit("_", 1)[1])
                    self.input_int[index] = int(value)  # type: ignore[call-overload]
                    self.int_writes[index] += 1
                elif name.startswith("input_double_register_"):
                    self.input_double[int(name.rsplit("_", 1)[1])] = float(value)  # type: ignore[arg-type]
                elif name.startswith("input_bit_register_"):
                    bit = 1 << int(name.rsplit("_", 1)[1])
                    self.input_bits = (self.input_bits | bit) if value else (self.input_bits & ~bit)
                elif name == "input_bit_registers0_to_31":
                    self.input_bits = (self.input_bits & ~0xFFFFFFFF) | int(value)  # type: ignore[call-overload]
                elif name == "input_bit_registers32_to_63":
                    self.input_bits = (self.input_bits & ~(0xFFFFFFFF << 32)) | (int(value) << 32)  # type: ignore[call-overload]
                else:
                    self.other_inputs[name] = value

    def read_int(self, index: int) -> int:
        """``input_int_register_<index>``."""
        with self._lock:
            return self.input_int[index]

    def read_double(self, index: int) -> float:
        """``input_double_register_<index>``."""
        with self._lock:
            return self.input_double[index]

    def read_doubles(self, first: int, count: int) -> list[float]:
        """``count`` input double registers from ``first``."""
        with self._lock:
            return self.input_double[first : first + count]

    def write_int(self, index: int, value: int) -> None:
        """``output_int_register_<index>``."""
        with self._lock:
            self.output_int[index] = int(value)

    def write_doubles(self, first: int, values: list[float]) -> None:
        """Output double registers from ``first``."""
        with self._lock:
            for offset, value in enumerate(values):
                self.output_double[first + offset] = float(value)

    def copy(self) -> tuple[list[int], list[float], int, list[int], list[float], int]:
        """A consistent copy: (input ints, input doubles, input bits, output ints, output doubles, output bits)."""
        with self._lock:
            return (
                list(self.input_int),
                list(self.input_double),
                self.input_bits,
                list(self.output_int),
                list(self.output_double),
                self.output_bits,
            )

    def int_write_count(self, index: int) -> int:
        """How many times a client has written ``input_int_register_<index>``."""
        with self._lock:
            return self.int_writes[index]
