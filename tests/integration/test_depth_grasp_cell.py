"""The depth-only grasp estimator (substitute for Berscheid et al.) in the pybullet cell.

Its errors are measured on rendered depth frames against the simulator's ground truth, and a
one-cube tree with the estimator in Detect's place (the paper's Table 1, row 4) must still end
within 1 mm after pushing.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from bt_arrange.behaviours import Inspect, MoveHome
from bt_arrange.behaviours.grasp_estimation import EstimateGraspFromDepth
from bt_arrange.geometry import fold_yaw
from bt_arrange.perception.depth_grasp import DepthGraspEstimator
from bt_arrange.trees import Arrangement, Target, by_depth, correction, set_target, transfer
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.runs import SimulatedRun
from bt_arrange_sim.scenes import scatter

COLOURS = ["red", "green", "blue", "yellow"]
#: Measured on 160 cubes of 40 scattered scenes: mean 0.9 mm, p95 1.5 mm, max 1.9 mm, yaw max 2.0 deg.
MAX_ERROR_MM = 4.0
MAX_YAW_ERROR_DEG = 3.0


@pytest.mark.parametrize("seed", [11, 12])
def test_estimates_on_rendered_frames_are_millimetres_off(seed, record_property):
    starts = scatter(COLOURS, seed)
    estimator = DepthGraspEstimator()
    rng = np.random.default_rng(seed)
    with WorkCell() as cell:
        cell.add_parts(starts)
        cell.settle(0.2)
        frame = cell.camera.capture(with_depth=True)
        view = estimator.sensor_view(frame, rng)
        errors_mm, yaw_errors_deg = [], []
        for start in starts:
            # The colour-blind hint: where the cube was put on the table (not the simulator's truth).
            estimate = estimator.estimate_view(view, near_xy_m=(start.x_m, start.y_m), name=start.colour)
            assert estimate.found, estimate.reason
            assert estimate.planar is not None
            true_x, true_y, true_yaw = cell.part_planar_truth(start.colour)
            errors_mm.append(math.hypot(estimate.planar.x_m - true_x, estimate.planar.y_m - true_y) * 1000)
            yaw_errors_deg.append(abs(math.degrees(fold_yaw(estimate.planar.yaw_rad - true_yaw))))
    summary = (
        f"depth grasp error over {len(errors_mm)} cubes: mean {np.mean(errors_mm):.2f} mm, "
        f"max {max(errors_mm):.2f} mm; yaw max {max(yaw_errors_deg):.2f} deg"
    )
    print(summary)
    record_property("depth_grasp_error_mm", [round(e, 3) for e in errors_mm])
    assert max(errors_mm) < MAX_ERROR_MM, summary
    assert max(yaw_errors_deg) < MAX_YAW_ERROR_DEG, summary
    # Errors of a substitute with realistic sensor errors: millimetres, not hundredths.
    assert np.mean(errors_mm) > 0.1, summary


def test_the_estimate_does_not_depend_on_the_colour_image():
    with WorkCell() as cell:
        cell.add_parts(scatter(["red"], 5))
        cell.settle(0.2)
        frame = cell.camera.capture(with_depth=True)
    blind = dataclasses.replace(frame, rgb=np.zeros_like(frame.rgb))
    estimator = DepthGraspEstimator()
    seen = estimator.estimate(frame, rng=np.random.default_rng(1))
    unseen = estimator.estimate(blind, rng=np.random.default_rng(1))
    assert seen.found and unseen.found
    assert seen.pose_world is not None and unseen.pose_world is not None
    np.testing.assert_array_equal(seen.pose_world.position_m, unseen.pose_world.position_m)


def row_four_tree(target: Target, seed: int) -> Arrangement:
    """Algorithm 1 for one cube with the depth estimator before picking, as ``trees.arrange_one`` builds it."""
    obj = target.obj
    return Arrangement(
        "row 4: depth grasp substitute",
        [
            set_target(target),
            transfer(target, locate=by_depth(seed)),
            Inspect(f"inspect {obj} after placing", obj, target.colour, after_placing=True),
            correction(target),  # a free part, to the default 1 mm and 1 deg
            MoveHome("park the arm"),
        ],
        [target],
        threshold_mm=1.0,
    )


#: Scenes whose start, near the edge of the view, gave a placed offset above 1 mm (measured: 1.5 and
#: 1.1 mm), so that the correction pushes; most scenes place within 1 mm and need no push.
@pytest.mark.parametrize("seed", [0, 1])
def test_a_tree_with_the_depth_estimator_ends_within_a_millimetre(seed, record_property):
    target = Target("red", 0.52, -0.12, 0.4)
    root = row_four_tree(target, seed)
    estimators = [node for node in root.iterate() if isinstance(node, EstimateGraspFromDepth)]
    assert len(estimators) == 1
    with SimulatedRun(root, scatter(["red"], seed, avoid=[target])) as run:
        report = run.run()
    (outcome,) = report.objects
    print(
        f"row 4 substitute: placed {outcome.placed_offset_mm} mm, final {outcome.final_offset_mm} mm, "
        f"{outcome.pushes} pushes"
    )
    record_property("placed_offset_mm", outcome.placed_offset_mm)
    assert report.tree_status == "SUCCESS", outcome.reason
    assert outcome.status == "within", outcome.reason
    assert outcome.placed_offset_mm is not None
    assert outcome.final_offset_mm is not None and outcome.final_offset_mm < 1.0
    assert outcome.final_offset_truth_mm < 1.0
    assert estimators[0].found is not None
