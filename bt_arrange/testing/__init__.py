"""Test your behaviours without a simulator: fake devices, a context over them, and a tick loop.

A test of ``Push`` in a user's project::

    from py_trees.common import Status

    from bt_arrange.behaviours import Inspect, Push, keys
    from bt_arrange.geometry import PlanarPose
    from bt_arrange.testing import make_context, part, tick_until_done


    def test_a_push_moves_towards_the_target(bt_blackboard):
        context = make_context(parts=[part("red", 0.503, 0.0)])
        bt_blackboard.set(keys.target("red"), PlanarPose(0.5, 0.0, 0.0))
        assert tick_until_done(Inspect("inspect red", "red"), context).status == Status.SUCCESS
        assert tick_until_done(Push("push red", "red"), context).status == Status.SUCCESS

- :func:`part` describes a part on the table that the fake camera renders;
- :func:`make_context` returns a :class:`~bt_arrange.behaviours.Context` over a :class:`FakeArm`
  (perfect tracking, every command recorded), a :class:`FakeGripper`, a :class:`FakeCamera`
  (synthetic top-camera frames of the parts) and a :class:`FakeClock`, with the real motion
  planner and part detector; :func:`fake_arm` and its siblings give the devices back;
- :func:`tick_until_done` ticks a behaviour on the fake clock as the runner ticks a tree and
  returns a :class:`Run` (``status``, ``feedback``, every ``Tick``).

The fakes move nothing they do not hold: a push's commands are recorded, the camera's parts stay
where the test put them (``fake_camera(context).parts`` may be changed between ticks).

Installing bt-arrange registers the pytest plugin :mod:`bt_arrange.testing.pytest_plugin`: its
``bt_blackboard`` fixture clears py_trees' blackboard before and after a test (and gives the
``Blackboard`` to set keys on), and it keeps the dependencies' warnings out of the test output.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from bt_arrange.testing.devices import (
        CAMERA_HEIGHT_PX,
        CAMERA_WIDTH_PX,
        CONTROL_PERIOD_S,
        GRIPPER_SPEED_M_S,
        ArmCommand,
        FakeArm,
        FakeCamera,
        FakeClock,
        FakeGripper,
        GripperCommand,
        SyntheticPart,
    )
    from bt_arrange.testing.scene import fake_arm, fake_camera, fake_clock, fake_gripper, make_context, part
    from bt_arrange.testing.ticking import Run, Tick, brake_until_idle, tick_until_done

#: Where each name lives: the kit is imported when a name is first asked for, so that pytest, which
#: loads the plugin (``bt_arrange.testing.pytest_plugin``) in every run, imports no robot for it.
_MODULES = {
    **dict.fromkeys(
        (
            "CAMERA_HEIGHT_PX",
            "CAMERA_WIDTH_PX",
            "CONTROL_PERIOD_S",
            "GRIPPER_SPEED_M_S",
            "ArmCommand",
            "FakeArm",
            "FakeCamera",
            "FakeClock",
            "FakeGripper",
            "GripperCommand",
            "SyntheticPart",
        ),
        "bt_arrange.testing.devices",
    ),
    **dict.fromkeys(
        ("fake_arm", "fake_camera", "fake_clock", "fake_gripper", "make_context", "part"), "bt_arrange.testing.scene"
    ),
    **dict.fromkeys(("Run", "Tick", "brake_until_idle", "tick_until_done"), "bt_arrange.testing.ticking"),
}


def __getattr__(name: str) -> Any:
    """A name of the kit, imported from its module when first asked for."""
    module = _MODULES.get(name)
    if module is None:
        raise AttributeError(f"module 'bt_arrange.testing' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_MODULES])


__all__ = [
    "CAMERA_HEIGHT_PX",
    "CAMERA_WIDTH_PX",
    "CONTROL_PERIOD_S",
    "GRIPPER_SPEED_M_S",
    "ArmCommand",
    "FakeArm",
    "FakeCamera",
    "FakeClock",
    "FakeGripper",
    "GripperCommand",
    "Run",
    "SyntheticPart",
    "Tick",
    "brake_until_idle",
    "fake_arm",
    "fake_camera",
    "fake_clock",
    "fake_gripper",
    "make_context",
    "part",
    "tick_until_done",
]
