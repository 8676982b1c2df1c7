"""The experiment command on a few trials: files, resuming, refusing another experiment's folder, rows, sweeps."""

import json
from concurrent.futures import Executor, Future

import pytest

from bt_arrange.errors import PlanError
from bt_arrange_sim.experiment import (
    ROW_INJECTORS,
    ROW_LABELS,
    ROWS,
    CampaignIncompleteError,
    combinations,
    parse_rows,
    parse_thresholds,
    read_trials,
    row_injectors,
    run_campaign,
    run_experiment,
)
from bt_arrange_sim.injection import INJECTORS


def test_an_experiment_writes_its_trials_summaries_and_figure_and_resumes(tmp_path):
    summary = run_experiment(["system", "translation"], trials=2, seed=5, threshold_mm=1.0, out_dir=tmp_path, workers=2)
    names = {p.name for p in tmp_path.iterdir()}
    assert {"trials.jsonl", "summary.json", "summary.csv", "summary.md", "fig4.png"} <= names
    records = read_trials(tmp_path / "trials.jsonl")
    assert sorted((r["row"], r["trial"]) for r in records) == [
        ("system", 0),
        ("system", 1),
        ("translation", 0),
        ("translation", 1),
    ]
    by_row = {s["row"]: s for s in summary}
    assert by_row["system"]["paper_placed_mean_mm"] == 0.47
    assert by_row["translation"]["placed_mean_mm"] > 2.0, "the injected translation error bites"
    for s in summary:
        assert s["success_rate"] == 1.0
        assert s["pushed_mean_mm"] < 1.0
    translation = [r for r in records if r["row"] == "translation"]
    assert all("pick_translation" in r["injected"] for r in translation)
    assert all(r["pushed_truth_mm"] is not None and r["placed_truth_mm"] is not None for r in records)

    # A rerun with one more trial per row runs only the two missing trials.
    calls = []
    run_experiment(
        ["system", "translation"],
        trials=3,
        seed=5,
        threshold_mm=1.0,
        out_dir=tmp_path,
        on_trial=lambda record, done, total: calls.append((record["row"], record["trial"], done, total)),
    )
    assert sorted(c[:2] for c in calls) == [("system", 2), ("translation", 2)]
    assert [c[2:] for c in calls] == [(5, 6), (6, 6)]
    assert len(read_trials(tmp_path / "trials.jsonl")) == 6
    assert json.loads((tmp_path / "summary.json").read_text())[0]["trials"] == 3


def test_a_folder_of_another_experiment_is_refused(tmp_path):
    (tmp_path / "trials.jsonl").write_text(
        json.dumps({"row": "system", "trial": 0, "seed": 1, "threshold_mm": 1.0}) + "\n"
    )
    with pytest.raises(PlanError, match="holds trials of another experiment"):
        run_experiment(["system"], trials=1, seed=2, threshold_mm=1.0, out_dir=tmp_path)


def test_a_line_cut_short_by_an_interruption_is_ignored(tmp_path):
    path = tmp_path / "trials.jsonl"
    path.write_text(json.dumps({"row": "system", "trial": 0}) + "\n" + '{"row": "sys')
    assert read_trials(path) == [{"row": "system", "trial": 0}]


def test_rows_are_checked_and_row_4_is_labelled_as_the_substitute():
    assert parse_rows("system, orientation") == ["system", "orientation"]
    with pytest.raises(PlanError, match="unknown row 'learned'; the rows are system, translation"):
        parse_rows("system,learned")
    assert "substitute for Berscheid et al." in ROW_LABELS["grasp-estimator"]


def test_every_error_of_section_3_is_a_row_with_its_injectors():
    assert ROWS[:4] == ("system", "translation", "orientation", "grasp-estimator"), "Table 1's seeds stay put"
    assert set(ROWS) == {
        *("system", "translation", "orientation", "grasp-estimator", "perception", "surface", "slip"),
        *("sticking", "release", "tilt", "all"),
    }
    assert set(ROW_INJECTORS["all"]) == set(INJECTORS), "the all row injects every error"
    for row in ROWS:
        assert [i.name for i in row_injectors(row)] == list(ROW_INJECTORS[row])
    assert all(len(ROW_INJECTORS[row]) == 1 for row in ROWS[4:-1])


def test_thresholds_and_the_campaign_product_are_checked():
    assert parse_thresholds("0.25, 0.5,1,2") == [0.25, 0.5, 1.0, 2.0]
    with pytest.raises(PlanError, match="'x' is not a number"):
        parse_thresholds("1,x")
    with pytest.raises(PlanError, match="-1 must be a positive"):
        parse_thresholds("-1")
    with pytest.raises(PlanError, match="empty"):
        parse_thresholds(" , ")
    combos = combinations([0.5, 1, 0.5])
    assert [c.threshold_mm for c in combos] == [0.5, 1.0]
    assert [c.folder for c in combos] == ["threshold-0.5mm", "threshold-1mm"]


def test_a_threshold_sweep_writes_a_folder_per_combination_and_the_threshold_figure(tmp_path):
    result = run_campaign(["system"], trials=1, seed=3, combos=combinations([0.5, 2.0]), out_dir=tmp_path)
    assert not result.lost
    for folder in ("threshold-0.5mm", "threshold-2mm"):
        assert {"trials.jsonl", "summary.json", "summary.md", "fig4.png"} <= {
            p.name for p in (tmp_path / folder).iterdir()
        }
    assert (tmp_path / "thresholds.png").stat().st_size > 0
    campaign = json.loads((tmp_path / "campaign.json").read_text())
    assert sorted(r["threshold_mm"] for r in campaign) == [0.5, 2.0]
    # The same trial (same start, same target) under both thresholds: only the threshold differs.
    (a,), (b,) = (read_trials(tmp_path / f / "trials.jsonl") for f in ("threshold-0.5mm", "threshold-2mm"))
    assert a["target"] == b["target"] and a["placed_mm"] == b["placed_mm"]


def test_a_trial_that_does_not_come_back_is_reported_and_a_rerun_completes_it(tmp_path):
    class DyingWorker(Executor):
        """Runs trials in this process, but the worker dies on the second one."""

        def __init__(self):
            self.calls = 0

        def submit(self, fn, /, *args, **kwargs):
            future = Future()
            self.calls += 1
            if self.calls == 2:
                future.set_exception(RuntimeError("worker died"))
            else:
                future.set_result(fn(*args, **kwargs))
            return future

    with pytest.raises(CampaignIncompleteError, match=r"1 trial\(s\) did not finish .*worker died.*rerun"):
        run_experiment(["system"], trials=2, seed=4, threshold_mm=1.0, out_dir=tmp_path, executor=DyingWorker())
    assert [r["trial"] for r in read_trials(tmp_path / "trials.jsonl")] == [0], "what finished is kept"
    run_experiment(["system"], trials=2, seed=4, threshold_mm=1.0, out_dir=tmp_path)
    assert sorted(r["trial"] for r in read_trials(tmp_path / "trials.jsonl")) == [0, 1]
