"""Detect and Inspect for a prism part: the same behaviours, the outline detector behind the seam."""

from __future__ import annotations

import math

import numpy as np
import pytest
from behaviour_helpers import read, set_up, write
from py_trees.common import Status

from bt_arrange.behaviours import Detect, Inspect
from bt_arrange.geometry import PlanarPose, Pose, fold_yaw
from bt_arrange.objects import ObjectType
from bt_arrange.perception.synthetic import SyntheticPrism
from bt_arrange.shapes import Prism
from bt_arrange.testing import fake_camera, make_context, tick_until_done

#: The brief's non-convex fragment, 20 mm tall.
FRAGMENT = ObjectType(
    "fragment",
    shape=Prism.from_outline(np.array([[0, 0], [45, 4], [60, 30], [35, 28], [30, 50], [5, 40]]) / 1000, 0.02),
)


def test_detect_writes_a_prism_parts_pose(clock) -> None:
    context = make_context(clock=clock)
    assert isinstance(FRAGMENT.shape, Prism)
    fake_camera(context).parts.append(SyntheticPrism("red", 0.55, -0.12, 2.5, FRAGMENT.shape))
    behaviour = Detect("detect the fragment", "fragment", colour="red", object_type=FRAGMENT)
    run = tick_until_done(set_up(behaviour, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    pose = read("/fragment/pose")
    assert isinstance(pose, Pose)
    assert 1000 * math.hypot(pose.x_m - 0.55, pose.y_m + 0.12) < 0.2
    assert math.degrees(fold_yaw(pose.yaw_rad - 2.5, 2 * math.pi)) == pytest.approx(0.0, abs=0.2)


def test_inspect_measures_a_prism_part_in_a_window_around_its_target(clock) -> None:
    context = make_context(clock=clock)
    assert isinstance(FRAGMENT.shape, Prism)
    camera = fake_camera(context)
    camera.parts.append(SyntheticPrism("blue", 0.452, 0.099, math.radians(31.0), FRAGMENT.shape))
    write({"/fragment/target": PlanarPose(0.45, 0.1, math.radians(30.0))})
    inspect = Inspect("inspect the fragment", "fragment", colour="blue", after_placing=True, object_type=FRAGMENT)
    run = tick_until_done(set_up(inspect, context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert read("/fragment/offset_mm") == pytest.approx(math.hypot(2.0, 1.0), abs=0.1)
    assert read("/fragment/yaw_error_deg") == pytest.approx(1.0, abs=0.1)
    window = camera.windows[-1]
    assert window is not None and window.width_px < 300, "measured in a window around the target"
