"""The bt-arrange command line: exit codes, one-line errors, the JSON report."""

import io
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from bt_arrange import cli, cli_run

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
    assert_one_line_error(code, err, "out of reach", "x 1200 mm")


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
    assert set(first) == {"time_s", "behaviour", "kind", "old", "new", "feedback", "node_id", "obj"}


def test_run_exits_1_and_says_so_on_the_last_line_when_an_object_is_not_within(capsys):
    # The time limit stops the run before the cube is placed: the object failed, and says why.
    code, out, _ = run_cli(capsys, "run", TREES / "single_cube.py", "--time-limit-s", "2")
    assert code == 1
    lines = out.strip().splitlines()
    assert "failed: stopped after 2 s of world time" in lines[1]
    assert lines[-1].startswith(
        "single_cube.py: 0 of 1 objects within 1 mm and 1 deg; stopped at the time limit after 2.0 s"
    )


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
        (("--executor", "dask", "--scheduler", " "), ("--scheduler is empty",)),
        (("--thresholds", "0.5,0.05"), ("--thresholds 0.05", "below 0.07 mm")),
        (("--cell", "ideal,lab"), ("--cell lab", "unknown cell 'lab'")),
        (("--cell", "real", "--strategy", "learned", "--thresholds", ","), ("--thresholds is empty",)),
    ],
)
def test_experiment_options_are_checked_before_any_trial_runs(capsys, tmp_path, argv, fragments):
    code, _, err = run_cli(capsys, "experiment", "--out", tmp_path / "out", *argv)
    assert_one_line_error(code, err, *fragments)
    assert not (tmp_path / "out").exists(), "nothing started"


def test_the_last_line_counts_the_objects_within_and_the_exit_status_agrees(capsys) -> None:  # item 2
    from bt_arrange_sim.pybullet.runs import ObjectOutcome, SimulationReport

    def outcome(name: str, status: str) -> ObjectOutcome:
        return ObjectOutcome(name, (0.5, 0.0, 0.0), 0.5, 0.5, 0.5, 0.5, 0, status, "" if status == "within" else "x")

    args = cli.build_parser().parse_args(["run", "four.py"])
    for statuses, expected, missed in [
        (["within"] * 4, "4 of 4 objects within 1 mm", ""),
        (
            ["within", "within", "within", "failed"],
            "3 of 4 objects within 1 mm",
            "; not within: 3 failed at 0.50 mm (x)",
        ),
        (
            ["failed", "outside"],
            "0 of 2 objects within 1 mm",
            "; not within: 0 failed at 0.50 mm (x); 1 outside at 0.50 mm (x)",
        ),
    ]:
        report = SimulationReport(
            [outcome(str(i), s) for i, s in enumerate(statuses)], "SUCCESS", 1.0, 10.0, 1.0, False
        )
        cli_run._print_report(report, args)
        last = capsys.readouterr().out.strip().splitlines()[-1]
        assert last.startswith(f"four.py: {expected} after 10.0 s of world time")
        assert "SUCCESS" not in last, "the tree's status is never the verdict beside the parts"
        assert last.endswith(missed) if missed else "not within" not in last
        assert report.all_within_threshold == (statuses == ["within"] * 4)
        assert report.to_dict()["objects_within"] == statuses.count("within")


def test_json_gives_the_target_yaw_in_degrees_too() -> None:  # item 9
    from bt_arrange_sim.pybullet.runs import ObjectOutcome, SimulationReport

    red = ObjectOutcome("red", (0.5, 0.0, math.pi / 6), 0.5, 0.5, 0.5, 0.5, 0, "within")
    (entry,) = SimulationReport([red], "SUCCESS", 1.0, 1.0, 1.0, False).to_dict()["objects"]
    assert entry["target"][2] == pytest.approx(math.pi / 6)
    assert entry["target_yaw_deg"] == pytest.approx(30.0)
    assert entry["target_mm"] == [500.0, 0.0]  # a plan's units beside the metres of "target"


def test_the_table_speaks_mm_and_degrees_and_the_last_line_names_the_yaw_threshold(capsys) -> None:
    from bt_arrange_sim.pybullet.runs import ObjectOutcome, SimulationReport

    red = ObjectOutcome("red", (0.45, -0.05, math.pi / 6), 0.5, 0.5, 0.5, 0.5, 0, "within")
    report = SimulationReport([red], "SUCCESS", 1.0, 10.0, 1.0, False, yaw_threshold_deg=1.0)
    cli_run._print_report(report, cli.build_parser().parse_args(["run", "plan.toml"]))
    lines = capsys.readouterr().out.strip().splitlines()
    assert "target x, y (mm), yaw (deg)" in lines[0]
    assert "450.0, -50.0, 30.0" in lines[1]
    assert lines[-1].startswith("plan.toml: 1 of 1 objects within 1 mm and 1 deg after 10.0 s of world time")


def test_show_text_into_a_file_names_the_file(capsys, tmp_path) -> None:  # item 6
    out_file = tmp_path / "tree.txt"
    code, out, _ = run_cli(capsys, "show", TREES / "single_cube.py", "--out", out_file)
    assert code == 0
    assert out == f"wrote {out_file}\n"
    assert "pick red" in out_file.read_text()


class ClosedPipe(io.StringIO):
    """stdout whose reader went away (``| head``): every write raises, as a pipe would."""

    def __init__(self, fd: int) -> None:
        super().__init__()
        self.fd = fd

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self) -> int:
        return self.fd


def test_a_closed_pipe_ends_quietly(capsys, monkeypatch) -> None:  # item 4
    read_end, write_end = os.pipe()
    try:
        monkeypatch.setattr(sys, "stdout", ClosedPipe(write_end))
        code = cli.main(["show", str(TREES / "four_cubes.py")])
    finally:
        os.close(read_end)
        os.close(write_end)
    assert code == cli.EXIT_BROKEN_PIPE
    assert capsys.readouterr().err == ""


def test_help_lists_the_exit_codes_and_the_experiment_rows(capsys) -> None:  # item 9
    from bt_arrange_sim.experiment import ROWS

    for argv, expected in [
        (["--help"], ["exit status:", "0    every object ended within", "2    a usage", "130", "141"]),
        (["run", "--help"], ["exit status:", "1    an object did not"]),
        (["experiment", "--help"], ["rows (--rows):", *ROWS]),
    ]:
        with pytest.raises(SystemExit) as exit_info:
            cli.main(argv)
        assert exit_info.value.code == 0
        out = capsys.readouterr().out
        for fragment in expected:
            assert fragment in out, (argv, fragment)


def test_building_the_help_starts_no_simulator() -> None:
    code = "import sys; from bt_arrange import cli; cli.build_parser(); print('pybullet' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert result.stdout.strip() == "False"


def test_a_work_cell_starts_without_pybullet_s_banner_on_stderr() -> None:  # item 9
    code = "from bt_arrange_sim.pybullet.cell import WorkCell; WorkCell().close()"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert result.stderr == ""
