"""The testing kit as a user gets it: the built wheel alone, in a project outside the repository.

The wheel is built (as ``test_packaging`` builds it, without build isolation) and installed with
``--no-deps`` into a fresh virtual environment that sees this interpreter's packages (numpy, placo,
py_trees, pytest ...) but takes bt-arrange from the wheel. A project folder holds the test file that
``docs/behaviours.md`` shows (Inspect and Push of a red cube, through ``bt_arrange.testing`` and the
``bt_blackboard`` fixture only) and pytest runs there: it passes, and no dependency's warning reaches
its output. A copy of the project's own ``tests/conftest.py`` beside it shows that the plugin, loaded
by its entry point, is not registered twice.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import docblocks
import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What the whole check may take (build, environment, install, pytest), on a busy two-core machine.
LIMIT_S = 60.0


def _user_test_file() -> str:
    """The pytest file that docs/behaviours.md shows under "Testing a behaviour"."""
    page = docblocks.read_page(ROOT / "docs" / "behaviours.md")
    tests = [b for b in page.blocks if b.language == "python" and "bt_blackboard" in b.code and "def test_" in b.code]
    (block,) = tests
    return block.code


def _clean_environment(venv: Path) -> dict[str, str]:
    """The environment of a user's shell in the virtual environment: nothing of this suite's own."""
    env = {key: value for key, value in os.environ.items() if not key.startswith(("PYTHON", "PYTEST"))}
    env["PATH"] = os.pathsep.join([str(venv / "bin"), env.get("PATH", "")])
    env["VIRTUAL_ENV"] = str(venv)
    env["MPLBACKEND"] = "Agg"
    return env


def test_the_user_test_of_the_docs_uses_only_the_kit() -> None:
    code = _user_test_file()
    assert len(code.strip().splitlines()) <= 32, "a user's test of Inspect and Push fits in about 30 lines"
    imports = [line for line in code.splitlines() if line.startswith(("import ", "from "))]
    assert "from bt_arrange.testing import make_context, part, tick_until_done" in imports
    assert not any("tests" in line or "conftest" in line for line in imports)


def test_a_project_with_only_the_wheel_installed_runs_the_docs_test(tmp_path: Path) -> None:
    started = time.monotonic()
    wheels, venv, project = tmp_path / "wheels", tmp_path / "venv", tmp_path / "project"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--no-build-isolation", "-q", "-w", str(wheels)],
        check=True,
        capture_output=True,
    )
    (wheel,) = wheels.glob("bt_arrange-*.whl")
    # Without pip of its own: this interpreter's pip (a system site package) installs into it.
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    env = _clean_environment(venv)
    install = [str(python), "-m", "pip", "install", "--no-deps", "--no-index", "-q", str(wheel)]
    subprocess.run(install, check=True, capture_output=True, env=env, cwd=tmp_path)

    located = subprocess.run(
        [str(python), "-c", "import bt_arrange; print(bt_arrange.__file__)"],
        check=True,
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
    ).stdout.strip()
    assert Path(located).is_relative_to(venv), f"bt_arrange comes from {located}, not from the wheel in {venv}"

    project.mkdir()
    (project / "test_red_cube.py").write_text(_user_test_file())
    checkout = project / "like_the_checkout"  # this project's own conftest, with the entry point installed
    checkout.mkdir()
    shutil.copy(ROOT / "tests" / "conftest.py", checkout / "conftest.py")
    (checkout / "test_blank.py").write_text(
        "import py_trees\n\n\ndef test_the_blackboard_starts_empty():\n"
        "    assert not py_trees.blackboard.Blackboard.storage\n"
        "    py_trees.blackboard.Blackboard.set('/left/over', 1)\n"
    )
    result = subprocess.run(
        [str(python), "-m", "pytest", "-p", "no:cacheprovider", "-q", str(project)],
        capture_output=True,
        text=True,
        env=env,
        cwd=project,
    )
    output = result.stdout + result.stderr
    took_s = time.monotonic() - started
    assert result.returncode == 0, output
    assert "3 passed" in output and "warning" not in output.lower(), output
    assert "hppfcl" not in output, output
    assert took_s < LIMIT_S, f"the wheel, the environment and the test took {took_s:.0f} s"


@pytest.mark.parametrize("registered_first", [True, False], ids=["by entry point", "by the conftest"])
def test_the_checkouts_conftest_registers_the_plugin_once(registered_first: bool) -> None:
    """The conftest's guard: the plugin is registered once, whether its entry point loaded it first or not."""
    from bt_arrange.testing import pytest_plugin

    # By path: other folders of the suite have a conftest of their own, and one of them may be "conftest".
    spec = importlib.util.spec_from_file_location("checkout_conftest", ROOT / "tests" / "conftest.py")
    assert spec is not None and spec.loader is not None
    conftest = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conftest)

    manager = pytest.PytestPluginManager()
    if registered_first:
        manager.register(pytest_plugin, "bt_arrange")
    config = type("Config", (), {"pluginmanager": manager})()
    conftest.pytest_configure(config)
    conftest.pytest_configure(config)
    assert manager.is_registered(pytest_plugin) and manager.get_plugin("bt_arrange") is pytest_plugin
