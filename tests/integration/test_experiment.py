"""The experiment command on a few trials: files, resuming, refusing another experiment's folder, rows, sweeps."""

import json
import math
from concurrent.futures import Executor, Future

import pytest

from bt_arrange.errors import PlanError
from bt_arrange_sim.experiment import (
    ROW_INJECTORS,
    ROW_LABELS,
    ROWS,
    CampaignIncompleteError,
    combinations,
    markdown_table,
    parse_rows,
    parse_thresholds,
    read_trials,
    row_injectors,
    run_campaign,
    run_experiment,
    summarise,
)
from bt_arrange_sim.injection import INJECTORS, grasp_fits


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
        *("sticking", "release", "tilt", "all", "raised", "raised-translation"),
    }
    # Every error once: pick_translation_xy is another reading of the translation error, not another error.
    assert set(ROW_INJECTORS["all"]) == set(INJECTORS) - {"pick_translation_xy"}, "the all row injects every error"
    for row in ROWS:
        assert [i.name for i in row_injectors(row)] == list(ROW_INJECTORS[row])
    assert all(len(ROW_INJECTORS[row]) == 1 for row in ROWS[4 : ROWS.index("all")])


def test_thresholds_and_the_campaign_product_are_checked():
    assert parse_thresholds("0.29, 0.5,1,2") == [0.29, 0.5, 1.0, 2.0]
    with pytest.raises(PlanError, match=r"--thresholds 0.05: .*below 0.07 mm"):
        parse_thresholds("0.05,1")
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


def test_a_trial_that_does_not_come_back_is_recorded_as_an_error_and_a_resume_reruns_it(tmp_path):
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

    errored = r"^1 trial\(s\) errored \(first: system #1: RuntimeError: worker died\).*--resume"
    with pytest.raises(CampaignIncompleteError, match=errored) as raised:
        run_experiment(["system"], trials=2, seed=4, threshold_mm=1.0, out_dir=tmp_path, executor=DyingWorker())
    records = sorted(read_trials(tmp_path / "trials.jsonl"), key=lambda r: r["trial"])
    assert [(r["trial"], r["status"]) for r in records] == [(0, "within"), (1, "error")]
    assert records[1]["reason"] == "RuntimeError: worker died"
    (row,) = raised.value.summary
    assert (row["trials"], row["errored_trials"]) == (1, 1), "the errored trial is counted apart"
    run_experiment(["system"], trials=2, seed=4, threshold_mm=1.0, out_dir=tmp_path, resume=True)
    records = sorted(read_trials(tmp_path / "trials.jsonl"), key=lambda r: r["trial"])
    assert [(r["trial"], r["status"]) for r in records] == [(0, "within"), (1, "within")], "the error line is gone"


def _quick_trial(spec):
    """A trial record without a world: enough for the campaign's files and summaries."""
    return {
        "row": spec.row,
        "trial": spec.index,
        "seed": spec.seed,
        "threshold_mm": spec.threshold_mm,
        "cell": spec.cell,
        "strategy": spec.strategy,
        "object": spec.object_name,
        "target": [0.5, 0.0, 0.0],
        "placed_mm": 2.0,
        "pushed_mm": 0.5,
        "placed_truth_mm": 2.0,
        "pushed_truth_mm": 0.5,
        "pushes": 1,
        "regrasps": 0,
        "status": "within",
    }


def test_cells_are_one_more_list_of_the_campaign_product(tmp_path, monkeypatch):
    import bt_arrange_sim.experiment as experiment

    combos = combinations([0.5, 1.0], ["ideal", "real"], strategy="learned")
    assert [(c.threshold_mm, c.cell, c.strategy) for c in combos] == [
        (0.5, "ideal", "learned"),
        (0.5, "real", "learned"),
        (1.0, "ideal", "learned"),
        (1.0, "real", "learned"),
    ]
    assert [c.folder for c in combos[:2]] == ["threshold-0.5mm", "threshold-0.5mm-cell-real"]
    assert combos[1].spec("system", 3, 7).cell == "real"
    assert not combos[1].owns({"threshold_mm": 0.5, "strategy": "learned"}), "a record without a cell is ideal"
    assert experiment.parse_cells(" ideal, real ,ideal") == ["ideal", "real"]
    with pytest.raises(PlanError, match="--cell lab: unknown cell 'lab'"):
        experiment.parse_cells("ideal,lab")

    monkeypatch.setattr(experiment.campaign, "run_trial", _quick_trial)
    summary = run_experiment(["system"], trials=2, seed=1, threshold_mm=1.0, out_dir=tmp_path, cell="ideal,real")
    assert [(r["cell"], r["folder"], r["trials"]) for r in summary] == [
        ("ideal", "threshold-1mm", 2),
        ("real", "threshold-1mm-cell-real", 2),
    ]
    assert {r["cell"] for r in read_trials(tmp_path / "threshold-1mm-cell-real" / "trials.jsonl")} == {"real"}
    assert len(json.loads((tmp_path / "campaign.json").read_text())) == 2
    table = experiment.markdown_table(summary)
    assert "## threshold 1 mm, cell real, strategy paper (threshold-1mm-cell-real)" in table
    # One threshold and one cell: straight into the folder, as before campaigns.
    flat = run_experiment(["system"], trials=1, seed=1, threshold_mm=1.0, out_dir=tmp_path / "flat", cell="real")
    assert "folder" not in flat[0] and (tmp_path / "flat" / "trials.jsonl").exists()
    with pytest.raises(PlanError, match="strategy learned"):
        run_experiment(["system"], 1, 1, 1.0, tmp_path / "flat", cell="real", strategy="learned")


def test_the_executor_option_opens_dask_through_the_executors_module(tmp_path, monkeypatch):
    import contextlib

    import bt_arrange_sim.executors as executors
    import bt_arrange_sim.experiment as experiment

    class InProcess(Executor):
        def submit(self, fn, /, *args, **kwargs):
            future = Future()
            future.set_result(fn(*args, **kwargs))
            return future

    opened = []

    @contextlib.contextmanager
    def fake_open(kind, workers, scheduler):
        opened.append((kind, workers, scheduler))
        yield InProcess()

    monkeypatch.setattr(experiment.campaign, "run_trial", _quick_trial)
    monkeypatch.setattr(executors, "open_executor", fake_open)
    run_experiment(
        ["system"], 1, 2, 1.0, tmp_path, executor="dask", workers=3, scheduler="tcp://10.0.0.5:8786", thresholds="1,2"
    )
    assert opened == [("dask", 3, "tcp://10.0.0.5:8786")]
    assert (tmp_path / "threshold-2mm" / "trials.jsonl").exists()
    with pytest.raises(PlanError, match="--scheduler needs --executor dask"):
        experiment.check_options(scheduler="tcp://10.0.0.5:8786")


def test_grasp_feasibility_of_a_bar_uses_its_size_not_the_cubes_edge():
    # A bar (40 mm closed on, 80 mm along the pads) square to an 85 mm opening: 22.5 mm across.
    bar = {"edge_m": 0.04, "open_width_m": 0.085, "along_pads_m": 0.08, "symmetry_rad": math.pi}
    assert grasp_fits(0.0225, 0.0, 0.0, (0.0, 0.0, 0.0), **bar)
    assert not grasp_fits(0.0235, 0.0, 0.0, (0.0, 0.0, 0.0), **bar)
    assert not grasp_fits(0.0225, 0.0, 0.0, (0.0, 0.0, 0.0), 0.05, 0.085), "a cube leaves 17.5 mm"
    # Along the pads the bar is held while their centre stays on it: up to 40 mm, not a cube's 25.
    assert grasp_fits(0.0, 0.039, 0.0, (0.0, 0.0, 0.0), **bar)
    assert not grasp_fits(0.0, 0.041, 0.0, (0.0, 0.0, 0.0), **bar)
    # Turned 10 degrees it spans 20 cos + 40 sin = 26.6 mm each side across the closing axis.
    turn = math.radians(10.0)
    half_extent_m = 0.02 * math.cos(turn) + 0.04 * math.sin(turn)
    assert grasp_fits(0.0425 - half_extent_m - 1e-4, 0.0, turn, (0.0, 0.0, 0.0), **bar)
    assert not grasp_fits(0.0425 - half_extent_m + 1e-4, 0.0, turn, (0.0, 0.0, 0.0), **bar)


def test_types_are_one_more_list_of_the_campaign_product(tmp_path, monkeypatch):
    import bt_arrange_sim.experiment as experiment

    combos = combinations([1.0], ["ideal", "real"], object_names=["cube", "bar"])
    assert [(c.cell, c.object_name) for c in combos] == [
        ("ideal", "cube"),
        ("ideal", "bar"),
        ("real", "cube"),
        ("real", "bar"),
    ]
    assert [c.folder for c in combos] == [
        "threshold-1mm",
        "threshold-1mm-object-bar",
        "threshold-1mm-cell-real",
        "threshold-1mm-cell-real-object-bar",
    ]
    assert combos[1].spec("system", 0, 7).object_name == "bar"
    assert experiment.parse_objects(" cube, bar ,cube") == ["cube", "bar"]

    monkeypatch.setattr(experiment.campaign, "run_trial", _quick_trial)
    summary = run_experiment(["system"], trials=2, seed=1, threshold_mm=1.0, out_dir=tmp_path, object_name="cube,bar")
    assert [(r["object"], r["folder"], r["trials"]) for r in summary] == [
        ("cube", "threshold-1mm", 2),
        ("bar", "threshold-1mm-object-bar", 2),
    ]
    assert {r["object"] for r in read_trials(tmp_path / "threshold-1mm-object-bar" / "trials.jsonl")} == {"bar"}
    assert [r["object"] for r in json.loads((tmp_path / "campaign.json").read_text())] == ["cube", "bar"]
    assert (tmp_path / "thresholds.png").stat().st_size > 0
    assert "## threshold 1 mm, cell ideal, strategy paper, object bar (threshold-1mm-object-bar)" in (
        experiment.markdown_table(summary)
    )
    # One type in a list is a flat experiment, as before types were a list.
    flat = run_experiment(
        ["system"], trials=1, seed=1, threshold_mm=1.0, out_dir=tmp_path / "flat", object_name=["bar"]
    )
    assert "folder" not in flat[0] and (tmp_path / "flat" / "trials.jsonl").exists()


def test_an_experiment_with_a_bar_runs_its_trials_with_the_bar_and_names_it(tmp_path):
    summary = run_experiment(["translation"], trials=1, seed=3, threshold_mm=1.0, out_dir=tmp_path, object_name="bar")
    (record,) = read_trials(tmp_path / "trials.jsonl")
    assert record["object"] == "bar"
    assert record["injected"]["pick_translation"]["fired"]
    assert record["status"] == "within", record["reason"]
    assert summary[0]["trials"] == 1
    with pytest.raises(PlanError, match="holds trials of another experiment"):
        run_experiment(["translation"], trials=1, seed=3, threshold_mm=1.0, out_dir=tmp_path)
    with pytest.raises(PlanError, match=r"^--object 'beam': unknown object type 'beam'"):
        run_experiment(["system"], trials=1, seed=3, threshold_mm=1.0, out_dir=tmp_path / "x", object_name="beam")


def test_sigterm_stops_the_pool_keeps_the_finished_trials_and_exits_143(tmp_path):
    """A cluster's job limit sends SIGTERM: the command and its pool workers end, what finished stays."""
    import contextlib
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "campaign"
    command = [sys.executable, "-m", "bt_arrange.cli", "experiment", "--rows", "system", "--trials", "40"]
    process = subprocess.Popen(
        [*command, "--workers", "2", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )

    def kill_the_group() -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)

    try:
        deadline = time.monotonic() + 120
        while not read_trials(out / "trials.jsonl") and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.2)
        assert process.poll() is None, "the campaign ended before it could be terminated"
        process.send_signal(signal.SIGTERM)
        # Workers left running would hold the pipes open: communicate would time out.
        _, stderr = process.communicate(timeout=60)
    except BaseException:
        kill_the_group()
        raise
    assert process.returncode == 143, stderr
    assert stderr.strip().splitlines()[-1] == "bt-arrange: terminated; what was logged so far is kept"
    assert "Traceback" not in stderr
    finished = read_trials(out / "trials.jsonl")
    assert 1 <= len(finished) < 40
    # No worker of the pool is left in the command's process group.
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.killpg(process.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        kill_the_group()
        pytest.fail("pool workers outlived the terminated command")


def test_the_summary_counts_regrasped_trials_and_trials_squared_in_the_grasp():
    base = {"row": "orientation", "placed_mm": 5.0, "pushed_mm": 0.2, "pushed_truth_mm": 0.2, "pushes": 1}
    records = [
        {**base, "status": "within", "regrasps": 0, "squarings": 1},
        {**base, "status": "within", "regrasps": 1, "squarings": 1},
        {**base, "status": "within", "regrasps": 0, "squarings": 0},
        {**base, "status": "within"},  # a record written before squarings were counted
    ]
    (row,) = summarise(records, ["orientation"])
    assert (row["regrasp_trials"], row["squared_trials"]) == (1, 2)
    assert "| regrasped trials | squared in the grasp |" in markdown_table([row])
    assert "| 1 | 2 |" in markdown_table([row])
