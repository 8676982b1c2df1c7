"""The experiment command on a few trials: files, resuming, refusing another experiment's folder."""

import json

import pytest

from bt_arrange.errors import PlanError
from bt_arrange_sim.experiment import ROW_LABELS, parse_rows, read_trials, run_experiment


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
