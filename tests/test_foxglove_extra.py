"""Without the ``foxglove`` extra: ``--foxglove`` is one line naming it; a recorded run writes all but ``run.mcap``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: The command line with the Foxglove SDK made unimportable, as on an install without the extra.
WITHOUT_SDK = """
import sys
sys.modules["foxglove"] = None
from bt_arrange import cli
sys.exit(cli.main(sys.argv[1:]))
"""


def without_sdk(*arguments: str) -> subprocess.CompletedProcess[str]:
    tree = str(ROOT / "trees" / "single_cube.py")
    command = [sys.executable, "-c", WITHOUT_SDK, "run", tree, *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=ROOT)


def test_foxglove_without_the_extra_is_one_line_naming_it(tmp_path: Path) -> None:
    result = without_sdk("--foxglove", "--record", str(tmp_path / "r"))
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip().splitlines() == [
        "bt-arrange: error: --foxglove needs the Foxglove SDK: pip install 'bt-arrange[foxglove]'"
    ]


def test_a_recorded_run_without_the_extra_writes_everything_but_the_mcap(tmp_path: Path) -> None:
    result = without_sdk("--record", str(tmp_path))
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if "run.mcap" in line]
    assert lines == ["bt-arrange: run.mcap not written: it needs the Foxglove SDK (pip install 'bt-arrange[foxglove]')"]
    assert (tmp_path / "replay.html").is_file() and (tmp_path / "report.json").is_file()
    assert not (tmp_path / "run.mcap").exists()
    assert "report.json, transitions.jsonl and replay.html" in result.stdout
