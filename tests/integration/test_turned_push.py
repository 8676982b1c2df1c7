"""The paper's correction (camera, tree, pushes) on a cube left turned beside its target, in the pybullet cell.

Table 1's translation trial 62 was placed 27.6 mm off and 9.4 deg turned; the paper's opening
left the cube's leading corner between the pads, where it wedged: 5.2 mm off after ten pushes.
"""

from __future__ import annotations

import math

import pytest

from bt_arrange.behaviours import Inspect, MoveHome
from bt_arrange.trees import Arrangement, Target, correction, set_target
from bt_arrange_sim.pybullet.runs import SimulatedRun
from bt_arrange_sim.scenes import PartStart


def correct_only(target: Target) -> Arrangement:
    """Look at a cube already on the table, then push it home (no pick and place)."""
    obj = target.obj
    return Arrangement(
        "correct a turned cube",
        [
            set_target(target),
            Inspect(f"inspect {obj} after placing", obj, target.colour, after_placing=True),
            correction(target),  # placed free: 1 mm, 1 deg, 10 pushes
            MoveHome("park the arm"),
        ],
        [target],
        threshold_mm=1.0,
    )


@pytest.mark.parametrize("turn_deg", [12.5, -12.5])
def test_a_cube_25_mm_off_and_turned_12_degrees_is_pushed_home_within_a_millimetre(turn_deg):
    target = Target("red", 0.52, -0.15, -0.1)
    # 25 mm beyond the target along its x axis, 3 mm along its y, turned from its yaw.
    along_m, across_m = 0.025, 0.003
    c, s = math.cos(target.yaw_rad), math.sin(target.yaw_rad)
    start = PartStart(
        "red",
        target.x_m + c * along_m - s * across_m,
        target.y_m + s * along_m + c * across_m,
        target.yaw_rad + math.radians(turn_deg),
    )
    with SimulatedRun(correct_only(target), [start]) as run:
        report = run.run()
    (outcome,) = report.objects
    print(
        f"turned {turn_deg:+.1f} deg: placed {outcome.placed_offset_mm} mm, "
        f"yaw error {outcome.placed_yaw_error_deg} deg; "
        f"final {outcome.final_offset_mm} mm after {outcome.pushes} pushes"
    )
    assert outcome.placed_offset_mm is not None and outcome.placed_offset_mm > 20.0
    assert outcome.placed_yaw_error_deg is not None and abs(outcome.placed_yaw_error_deg) > 11.0
    assert outcome.status == "within", outcome.reason
    assert outcome.final_offset_mm is not None and outcome.final_offset_mm < 1.0
    assert outcome.final_offset_truth_mm < 1.0
