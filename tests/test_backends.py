"""The framework reaches its simulator only through a backend found by name (issue 9, item 2)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from bt_arrange import backends, cli
from bt_arrange.errors import BackendError

PACKAGE = Path(__file__).resolve().parents[1] / "bt_arrange"


def test_no_module_of_the_framework_imports_the_simulator() -> None:
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            offenders += [
                f"{path.relative_to(PACKAGE)}:{node.lineno} {n}"
                for n in names
                if n.split(".")[0] in ("bt_arrange_sim", "pybullet")
            ]
    assert offenders == []


def test_importing_every_framework_module_loads_no_simulator_module() -> None:
    code = (
        "import pkgutil, importlib, sys, bt_arrange, bt_arrange.cli\n"
        "for info in pkgutil.walk_packages(bt_arrange.__path__, 'bt_arrange.'):\n"
        "    importlib.import_module(info.name)\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('bt_arrange_sim', 'pybullet')))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert result.stdout.strip() == "[]", result.stdout


def test_the_default_backend_is_the_simulated_cell() -> None:
    backend = backends.load()
    assert isinstance(backend, backends.Backend)
    assert backend.name == backends.DEFAULT_BACKEND == "sim"
    assert backend.experiment is not None and "system" in backend.experiment.ROWS


def test_an_unknown_backend_is_one_line_naming_the_known_ones(capsys) -> None:
    with pytest.raises(BackendError, match=r"^no backend 'ur5'; installed: .*sim"):
        backends.load("ur5")
    assert cli.main(["info", "--backend", "ur5"]) == cli.EXIT_USAGE
    err = capsys.readouterr().err
    assert err.startswith("bt-arrange: error: no backend 'ur5'") and err.count("\n") == 1


class _Bench:
    """A backend of nothing but a check: what a real-robot backend registers."""

    name = "bench"
    experiment = None

    def open_run(self, root, starts, **options):  # noqa: ANN001, ANN003, ANN201
        raise AssertionError("not run here")

    def scatter(self, colours, seed, avoid=()):  # noqa: ANN001, ANN201
        return []

    def check(self):  # noqa: ANN201
        yield "bench: arm and camera answer"

    def prepare_out(self, path):  # noqa: ANN001, ANN201
        return path


def test_a_registered_backend_serves_the_command_line(capsys, tmp_path) -> None:
    backends.register("bench", _Bench)
    try:
        assert "bench" in backends.available()
        assert cli.main(["info", "--backend", "bench"]) == cli.EXIT_OK
        assert "  bench: arm and camera answer" in capsys.readouterr().out
        code = cli.main(["experiment", "--backend", "bench", "--out", str(tmp_path)])
        assert code == cli.EXIT_USAGE
        assert "backend 'bench' cannot run the experiment" in capsys.readouterr().err
    finally:
        backends._registered.pop("bench")
