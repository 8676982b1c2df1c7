"""1) Perception (the paper's Sec. 3, Fig. 2a): the detection before the pick is off."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from py_trees.common import Status

from bt_arrange.behaviours import Detect, keys
from bt_arrange.geometry import Pose, rotation_z
from bt_arrange.runner import Transition
from bt_arrange_sim.injection.framework import MAX_DRAWS, Injector, Parameter, _deg, _mm, _sample, read_blackboard

if TYPE_CHECKING:
    from bt_arrange_sim.injection.framework import InjectableRun


class PerceptionOffset(Injector):
    """Object detection and pose estimation error (Fig. 2a): the detection before the pick is off.

    From ``attach`` until ``detect <obj>`` first succeeds, the camera renders from a pose moved by
    up to ``max_m`` (uniform in a disc, world x and y) and turned by up to ``max_deg`` about the
    vertical (uniform, default 0), while its frames still report the calibrated pose: the robot
    measures the cube about (dx, dy) off (and turned by -dyaw about the point below the camera),
    so it picks off-centre. The camera is put back right after that detection: inspection is exact.
    The draw is resampled while the estimate it causes would put a pad on the cube.

    Note: the camera is displaced from ``attach``; in a tree that handles other objects before
    ``obj``, their detections and inspections see the displaced camera too. ``record()`` lists
    them under ``"also_seen_by"``; attach this injector to the first object handled.

    Record: ``camera_dx_mm``, ``camera_dy_mm``, ``camera_dyaw_deg`` (the displacement);
    ``estimate_error_dx_mm``, ``estimate_error_dy_mm``, ``estimate_error_dyaw_deg`` (the measured
    minus the true pose of that detection, for the log).
    """

    name = "perception_offset"
    PARAMETERS = (
        Parameter("max_m", 0.010, 0.0, 0.0175, "m"),
        Parameter("max_deg", 0.0, 0.0, 10.0, "deg", low_inclusive=True),
    )

    def __init__(self, max_m: float = 0.010, max_deg: float = 0.0) -> None:
        super().__init__(max_m=max_m, max_deg=max_deg)

    def _attach(self, run: InjectableRun, obj: str) -> None:
        camera = run.cell.camera
        cx, cy = camera.pose_world.x_m, camera.pose_world.y_m
        truth = run.cell.part_pose_truth(obj)
        max_m, max_rad = self.params["max_m"], math.radians(self.params["max_deg"])

        def draw() -> tuple[float, float, float]:
            radius = max_m * math.sqrt(self.rng.uniform())
            direction = self.rng.uniform(-math.pi, math.pi)
            dyaw = self.rng.uniform(-max_rad, max_rad) if max_rad > 0 else 0.0
            return radius * math.cos(direction), radius * math.sin(direction), dyaw

        def fits(offset: tuple[float, float, float]) -> bool:
            dx, dy, dyaw = offset
            # What the calibrated camera will report for the cube (see SimCamera.set_render_offset).
            seen = rotation_z(-dyaw)[:2, :2] @ np.array([truth.x_m - cx - dx, truth.y_m - cy - dy]) + (cx, cy)
            return self._fits(
                truth.x_m, truth.y_m, truth.yaw_rad, (seen[0], seen[1], self._closing_yaw(truth.yaw_rad - dyaw))
            )

        drawn = _sample(draw, fits)
        (dx, dy, dyaw), draws = drawn or ((0.0, 0.0, 0.0), MAX_DRAWS)
        camera.set_render_offset(dx, dy, dyaw)
        self.details.update(
            camera_dx_mm=_mm(dx), camera_dy_mm=_mm(dy), camera_dyaw_deg=_deg(dyaw), draws=draws, also_seen_by=[]
        )
        if drawn is None:
            self.details["skipped"] = "no draw keeps the pads off the cube"

        def hook(transition: Transition) -> None:
            if self.fired or transition.new != Status.SUCCESS.value:
                return
            if not self._is_detection(transition):
                if isinstance(run.node(transition), Detect):  # another look through the displaced camera
                    self.details["also_seen_by"].append(transition.behaviour)
                return
            self.fired = True
            camera.set_render_offset()
            now = run.cell.part_pose_truth(obj)
            measured = read_blackboard(keys.key(obj, keys.POSE))
            self.details["time_s"] = round(transition.time_s, 4)
            if isinstance(measured, Pose):
                dyaw_seen = (measured.yaw_rad - now.yaw_rad + math.pi / 4) % (math.pi / 2) - math.pi / 4
                self.details.update(
                    estimate_error_dx_mm=_mm(measured.x_m - now.x_m),
                    estimate_error_dy_mm=_mm(measured.y_m - now.y_m),
                    estimate_error_dyaw_deg=_deg(dyaw_seen),
                )

        run.transition_hooks.append(hook)
