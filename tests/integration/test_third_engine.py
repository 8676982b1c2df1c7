"""A third engine is one backend and its name: the campaign runs its trials with no edit of its own."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_arrange import backends
from bt_arrange.errors import PlanError
from bt_arrange_sim.pybullet.backend import SimBackend


class _Twin(SimBackend):
    """An engine the campaign has never heard of (here: pybullet's cell again, under another name)."""

    name = "twin"
    ideal_cell_only = "the twin engine has the ideal cell only"


@pytest.fixture
def twin():  # noqa: ANN201
    backends.register("twin", _Twin)
    yield _Twin()
    backends._registered.pop("twin")


def test_a_registered_engine_runs_the_campaigns_trials_and_names_itself_in_the_records(twin, tmp_path: Path) -> None:
    twin.experiment.run_experiment(["system"], 1, 0, 1.0, tmp_path)
    (record,) = [json.loads(line) for line in (tmp_path / "trials.jsonl").read_text().splitlines()]
    assert record["engine"] == "twin" and record["status"] == "within"
    assert json.loads((tmp_path / "specification.json").read_text())["engine"] == "twin"


def test_a_registered_engines_refusals_come_before_anything_runs(twin, tmp_path: Path) -> None:
    with pytest.raises(PlanError, match="^--cell real: the twin engine has the ideal cell only"):
        twin.experiment.run_experiment(["system"], 1, 0, 1.0, tmp_path / "out", cell="real")
    assert not (tmp_path / "out").exists()


def test_an_engine_that_is_no_backend_is_refused_in_one_line(tmp_path: Path) -> None:
    from bt_arrange_sim.experiment import run_experiment

    with pytest.raises(PlanError, match="^engine 'nowhere': no backend 'nowhere'"):
        run_experiment(["system"], 1, 0, 1.0, tmp_path, engine="nowhere")
