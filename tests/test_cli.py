"""The bt-arrange command line: exit codes, one-line errors, the JSON report."""

import json
import textwrap
from pathlib import Path

import pytest

from bt_arrange import cli

TREES = Path(__file__).resolve().parents[1] / "trees"


def write_tree(tmp_path, body: str) -> Path:
    path = tmp_path / "tree.py"
    path.write_text(textwrap.dedent(body))
    return path


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code, err, *fragments):
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("bt-arrange: error: ")
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in lines[0]


def test_missing_tree_file(capsys, tmp_path):
    code, _, err = run_cli(capsys, "run", tmp_path / "nope.py")
    assert_one_line_error(code, err, "nope.py not found")


def test_tree_file_with_a_syntax_error(capsys, tmp_path):
    code, _, err = run_cli(capsys, "run", write_tree(tmp_path, "def create_root(:\n"))
    assert_one_line_error(code, err, "syntax error at line 1")


def test_tree_file_without_create_root(capsys, tmp_path):
    code, _, err = run_cli(capsys, "show", write_tree(tmp_path, "X = 1\n"))
    assert_one_line_error(code, err, "defines no create_root()")


def test_plan_with_an_unknown_colour(capsys, tmp_path):
    path = write_tree(
        tmp_path,
        """
        from bt_arrange.trees import Target, arrangement
        def create_root():
            return arrangement([Target("purple", 0.5, 0.0)])
        """,
    )
    code, _, err = run_cli(capsys, "show", path)
    assert_one_line_error(code, err, "unknown colour 'purple'", "red")


def test_plan_with_a_target_out_of_reach(capsys, tmp_path):
    path = write_tree(
        tmp_path,
        """
        from bt_arrange.trees import Target, arrangement
        def create_root():
            return arrangement([Target("red", 1.2, 0.0)])
        """,
    )
    code, _, err = run_cli(capsys, "run", path)
    assert_one_line_error(code, err, "out of reach", "1.200")


def test_run_needs_a_scene(capsys, tmp_path):
    path = write_tree(
        tmp_path,
        """
        from bt_arrange.trees import Target, arrangement
        def create_root():
            return arrangement([Target("red", 0.5, 0.0)])
        """,
    )
    code, _, err = run_cli(capsys, "run", path)
    assert_one_line_error(code, err, "create_scene(seed)")


@pytest.mark.parametrize("value", ["0", "-1", "nan"])
def test_threshold_must_be_positive(capsys, value):
    code, _, err = run_cli(capsys, "run", TREES / "single_cube.py", "--threshold-mm", value)
    assert_one_line_error(code, err, "--threshold-mm")


def test_unknown_option_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["run", str(TREES / "single_cube.py"), "--bogus"])
    assert exit_info.value.code == 2


def test_run_json_reports_every_object(capsys, tmp_path):
    code, out, _ = run_cli(capsys, "run", TREES / "single_cube.py", "--json", "--record", tmp_path / "rec")
    assert code == 0
    report = json.loads(out)
    (red,) = report["objects"]
    assert set(red) >= {"name", "target", "placed_offset_mm", "final_offset_mm", "final_offset_truth_mm", "pushes"}
    assert red["status"] == "within"
    assert red["final_offset_mm"] < 1.0
    assert report["sim_seconds"] > 0 and report["wall_seconds"] > 0
    recorded = {p.name for p in (tmp_path / "rec").iterdir()}
    assert {"before_picking.png", "after_placing_red.png", "after_pushing.png", "transitions.jsonl"} <= recorded
    first = json.loads((tmp_path / "rec" / "transitions.jsonl").read_text().splitlines()[0])
    assert set(first) == {"time_s", "behaviour", "kind", "old", "new", "feedback"}


def test_run_exits_1_when_an_object_does_not_end_within_the_threshold(capsys, tmp_path):
    # No pushes allowed and a threshold below anything the camera reads.
    path = write_tree(
        tmp_path,
        """
        from bt_arrange.trees import Target, arrangement
        from bt_arrange_sim.scenes import scatter
        TARGETS = [Target("red", 0.5, 0.0)]
        def create_root(threshold_mm=0.001):
            return arrangement(TARGETS, threshold_mm=threshold_mm, max_pushes=0)
        def create_scene(seed):
            return scatter(["red"], seed, avoid=TARGETS)
        """,
    )
    code, out, _ = run_cli(capsys, "run", path)
    assert code == 1
    assert "outside" in out
    assert "after 0 correction(s)" in out


def test_show_prints_the_tree_as_text(capsys):
    code, out, _ = run_cli(capsys, "show", TREES / "four_cubes.py")
    assert code == 0
    for name in ("arrange red", "detect red", "pick red", "while holding red", "correct yellow to 1 mm"):
        assert name in out


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (("--threshold-mm", "1", "--thresholds", "0.5,1"), ("--threshold-mm or --thresholds",)),
        (("--thresholds", "0.5,abc"), ("--thresholds", "'abc' is not a number")),
        (("--scheduler", "tcp://127.0.0.1:8786"), ("--scheduler needs --executor dask",)),
        (("--rows", "system,wobble"), ("unknown row 'wobble'", "tilt, all")),
        (("--executor", "dask", "--workers", "0"), ("--workers must be at least 1",)),
        (("--trials", "0"), ("--trials must be at least 1",)),
    ],
)
def test_experiment_options_are_checked_before_any_trial_runs(capsys, tmp_path, argv, fragments):
    code, _, err = run_cli(capsys, "experiment", "--out", tmp_path / "out", *argv)
    assert_one_line_error(code, err, *fragments)
    assert not (tmp_path / "out").exists(), "nothing started"
