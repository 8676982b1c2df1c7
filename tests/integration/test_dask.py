"""A campaign on a real Dask LocalCluster of two workers gives the local executor's records."""

import pytest

from bt_arrange.errors import PlanError
from bt_arrange_sim import executors
from bt_arrange_sim.executors import check_choice, open_executor
from bt_arrange_sim.experiment import read_trials, run_experiment

pytest.importorskip("dask.distributed", reason="the [cluster] extra (dask[distributed]) is not installed")

#: Wall time differs from run to run and machine to machine; everything else must not.
VARYING = ("wall_seconds",)


def _by_trial(path):
    return {(r["row"], r["trial"]): {k: v for k, v in r.items() if k not in VARYING} for r in read_trials(path)}


def test_dask_local_cluster_of_two_workers_gives_the_same_records_as_the_local_executor(tmp_path):
    rows, trials = ["translation"], 2
    run_experiment(rows, trials, seed=11, threshold_mm=1.0, out_dir=tmp_path / "local")
    # A campaign killed mid-write: its first record, then half of the second.
    first, second = (tmp_path / "local" / "trials.jsonl").read_text().splitlines()
    (tmp_path / "resumed").mkdir()
    (tmp_path / "resumed" / "trials.jsonl").write_text(first + "\n" + second[: len(second) // 2])
    with open_executor("dask", workers=2) as executor:
        assert executor is not None
        assert len(executor._client.scheduler_info()["workers"]) == 2, "two real worker processes"
        run_experiment(rows, trials, seed=11, threshold_mm=1.0, out_dir=tmp_path / "dask", executor=executor)
        run_experiment(rows, trials, 11, 1.0, tmp_path / "resumed", executor=executor, resume=True)
    local, dask = _by_trial(tmp_path / "local" / "trials.jsonl"), _by_trial(tmp_path / "dask" / "trials.jsonl")
    assert sorted(local) == [("translation", 0), ("translation", 1)]
    assert dask == local
    resumed = (tmp_path / "resumed" / "trials.jsonl").read_text().splitlines()
    assert len(resumed) == 2 and _by_trial(tmp_path / "resumed" / "trials.jsonl") == local, "resumed on Dask"


def test_executor_choices_are_checked_before_anything_starts():
    with pytest.raises(PlanError, match="--scheduler needs --executor dask"):
        check_choice("local", 1, "tcp://127.0.0.1:8786")
    with pytest.raises(PlanError, match="unknown executor 'slurm'"):
        check_choice("slurm", 1, None)
    with pytest.raises(PlanError, match="--workers must be at least 1"):
        check_choice("dask", 0, None)
    with open_executor("local", workers=1) as executor:
        assert executor is None, "one local worker: trials run in this process"


def test_an_unreachable_scheduler_is_a_one_line_error(monkeypatch):
    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT_S", 1.0)
    with pytest.raises(PlanError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        with open_executor("dask", scheduler="tcp://127.0.0.1:9"):
            pass
