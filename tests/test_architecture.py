"""The house's floors: no import circle in bt_arrange/ or sim/, the plan below the tree, the engines siblings.

Every import counts: at module level, inside a function, under ``TYPE_CHECKING`` (the same coupling).
The plan's floor (``bt_arrange.plan``) imports no behaviour, tree builder or session. The neutral layer
is every module of ``bt_arrange_sim`` outside its engine packages; it imports no engine, and neither
engine imports the other.
"""

from __future__ import annotations

import ast
from pathlib import Path

SIM = Path(__file__).resolve().parents[1] / "sim"
PACKAGE = "bt_arrange_sim"
FRAMEWORK = Path(__file__).resolve().parents[1] / "bt_arrange"
#: What the plan's floor must never import: the floors above it.
ABOVE_THE_PLAN = (
    "bt_arrange.behaviours",
    "bt_arrange.decorators",
    "bt_arrange.trees",
    "bt_arrange.session",
    "bt_arrange.runner",
    "bt_arrange.xmltree",
    "bt_arrange.plans",
    "bt_arrange.cli",
)
ENGINES = ("bt_arrange_sim.pybullet", "bt_arrange_sim.mujoco")
MAX_MODULE_LINES = 600


def _modules(root: Path = SIM, package: str = PACKAGE) -> dict[str, Path]:
    modules = {}
    for path in root.rglob("*.py"):
        parts = [package, *path.relative_to(root).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _owner(name: str, modules: dict[str, Path]) -> str | None:
    """The module of ``modules`` that ``name`` (a module, or a name inside one) is, or is in."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _imports(module: str, path: Path, modules: dict[str, Path], prefix: str = PACKAGE) -> set[str]:
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str | None] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {_owner(alias.name, modules) for alias in node.names if alias.name.startswith(prefix)}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            if base.startswith(prefix):
                found |= {_owner(f"{base}.{alias.name}", modules) for alias in node.names}
    return {name for name in found if name is not None and name != module}


def _graph(root: Path = SIM, package: str = PACKAGE) -> dict[str, set[str]]:
    modules = _modules(root, package)
    return {module: _imports(module, path, modules, package) for module, path in modules.items()}


def _engine_of(module: str) -> str | None:
    return next((e for e in ENGINES if module == e or module.startswith(e + ".")), None)


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    circles: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for other in graph.get(node, ()):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return circles


def test_no_import_circle_in_sim() -> None:
    assert _circles(_graph()) == []


def test_no_import_circle_in_the_framework() -> None:
    assert _circles(_graph(FRAMEWORK, "bt_arrange")) == []


def test_the_plan_imports_nothing_above_it() -> None:
    graph = _graph(FRAMEWORK, "bt_arrange")
    offenders = sorted(
        f"{module} -> {other}"
        for module, imported in graph.items()
        if module == "bt_arrange.plan" or module.startswith("bt_arrange.plan.")
        for other in imported
        if any(other == above or other.startswith(above + ".") for above in ABOVE_THE_PLAN)
    )
    assert offenders == []


def test_the_framework_graph_sees_imports_inside_functions_and_type_checking() -> None:
    graph = _graph(FRAMEWORK, "bt_arrange")
    # plan.stacking takes Target under TYPE_CHECKING and parts_of inside a function: both are arrows.
    assert "bt_arrange.plan.targets" in graph["bt_arrange.plan.stacking"]


def test_the_circle_check_finds_a_circle() -> None:
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_neither_engine_imports_the_other_and_the_neutral_layer_imports_neither() -> None:
    offenders = []
    for module, imported in sorted(_graph().items()):
        mine = _engine_of(module)
        for other in sorted(imported):
            theirs = _engine_of(other)
            if theirs is not None and theirs != mine:
                offenders.append(f"{module} -> {other}")
    assert offenders == []


def test_every_engine_is_found_through_the_backends_entry_points() -> None:
    import tomllib

    pyproject = tomllib.loads((SIM.parent / "pyproject.toml").read_text(encoding="utf-8"))
    declared = pyproject["project"]["entry-points"]["bt_arrange.backends"].values()
    # The real cell's backend (bt_arrange.ur) is declared there too, and is no simulated engine.
    engines = {_engine_of(value.partition(":")[0]) for value in declared if not value.startswith("bt_arrange.ur.")}
    assert engines == set(ENGINES)


def test_every_module_of_sim_stays_under_600_lines() -> None:
    long = {
        str(p.relative_to(SIM)): n
        for p in SIM.rglob("*.py")
        if (n := len(p.read_text().splitlines())) >= MAX_MODULE_LINES
    }
    assert long == {}


def test_the_names_that_moved_to_the_pybullet_engine_still_resolve_with_a_deprecation_warning() -> None:
    import pytest

    import bt_arrange_sim
    from bt_arrange_sim.pybullet.cell import WorkCell
    from bt_arrange_sim.pybullet.runs import SimulatedRun

    with pytest.warns(DeprecationWarning, match="bt_arrange_sim.pybullet.cell"):
        assert bt_arrange_sim.WorkCell is WorkCell
    with pytest.warns(DeprecationWarning, match="bt_arrange_sim.pybullet.runs"):
        assert bt_arrange_sim.SimulatedRun is SimulatedRun


#: What ticks a tree: bt_arrange's session builds these, a backend supplies the world they tick.
_SESSION_BUILDERS = {"Runner", "Session", "BehaviourTree"}


def _session_builders(source: str) -> list[str]:
    """Where ``source`` imports the runner, or calls a ``Runner``, ``Session`` or py_trees ``BehaviourTree`` itself.

    Subclassing ``Session`` (``CellRun``) and calling ``super().__init__`` is the session's own API,
    not a session built beside it.
    """
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.module == "bt_arrange.runner":
            found += [f"line {node.lineno}: imports {a.name}" for a in node.names if a.name in _SESSION_BUILDERS]
        elif isinstance(node, ast.Call):
            function = node.func
            name = function.id if isinstance(function, ast.Name) else getattr(function, "attr", None)
            if name in _SESSION_BUILDERS:
                found.append(f"line {node.lineno}: calls {name}")
    return found


def test_sim_builds_no_runner_or_session_of_its_own() -> None:
    """The session belongs to bt_arrange, a backend supplies a world (docs/architecture.md)."""
    offenders = {
        str(path.relative_to(SIM)): found
        for path in sorted(SIM.rglob("*.py"))
        if (found := _session_builders(path.read_text(encoding="utf-8")))
    }
    assert offenders == {}


def test_the_session_check_finds_a_runner_built_in_a_backend() -> None:
    source = (
        "from bt_arrange.runner import Runner, Transition\n"
        "import py_trees\n"
        "def f(tree, context, step):\n"
        "    py_trees.trees.BehaviourTree(tree)\n"
        "    return Runner(tree, context, step).run()\n"
        "class Run(Session):\n"
        "    def __init__(self):\n"
        "        super().__init__()\n"
    )
    assert _session_builders(source) == [
        "line 1: imports Runner",
        "line 4: calls BehaviourTree",
        "line 5: calls Runner",
    ]
