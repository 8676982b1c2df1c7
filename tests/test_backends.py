"""The framework reaches its simulator only through a backend found by name."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from bt_arrange import backends, cli
from bt_arrange.errors import BackendError, BtArrangeError, PlanError

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
                if n.split(".")[0] in ("bt_arrange_sim", "pybullet", "mujoco")
            ]
    assert offenders == []


def test_importing_every_framework_module_loads_no_simulator_module() -> None:
    code = (
        "import pkgutil, importlib, sys, bt_arrange, bt_arrange.cli\n"
        "for info in pkgutil.walk_packages(bt_arrange.__path__, 'bt_arrange.'):\n"
        "    importlib.import_module(info.name)\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('bt_arrange_sim', 'pybullet', 'mujoco')))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert result.stdout.strip() == "[]", result.stdout


def test_the_default_backend_is_the_simulated_cell() -> None:
    backend = backends.load()
    assert isinstance(backend, backends.Backend)
    assert backend.name == backends.DEFAULT_BACKEND == "sim"
    assert backend.experiment is not None and "system" in backend.experiment.ROWS


# -- the contract every engine's backend keeps (the pybullet cell and MuJoCo's) ---------------------

#: The backends of a physics engine this project ships, by entry point name (a contract: keep the names).
ENGINES = ("sim", "mujoco")


def _engine(name: str) -> backends.Backend:
    import importlib.util

    if name == "mujoco" and importlib.util.find_spec("mujoco") is None:
        pytest.skip("the mujoco backend needs the mujoco package (pip install -e '.[mujoco]')")
    return backends.load(name)


def test_every_engine_is_declared_as_an_entry_point() -> None:
    from importlib import metadata

    declared = {ep.name: ep.value for ep in metadata.entry_points(group=backends.ENTRY_POINT_GROUP)}
    assert declared.get("sim") == "bt_arrange_sim.pybullet.backend:SimBackend"
    assert declared.get("mujoco") == "bt_arrange_sim.mujoco.backend:MujocoBackend"
    assert set(ENGINES) <= set(backends.available())


@pytest.mark.parametrize("name", ENGINES)
def test_an_engine_is_a_backend_with_the_papers_experiment(name: str) -> None:
    backend = _engine(name)
    assert isinstance(backend, backends.Backend) and backend.name == name
    experiment = backend.experiment
    assert experiment is not None
    assert experiment.ROWS[:3] == ("system", "translation", "orientation")
    assert experiment.parse_rows("system, translation") == ["system", "translation"]
    with pytest.raises(BtArrangeError, match="unknown row 'sytem'"):
        experiment.parse_rows("sytem")


@pytest.mark.parametrize("name", ENGINES)
def test_an_engines_scenes_are_the_same_seeded_starts(name: str) -> None:
    from bt_arrange.trees import Target

    target = Target("red", 0.5, 0.0)
    starts = _engine(name).scatter(["red", "green"], 3, avoid=[target])
    assert [s.colour for s in starts] == ["red", "green"]
    assert starts == backends.load("sim").scatter(["red", "green"], 3, avoid=[target])


@pytest.mark.parametrize("name", ENGINES)
def test_an_engine_refuses_a_bad_scene_before_building_its_world(name: str, monkeypatch) -> None:
    from bt_arrange.objects import ObjectStart
    from bt_arrange.trees import Target, arrangement

    backend = _engine(name)
    cell = "bt_arrange_sim.mujoco.cell.MujocoCell" if name == "mujoco" else "bt_arrange_sim.pybullet.cell.WorkCell"

    def never(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("the world was built")

    monkeypatch.setattr(f"{cell}.__init__", never)
    outside_the_view = [ObjectStart("red", 0.5, 0.62, 0.0)]
    with pytest.raises(PlanError, match="red"):
        backend.open_run(arrangement([Target("red", 0.5, 0.0)]), outside_the_view)


@pytest.mark.parametrize("name", ENGINES)
def test_an_engine_refuses_an_output_folder_that_is_a_file(name: str, tmp_path: Path) -> None:
    path = tmp_path / "file"
    path.write_text("")
    with pytest.raises(PlanError, match="it is a file"):
        _engine(name).prepare_out(path)


def test_the_mujoco_backend_refuses_what_only_pybullet_has_in_one_line() -> None:
    backend = _engine("mujoco")
    from bt_arrange.trees import Target, arrangement

    root = arrangement([Target("red", 0.5, 0.0)])
    with pytest.raises(PlanError, match=r"^--cell real: the MuJoCo backend has the ideal cell only"):
        backend.open_run(root, backend.scatter(["red"], 0), cell="real")
    with pytest.raises(PlanError, match="^--gui: the MuJoCo backend renders headless only"):
        backend.open_run(root, backend.scatter(["red"], 0), gui=True)
    assert backend.experiment is not None
    with pytest.raises(PlanError, match="^--cell real: the MuJoCo backend has the ideal cell only"):
        backend.experiment.check_options(cell="real")  # type: ignore[attr-defined]


def test_loading_the_mujoco_backend_imports_no_engine() -> None:
    code = (
        "import sys\n"
        "from bt_arrange import backends\n"
        "backends.load('mujoco')\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('pybullet', 'mujoco')))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert result.stdout.strip() == "[]", result.stdout


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


def test_the_experiments_backends_are_one_or_several_each_once(capsys, tmp_path) -> None:
    from bt_arrange.cli_experiment import backend_names

    assert backend_names("sim") == ["sim"] and backend_names(" sim, mujoco ") == ["sim", "mujoco"]
    with pytest.raises(BtArrangeError, match="--backend names sim more than once"):
        backend_names("sim,sim")
    code = cli.main(["experiment", "--backend", "sim,ur5", "--out", str(tmp_path / "x")])
    assert code == cli.EXIT_USAGE
    assert capsys.readouterr().err.startswith("bt-arrange: error: no backend 'ur5'")
    assert not (tmp_path / "x").exists()  # refused before anything ran or was made
