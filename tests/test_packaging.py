"""What a user gets from ``pip install .`` and from the console script."""

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from bt_arrange import cli

ROOT = Path(__file__).resolve().parents[1]


def test_the_wheel_ships_the_cell_under_the_projects_name_with_its_robot(tmp_path):
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            str(ROOT),
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(tmp_path),
        ],
        check=True,
        capture_output=True,
    )
    (wheel,) = tmp_path.glob("bt_arrange-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "bt_arrange_sim/pybullet/cell.py" in names and "bt_arrange_sim/config.py" in names, "both layers"
    assert "bt_arrange_sim/experiment/campaign.py" in names, "the experiment package (pyproject's packages)"
    assert "bt_arrange/descriptions/ur5_2f85.urdf" in names
    assert "bt_arrange/py.typed" in names
    sources = {path.relative_to(ROOT).as_posix() for path in (ROOT / "bt_arrange").rglob("*.py")}
    assert sources <= names, f"modules left out of the wheel (pyproject's packages): {sorted(sources - names)}"
    assert not any(name.startswith("sim/") for name in names), "no generic top-level 'sim' package"


def test_cli_info_starts_a_headless_cell(capsys):
    assert cli.main(["info"]) == 0
    out = capsys.readouterr().out
    assert "headless work cell: ok" in out
    assert "pybullet" in out


def test_cli_without_a_command_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main([])
    assert exit_info.value.code == 2
    assert "required" in capsys.readouterr().err


def test_every_package_of_the_framework_is_listed_in_pyproject():
    """A package left out of ``packages`` is missing from the wheel (a stale build/ hides that from the test above)."""
    tomllib = pytest.importorskip("tomllib" if sys.version_info >= (3, 11) else "tomli")
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(init.parent.relative_to(ROOT).parts) for init in (ROOT / "bt_arrange").rglob("__init__.py")}
    assert found <= listed, f"add to pyproject's packages: {sorted(found - listed)}"
