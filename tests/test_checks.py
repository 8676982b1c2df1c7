"""bt_arrange.checks: one home for "finite / positive / whole"; errors carry their fields."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.checks import finite_number, positive_number, whole_number
from bt_arrange.errors import BtArrangeError, GeometryError, OutOfRangeError, PlanError, UnreachableError
from bt_arrange.geometry import Pose
from bt_arrange.motion import JointLimits, nearest_symmetric_yaw


@pytest.mark.parametrize(
    ("check", "args", "kwargs", "message"),
    [
        (positive_number, ("threshold_mm", 0, "mm"), {}, "threshold_mm=0 must be a positive number of millimetres"),
        (
            positive_number,
            ("threshold_mm", math.inf, "mm"),
            {},
            "threshold_mm=inf must be a finite number of millimetres",
        ),
        (
            positive_number,
            ("time limit", -1.0, "s"),
            {"style": "unit"},
            "time limit -1.0 s must be a positive number of seconds",
        ),
        (
            positive_number,
            ("threshold_mm", True, "mm"),
            {},
            "threshold_mm=True must be a positive number of millimetres",
        ),
        (whole_number, ("max_pushes", 2.5), {}, "max_pushes=2.5 must be a whole number, 0 or more"),
        (whole_number, ("--workers", 0, 1), {"style": "unit"}, "--workers 0 must be a whole number, 1 or more"),
        (
            finite_number,
            ("x_m", math.nan),
            {"where": "target 1 (red): "},
            "target 1 (red): x_m=nan is not a finite number",
        ),
    ],
)
def test_a_bad_number_is_one_plan_error_naming_the_field(check, args, kwargs, message) -> None:
    with pytest.raises(PlanError) as caught:
        check(*args, **kwargs)
    assert str(caught.value) == message
    assert caught.value.field == args[0]
    assert caught.value.value is args[1] or caught.value.value == args[1] or math.isnan(caught.value.value)


def test_good_numbers_come_back_typed() -> None:
    assert positive_number("threshold_mm", 1, "mm") == 1.0 and isinstance(positive_number("x", 2, "m"), float)
    assert whole_number("seed", np.int64(3)) == 3
    assert finite_number("yaw_rad", -0.5) == -0.5
    assert positive_number("threshold", math.inf, "mm", finite=False) == math.inf


def test_the_error_class_can_be_chosen() -> None:
    with pytest.raises(OutOfRangeError, match="is not a finite number"):
        finite_number("max_m", "a", error=OutOfRangeError)


def test_geometry_and_kinematics_raise_the_family_and_stay_value_errors() -> None:
    with pytest.raises(GeometryError) as caught:
        Pose([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0])
    assert isinstance(caught.value, (BtArrangeError, ValueError)) and caught.value.field == "pose"
    with pytest.raises(ValueError, match="must be positive"):
        nearest_symmetric_yaw(0.1, 0.0, 0.0)


def test_an_unreachable_joint_carries_the_joint_its_value_and_its_bound() -> None:
    limits = JointLimits()
    with pytest.raises(UnreachableError) as caught:
        limits.check_positions([0.0, 0.0, 0.0, 0.0, 0.0, 100.0])
    error = caught.value
    assert error.joint == "wrist_3_joint" and error.value == 100.0
    assert error.bound == (limits.lower_rad[5], limits.upper_rad[5])


def test_display_error_lives_with_the_others() -> None:
    from bt_arrange import display, errors

    assert display.DisplayError is errors.DisplayError
