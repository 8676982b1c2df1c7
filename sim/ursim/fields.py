"""The RTDE field names a CB3 controller knows, their types, and how each type is packed on the wire.

The names and types are the RTDE guide's table (as Universal Robots' client library lists them,
``DataPackage::g_type_list``); a name not here is answered ``NOT_FOUND``, as a real controller
does. Every value travels big-endian (network order).
"""

from __future__ import annotations

import struct

#: The ``struct`` format of each RTDE type (without the byte-order mark).
TYPE_FORMATS: dict[str, str] = {
    "BOOL": "?",
    "UINT8": "B",
    "UINT32": "I",
    "UINT64": "Q",
    "INT32": "i",
    "DOUBLE": "d",
    "VECTOR3D": "3d",
    "VECTOR6D": "6d",
    "VECTOR6INT32": "6i",
    "VECTOR6UINT32": "6I",
}

#: How many values a field of each type carries (1 for a scalar).
TYPE_LENGTHS: dict[str, int] = {"VECTOR3D": 3, "VECTOR6D": 6, "VECTOR6INT32": 6, "VECTOR6UINT32": 6}

#: The number of general-purpose registers of each kind (0..47: the lower range 0..23 and the upper 24..47).
REGISTER_COUNT = 48

_OUTPUT_FIELDS: dict[str, str] = {
    "timestamp": "DOUBLE",
    "target_q": "VECTOR6D",
    "target_qd": "VECTOR6D",
    "target_qdd": "VECTOR6D",
    "target_current": "VECTOR6D",
    "target_moment": "VECTOR6D",
    "actual_q": "VECTOR6D",
    "actual_qd": "VECTOR6D",
    "actual_current": "VECTOR6D",
    "joint_control_output": "VECTOR6D",
    "actual_TCP_pose": "VECTOR6D",
    "actual_TCP_speed": "VECTOR6D",
    "actual_TCP_force": "VECTOR6D",
    "target_TCP_pose": "VECTOR6D",
    "target_TCP_speed": "VECTOR6D",
    "actual_digital_input_bits": "UINT64",
    "joint_temperatures": "VECTOR6D",
    "actual_execution_time": "DOUBLE",
    "robot_mode": "INT32",
    "joint_mode": "VECTOR6INT32",
    "safety_mode": "INT32",
    "actual_tool_accelerometer": "VECTOR3D",
    "speed_scaling": "DOUBLE",
    "target_speed_fraction": "DOUBLE",
    "actual_momentum": "DOUBLE",
    "actual_main_voltage": "DOUBLE",
    "actual_robot_voltage": "DOUBLE",
    "actual_robot_current": "DOUBLE",
    "actual_joint_voltage": "VECTOR6D",
    "actual_digital_output_bits": "UINT64",
    "runtime_state": "UINT32",
    "elbow_position": "VECTOR3D",
    "elbow_velocity": "VECTOR3D",
    "robot_status_bits": "UINT32",
    "safety_status_bits": "UINT32",
    "analog_io_types": "UINT32",
    "standard_analog_input0": "DOUBLE",
    "standard_analog_input1": "DOUBLE",
    "standard_analog_output0": "DOUBLE",
    "standard_analog_output1": "DOUBLE",
    "io_current": "DOUBLE",
    "euromap67_input_bits": "UINT32",
    "euromap67_output_bits": "UINT32",
    "euromap67_24V_voltage": "DOUBLE",
    "euromap67_24V_current": "DOUBLE",
    "tool_mode": "UINT32",
    "tool_analog_input_types": "UINT32",
    "tool_analog_input0": "DOUBLE",
    "tool_analog_input1": "DOUBLE",
    "tool_output_voltage": "INT32",
    "tool_output_current": "DOUBLE",
    "tool_temperature": "DOUBLE",
    "tcp_force_scalar": "DOUBLE",
    "output_bit_registers0_to_31": "UINT32",
    "output_bit_registers32_to_63": "UINT32",
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
    "payload": "DOUBLE",
    "payload_cog": "VECTOR3D",
    "payload_inertia": "VECTOR6D",
    "script_control_line": "UINT32",
    "tcp_offset": "VECTOR6D",
}

#: What a client may write (``setup inputs``): the registers, the speed slider and the outputs.
_INPUT_FIELDS: dict[str, str] = {
    "speed_slider_mask": "UINT32",
    "speed_slider_fraction": "DOUBLE",
    "standard_digital_output_mask": "UINT8",
    "standard_digital_output": "UINT8",
    "configurable_digital_output_mask": "UINT8",
    "configurable_digital_output": "UINT8",
    "tool_digital_output_mask": "UINT8",
    "tool_digital_output": "UINT8",
    "standard_analog_output_mask": "UINT8",
    "standard_analog_output_type": "UINT8",
    "standard_analog_output_0": "DOUBLE",
    "standard_analog_output_1": "DOUBLE",
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
    "external_force_torque": "VECTOR6D",
}

for _index in range(REGISTER_COUNT):
    for _direction in ("input", "output"):
        _OUTPUT_FIELDS[f"{_direction}_int_register_{_index}"] = "INT32"
        _OUTPUT_FIELDS[f"{_direction}_double_register_{_index}"] = "DOUBLE"
    _INPUT_FIELDS[f"input_int_register_{_index}"] = "INT32"
    _INPUT_FIELDS[f"input_double_register_{_index}"] = "DOUBLE"
for _index in range(64, 128):
    # The single bit registers are the upper range's (64..127); 0..63 travel as the two UINT32 words.
    _OUTPUT_FIELDS[f"output_bit_register_{_index}"] = "BOOL"
    _OUTPUT_FIELDS[f"input_bit_register_{_index}"] = "BOOL"
    _INPUT_FIELDS[f"input_bit_register_{_index}"] = "BOOL"

OUTPUT_FIELDS: dict[str, str] = _OUTPUT_FIELDS
INPUT_FIELDS: dict[str, str] = _INPUT_FIELDS

#: The placeholder type of an unknown name, in a setup's reply.
NOT_FOUND = "NOT_FOUND"
#: The placeholder type of an input another client already writes.
IN_USE = "IN_USE"


def recipe_struct(types: list[str]) -> struct.Struct:
    """The big-endian ``struct`` of a data package's fields of ``types`` (the recipe id byte first)."""
    return struct.Struct(">B" + "".join(TYPE_FORMATS[t] for t in types))


def flatten(values: list[object], types: list[str]) -> list[object]:
    """The fields' values as ``struct.pack`` takes them: each vector's elements in turn."""
    flat: list[object] = []
    for value, kind in zip(values, types, strict=True):
        if kind in TYPE_LENGTHS:
            flat.extend(value)  # type: ignore[arg-type]
        else:
            flat.append(value)
    return flat


def unflatten(flat: tuple[object, ...], types: list[str]) -> list[object]:
    """The inverse of ``flatten``: one value (a list for a vector) per field."""
    values: list[object] = []
    position = 0
    for kind in types:
        length = TYPE_LENGTHS.get(kind)
        if length is None:
            values.append(flat[position])
            position += 1
        else:
            values.append(list(flat[position : position + length]))
            position += length
    return values
