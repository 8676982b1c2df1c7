"""A scene for a behaviour's test: the parts the fake camera sees, and a ``Context`` over the fake devices."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TypeVar, cast

from bt_arrange.behaviours import Context
from bt_arrange.geometry import FloatArray
from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, CartesianLimits, JointLimits, MotionPlanner
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception import PartDetector
from bt_arrange.perception.synthetic import SyntheticPrism
from bt_arrange.robot import GRIPPER_MAX_WIDTH_M, Robot
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import Prism
from bt_arrange.testing.devices import FakeArm, FakeCamera, FakeClock, FakeGripper, SyntheticPart


def part(
    colour: str, x_m: float, y_m: float, yaw_rad: float = 0.0, object_type: ObjectType | None = None
) -> SyntheticPart:
    """A part resting on the table, as the fake camera renders it: centre ``(x_m, y_m)`` (m), turned by ``yaw_rad``.

    ``colour`` is one of the cell's colours (``red``, ``green``, ``blue``, ``yellow``); ``object_type``
    (default the paper's 5 cm cube, :data:`bt_arrange.objects.CUBE`) gives its shape: any prism,
    drawn at its area centroid.
    """
    # The drawing reads only the top face's outline and height, which every shape has (a box is a prism).
    return SyntheticPrism(colour, x_m, y_m, yaw_rad, cast(Prism, (object_type or CUBE).shape))


def make_context(
    parts: Iterable[SyntheticPart] = (),
    *,
    clock: FakeClock | None = None,
    q: Sequence[float] | FloatArray = DEFAULT_HOME_Q,
    gripper_width_m: float = GRIPPER_MAX_WIDTH_M,
    object_width_m: float | None = None,
    stuck_gripper: bool = False,
    settings: ManipulationSettings | None = None,
) -> Context:
    """A ``Context`` over fake devices, with the real planner (placo and ruckig) and the real detector.

    ``parts`` (made by :func:`part`) are what the camera sees; the arm starts at joints ``q`` (home:
    out of the camera's view), the gripper open to ``gripper_width_m``. A close of the gripper stops
    at ``object_width_m`` (the width of the part held between the pads; None: nothing, it closes to
    0); ``stuck_gripper`` makes the fingers never report standing still. ``clock`` (default a new
    one at 0 s) is the world time of every device. The devices are reached with :func:`fake_arm`,
    :func:`fake_gripper`, :func:`fake_camera` and :func:`fake_clock`.
    """
    clock = clock or FakeClock()
    kinematics = ArmKinematics()
    arm = FakeArm(clock, q, kinematics)
    gripper = FakeGripper(clock, gripper_width_m, object_width_m, stuck=stuck_gripper)
    camera = FakeCamera(clock, parts, arm=arm)
    planner = MotionPlanner(kinematics, JointLimits(), CartesianLimits(), arm.control_period_s)
    return Context(
        robot=Robot(arm=arm, gripper=gripper, camera=camera, clock=clock),
        planner=planner,
        detector=PartDetector(),
        settings=settings or ManipulationSettings(),
    )


def fake_arm(context: Context) -> FakeArm:
    """The context's arm, as the fake it is (its ``commands``)."""
    return _fake(context.robot.arm, FakeArm, "arm")


def fake_gripper(context: Context) -> FakeGripper:
    """The context's gripper, as the fake it is (its ``commands``, ``slip()``, ``wedge()``)."""
    return _fake(context.robot.gripper, FakeGripper, "gripper")


def fake_camera(context: Context) -> FakeCamera:
    """The context's camera, as the fake it is (its ``parts``, ``captures`` and ``windows``)."""
    return _fake(context.robot.camera, FakeCamera, "camera")


def fake_clock(context: Context) -> FakeClock:
    """The context's clock, as the fake it is (``advance(dt_s)``)."""
    return _fake(context.robot.clock, FakeClock, "clock")


D = TypeVar("D")


def _fake(device: object, fake: type[D], role: str) -> D:
    """``device`` as the fake it must be, or a ``TypeError`` naming the device the context has instead."""
    if not isinstance(device, fake):
        raise TypeError(
            f"the context's {role} is a {type(device).__name__}, not a {fake.__name__} (make_context makes one)"
        )
    return device
