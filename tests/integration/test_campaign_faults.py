"""A campaign on a machine that fails it: SIGKILL mid-write, a worker killed mid-trial, a full disk, a folder removed.

Each time the campaign goes on or ``--resume`` continues it, and the records end identical to an
uninterrupted campaign's (wall times aside): no trial lost, none twice. The trials here are quick
stand-ins (no world: a record computed from the spec) so the faults, not the physics, take the time.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from diskfaults import assert_whole, full_disk  # noqa: F401 - a fixture

import bt_arrange_sim.experiment as experiment
from bt_arrange import cli
from bt_arrange.errors import PlanError, RecordError
from bt_arrange_sim.experiment import CampaignIncompleteError, read_trials, run_experiment
from bt_arrange_sim.experiment.options import TrialSpec
from bt_arrange_sim.experiment.rows import ROWS

TESTS = Path(__file__).resolve().parents[1]
ROOT = TESTS.parent
ROWS_RUN = ["system", "translation"]
TRIALS = 3


def quick_trial(spec: TrialSpec) -> dict:
    """A trial record from its spec alone: the same spec, the same record (the wall time aside)."""
    placed = 1.0 + ROWS.index(spec.row) + spec.index / 10
    return {
        "row": spec.row,
        "trial": spec.index,
        "seed": spec.seed,
        "threshold_mm": spec.threshold_mm,
        "cell": spec.cell,
        "strategy": spec.strategy,
        "object": spec.object_name,
        "target": [0.5, 0.01 * spec.index, 0.0],
        "placed_mm": placed,
        "pushed_mm": placed / 10,
        "placed_truth_mm": placed,
        "pushed_truth_mm": placed / 10,
        "pushes": 1,
        "regrasps": 0,
        "status": "within",
        "wall_seconds": time.perf_counter(),
    }


def killed_at_system_2(spec: TrialSpec) -> dict:
    """A quick trial whose worker process is killed (SIGKILL) while it runs system #2."""
    if (spec.row, spec.index) == ("system", 2):
        os.kill(os.getpid(), signal.SIGKILL)
    return quick_trial(spec)


@pytest.fixture(autouse=True)
def quick(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(experiment.campaign, "run_trial", quick_trial)


def by_trial(folder: Path) -> dict:
    """The records of a folder by (row, trial), wall time aside; a trial recorded twice fails."""
    records = read_trials(folder / "trials.jsonl")
    keys = [(r["row"], r["trial"]) for r in records]
    assert len(keys) == len(set(keys)), "a trial recorded twice"
    return {(r["row"], r["trial"]): {k: v for k, v in r.items() if k != "wall_seconds"} for r in records}


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The uninterrupted campaign's records."""
    folder = tmp_path_factory.mktemp("uninterrupted")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(experiment.campaign, "run_trial", quick_trial)
        run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=folder)
    records = by_trial(folder)
    assert len(records) == len(ROWS_RUN) * TRIALS
    return records


def call(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main(argv)
    return code, out.getvalue(), err.getvalue()


def test_resume_refuses_another_specification_in_one_line_naming_what_differs(tmp_path):
    out = str(tmp_path / "campaign")
    base = ["experiment", "--rows", "system", "--trials", "2", "--seed", "1", "--out", out]
    assert call(base)[0] == 0
    assert json.loads((tmp_path / "campaign" / "specification.json").read_text())["trials"] == 2
    code, _, err = call([*base[:-2], "--trials", "3", "--seed", "2", "--cell", "real", "--out", out, "--resume"])
    assert code == 2
    (line,) = err.splitlines()[-1:]
    assert line == (
        f"bt-arrange: error: --resume: {out} holds another campaign: --trials 2 there, 3 asked; --seed 1 there, "
        "2 asked; --cell ideal there, real asked; give its options, or another --out for a new campaign"
    )
    assert "Traceback" not in err
    # The same specification resumes: nothing is missing, nothing runs again.
    ran: list[tuple[str, int]] = []

    def counted(spec: TrialSpec) -> dict:
        ran.append((spec.row, spec.index))
        return quick_trial(spec)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(experiment.campaign, "run_trial", counted)
        assert call([*base, "--resume"])[0] == 0
        # --resume into a new folder starts the campaign (a job script can always pass it).
        assert call([*base[:-1], str(tmp_path / "new"), "--resume"])[0] == 0
    assert ran == [("system", 0), ("system", 1)]
    with pytest.raises(PlanError, match=r"--rows system there, system,translation asked$|--rows system there"):
        run_experiment(["system", "translation"], 2, 1, 1.0, tmp_path / "campaign", resume=True)
    with pytest.raises(PlanError, match="a folder per combination \\(--thresholds\\) no there, yes asked"):
        run_experiment(["system"], 2, 1, 1.0, tmp_path / "campaign", thresholds="1", resume=True)


def test_a_torn_last_line_is_dropped_and_its_trial_run_again(tmp_path, reference):
    out = tmp_path / "campaign"
    run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out)
    lines = (out / "trials.jsonl").read_text().splitlines()
    # Killed mid-write: three whole lines, then half of the fourth, no newline.
    (out / "trials.jsonl").write_text("\n".join(lines[:3]) + "\n" + lines[3][: len(lines[3]) // 2])
    run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out, resume=True)
    assert by_trial(out) == reference
    assert_whole(out)


def test_a_campaign_killed_with_sigkill_mid_write_resumes_to_the_same_records(tmp_path, reference):
    """The process dies inside the write of the fourth record (half of its bytes on the disk)."""
    out = tmp_path / "campaign"
    script = f"""
import os, signal, sys
sys.path[:0] = [{str(TESTS)!r}, {str(TESTS / "integration")!r}]
import bt_arrange.files as files
import bt_arrange_sim.experiment as experiment
from test_campaign_faults import quick_trial
experiment.campaign.run_trial = quick_trial
appends = []

def write(fd, data):
    if os.readlink(f"/proc/self/fd/{{fd}}").endswith("trials.jsonl"):
        appends.append(fd)
        if len(appends) == 4:
            os.write(fd, bytes(data[: len(data) // 2]))
            os.kill(os.getpid(), signal.SIGKILL)
    return os.write(fd, data)

files._write = write
from pathlib import Path
experiment.run_experiment({ROWS_RUN!r}, {TRIALS}, seed=3, threshold_mm=1.0, out_dir=Path({str(out)!r}))
"""
    killed = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    torn = (out / "trials.jsonl").read_bytes()
    assert not torn.endswith(b"\n") and torn.count(b"\n") == 3, "killed mid-write: three records and half a line"
    code, out_text, err = call(
        ["experiment", "--rows", ",".join(ROWS_RUN), "--trials", str(TRIALS), "--seed", "3"]
        + ["--out", str(out), "--resume"]
    )
    assert code == 0, err
    assert by_trial(out) == reference, "no trial lost, none twice, each the same"
    assert "| 1) System accuracy | 3 |" in out_text
    assert_whole(out)


def test_a_worker_killed_mid_trial_errs_that_trial_only_and_resume_reruns_it(tmp_path, monkeypatch, reference):
    out = tmp_path / "campaign"
    monkeypatch.setattr(experiment.campaign, "run_trial", killed_at_system_2)
    with pytest.raises(CampaignIncompleteError, match=r"^1 trial\(s\) errored \(first: system #2: .*SIGKILL") as raised:
        run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out, workers=2)
    records = read_trials(out / "trials.jsonl")
    errored = [r for r in records if r["status"] == "error"]
    assert [(r["row"], r["trial"]) for r in errored] == [("system", 2)], "the pool started again for the others"
    assert "the worker process running it died (killed by SIGKILL)" in errored[0]["reason"]
    assert len(records) == len(ROWS_RUN) * TRIALS
    summary = {row["row"]: row for row in raised.value.summary}
    assert (summary["system"]["trials"], summary["system"]["errored_trials"]) == (2, 1)
    assert "1 trial(s) errored and are not counted above" in experiment.markdown_table(raised.value.summary)
    monkeypatch.setattr(experiment.campaign, "run_trial", quick_trial)
    run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out, resume=True)
    assert by_trial(out) == reference, "the errored record is replaced by the trial's measurement"


def test_an_exception_in_a_trial_is_its_record_and_the_campaign_goes_on(tmp_path, monkeypatch):
    def broken(spec: TrialSpec) -> dict:
        if spec.index == 1:
            raise ValueError("pybullet said no\nsecond line")
        return quick_trial(spec)

    monkeypatch.setattr(experiment.campaign, "run_trial", broken)
    with pytest.raises(
        CampaignIncompleteError, match=r"^2 trial\(s\) errored \(first: system #1: ValueError: pybullet"
    ):
        run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=tmp_path)
    records = read_trials(tmp_path / "trials.jsonl")
    assert len(records) == 6 and {r["reason"] for r in records if r["status"] == "error"} == {
        "ValueError: pybullet said no"
    }


@pytest.mark.parametrize("budget", [0, 700, 2500, 6000])
def test_a_disk_that_fills_mid_campaign_keeps_whole_records_and_resume_completes_them(
    tmp_path,
    full_disk,  # noqa: F811
    reference,
    budget,
):
    out = tmp_path / "campaign"
    disk = full_disk(budget)
    with pytest.raises(RecordError, match=r"^cannot write .*No space left on device.*the campaign finished") as raised:
        run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out)
    assert "\n" not in str(raised.value)
    summary = {row["row"]: row["trials"] for row in raised.value.result}
    assert summary == {"system": 3, "translation": 3}, "every measurement reaches the user"
    assert_whole(out)
    disk.free()
    run_experiment(ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out, resume=True)
    assert by_trial(out) == reference
    assert {"summary.json", "summary.csv", "summary.md", "fig4.png", "specification.json"} <= set(assert_whole(out))


def test_a_campaign_folder_removed_mid_run_is_one_line_and_the_summary_still_printed(tmp_path):
    out = tmp_path / "campaign"
    thresholds = "0.5,1"

    def remove_after_two(record: dict, done: int, total: int) -> None:
        if done == 2:
            import shutil

            shutil.rmtree(out)

    with pytest.raises(RecordError, match="its folder no longer exists") as raised:
        run_experiment(
            ROWS_RUN, TRIALS, seed=3, threshold_mm=1.0, out_dir=out, thresholds=thresholds, on_trial=remove_after_two
        )
    assert len(raised.value.result) == 4 and all(row["trials"] == 3 for row in raised.value.result)
    assert not out.exists()
