"""The campaign's raised rows: a cube placed on top of another, reported as Table 1's rows are."""

import json
import math

import numpy as np
import pytest

from bt_arrange.objects import BAR, CUBE
from bt_arrange.trees import Target
from bt_arrange_sim.experiment import ROW_INJECTORS, ROWS, run_experiment
from bt_arrange_sim.experiment.raised import SUPPORT_TURN_DEG, raised_plan
from bt_arrange_sim.experiment.rows import RAISED_ROWS


def test_the_raised_rows_come_after_every_other_so_no_earlier_row_changes_its_seeds():
    assert ROWS[: ROWS.index("all") + 1][-1] == "all" and ROWS.index("all") == 10
    assert ROWS[11:] == RAISED_ROWS == ("raised", "raised-translation")
    assert ROW_INJECTORS["raised"] == () and ROW_INJECTORS["raised-translation"] == ("pick_translation",)


@pytest.mark.parametrize("kind", [CUBE, BAR])
def test_a_raised_plan_puts_the_target_on_a_turned_support_of_its_type(kind):
    target = Target("red", 0.5, 0.1, 0.3, object_type=kind)
    turns = []
    for seed in range(20):
        support, raised = raised_plan(target, np.random.default_rng(seed))
        assert (support.colour, support.z_m, support.object_type) == ("green", 0.0, kind)
        assert (support.x_m, support.y_m) == (target.x_m, target.y_m)
        assert raised.z_m == pytest.approx(kind.shape.height_m) and raised.planar == target.planar
        turns.append(math.degrees(support.yaw_rad - target.yaw_rad))
    assert max(abs(t) for t in turns) <= SUPPORT_TURN_DEG and np.std(turns) > 5, "turned, by a draw"


def test_a_raised_campaign_places_the_cube_on_the_support_and_reports_it(tmp_path):
    summary = run_experiment(["raised", "raised-translation"], trials=1, seed=0, threshold_mm=1.0, out_dir=tmp_path)
    records = [json.loads(line) for line in (tmp_path / "trials.jsonl").read_text().splitlines()]
    assert sorted(r["row"] for r in records) == ["raised", "raised-translation"]
    for record in records:
        assert record["target_z_mm"] == pytest.approx(50.0) and record["support"] == "green"
        assert record["status"] == "within" and record["pushed_truth_mm"] < 1.0, record
        assert record["support_pushed_truth_mm"] < 1.0, record
        # The support stays put while the cube is placed on it and corrected (the 0.1 mm).
        assert record["support_moved_truth_mm"] < 0.1, record
    translation = next(r for r in records if r["row"] == "raised-translation")
    assert translation["injected"]["pick_translation"]["distance_mm"] > 0, "the error was injected"
    by_row = {row["row"]: row for row in summary}
    assert by_row["raised"]["label"].startswith("Raised target") and by_row["raised"]["trials"] == 1
    assert by_row["raised-translation"]["placed_mean_mm"] is not None
    assert "Raised target: translation error" in (tmp_path / "summary.md").read_text()
