"""The exit-status table: one for every command (``cli_common.EXIT_CODES``), in each ``--help`` and in docs/cli.md.

And the statuses the table promises where they used to be otherwise: a campaign with errored trials
exits 4 (not 2, which means a usage error before anything moved), a calibration that falls short
after the arm moved exits 1.
"""

from __future__ import annotations

import contextlib
import re
from pathlib import Path
from types import SimpleNamespace

import pytest

from bt_arrange import cli
from bt_arrange.cli_common import EXIT_CODES, EXIT_NOT_WITHIN, EXIT_TRIALS_ERRORED, EXIT_USAGE, exit_codes_markdown

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _commands() -> list[str]:
    parser = cli.build_parser()
    (action,) = [a for a in parser._actions if a.dest == "command"]
    return sorted(action.choices)


def test_every_command_s_help_ends_with_the_whole_table(capsys: pytest.CaptureFixture[str]) -> None:
    commands = _commands()
    assert {"run", "experiment", "calibrate", "show", "examples", "info"} <= set(commands)
    for argv in ([], *([command] for command in commands)):
        with pytest.raises(SystemExit) as exit_info:
            cli.main([*argv, "--help"])
        assert exit_info.value.code == 0
        out = capsys.readouterr().out
        table = out[out.index("exit status:") :]
        codes = [int(code) for code in re.findall(r"^  (\d+) ", table, flags=re.MULTILINE)]
        assert codes == [code for code, _ in EXIT_CODES], (argv, table)
        flat = " ".join(table.split())
        for _, meaning in EXIT_CODES:
            assert meaning in flat, (argv, meaning)


def test_the_table_has_a_code_for_errored_trials_other_than_a_usage_error() -> None:
    meanings = dict(EXIT_CODES)
    assert len(meanings) == len(EXIT_CODES), "one meaning per code"
    assert EXIT_TRIALS_ERRORED not in (EXIT_USAGE, EXIT_NOT_WITHIN)
    assert "some trials errored" in meanings[EXIT_TRIALS_ERRORED]
    assert "before anything moves" in meanings[EXIT_USAGE]


def test_docs_cli_holds_the_same_table() -> None:
    assert exit_codes_markdown() in (DOCS / "cli.md").read_text()


def _quick_or_dying_trial(spec):  # noqa: ANN001, ANN202 - a TrialSpec, a record
    if spec.index == 1:
        raise RuntimeError("the trial broke")
    return {
        **spec.record_fields(),
        "target": [0.5, 0.0, 0.0],
        "placed_mm": 2.0,
        "pushed_mm": 0.5,
        "placed_truth_mm": 2.0,
        "pushed_truth_mm": 0.5,
        "pushes": 1,
        "regrasps": 0,
        "status": "within",
    }


def test_a_campaign_with_errored_trials_exits_4_with_its_tables_and_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from bt_arrange_sim.experiment import campaign

    monkeypatch.setattr(campaign, "run_trial", _quick_or_dying_trial)
    code = cli.main(["experiment", "--rows", "system", "--trials", "3", "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code == EXIT_TRIALS_ERRORED == 4
    lines = [line for line in captured.err.splitlines() if line.startswith("bt-arrange:")]
    assert lines == [
        "bt-arrange: error: 1 trial(s) errored (first: system #1: RuntimeError: the trial broke); "
        "the others are recorded: --resume reruns them"
    ]
    assert "| " in captured.out and "1 trial(s) errored" in captured.out, "the table of the others is printed"


def test_a_calibration_that_falls_short_after_the_arm_moved_exits_1(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    outcome = SimpleNamespace(calibration=None, reason="too few views to calibrate: 3 usable", poses=10,
                              unreachable=2, not_seen=5)  # fmt: skip
    run = SimpleNamespace(tick_hooks=[], run=lambda: outcome, elapsed_s=lambda: 0.0)
    backend = SimpleNamespace(name="fake", open_calibration=lambda **options: contextlib.nullcontext(run))
    from bt_arrange import cli_calibrate

    monkeypatch.setattr(cli_calibrate, "backends", SimpleNamespace(load=lambda name=None: backend))
    code = cli.main(["calibrate", "--out", str(tmp_path / "camera.toml")])
    err = capsys.readouterr().err
    assert code == EXIT_NOT_WITHIN
    assert err == (
        "bt-arrange: error: calibration failed: too few views to calibrate: 3 usable "
        "(10 poses: 2 unreachable, 5 with the board not seen)\n"
    )
    assert not (tmp_path / "camera.toml").exists()
