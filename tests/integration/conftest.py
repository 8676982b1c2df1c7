"""A recorded four-cube run from the XML tree, shared by the XML round-trip and the replay-page tests."""

import json
from pathlib import Path

import pytest

from bt_arrange import cli

TREES = Path(__file__).resolve().parents[2] / "trees"


@pytest.fixture(scope="session")
def four_cubes_xml_record(tmp_path_factory):
    """``bt-arrange run trees/four_cubes.xml --record DIR --json``: the folder, its report and transition log."""
    folder = tmp_path_factory.mktemp("four_cubes_xml")
    code = cli.main(["run", str(TREES / "four_cubes.xml"), "--seed", "0", "--record", str(folder), "--json"])
    assert code == 0
    transitions = [json.loads(line) for line in (folder / "transitions.jsonl").read_text().splitlines()]
    return {"dir": folder, "report": json.loads((folder / "report.json").read_text()), "transitions": transitions}


@pytest.fixture(scope="session")
def real_cell_calibration(tmp_path_factory):
    """``bt-arrange calibrate --cell real --views 16``: a short calibration of the real cell (16 views), its file."""
    folder = tmp_path_factory.mktemp("calibration")
    out = folder / "camera.toml"
    code = cli.main(["calibrate", "--cell", "real", "--views", "16", "--out", str(out), "--record", str(folder)])
    assert code == 0
    return out
