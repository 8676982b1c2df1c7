"""Backends: what the command line runs a tree on, found by name, never imported by the framework.

``bt-arrange run``, ``experiment`` and ``info`` reach the world through a ``Backend``: the
simulated work cell (``sim``, the default, from the ``bt_arrange_sim`` package) or a real UR5 cell
(``ur``, ``bt_arrange.ur``). What only some backends can do is declared, never probed: a backend is
a ``ScatteringBackend``, a ``CalibratingBackend``, ... when it provides that protocol's members, and a
command that needs one says in one line which is missing (``require``).

A backend is found through the ``bt_arrange.backends`` entry-point group, which a package
declares in its ``pyproject.toml``::

    [project.entry-points."bt_arrange.backends"]
    sim = "bt_arrange_sim.pybullet.backend:SimBackend"

or registered at run time with ``register(name, factory)``. The framework names no backend
module in its code: ``load("sim")`` imports whatever the entry point says, only when a command
needs it. (When the installed metadata predates the entry point, e.g. an editable install not
reinstalled since, the backends this package ships, ``sim`` and ``ur``, are still found through
``FALLBACK``: strings, not imports.)

The protocols below say what the CLI uses of a backend, its runs and their reports.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import py_trees

from bt_arrange.errors import BackendError, PlanError
from bt_arrange.suggest import did_you_mean

#: The entry-point group backends are declared in.
ENTRY_POINT_GROUP = "bt_arrange.backends"
#: The backend the command line uses unless told otherwise: the simulated work cell.
DEFAULT_BACKEND = "sim"
#: Where the backends this package ships live when no installed entry point declares them (stale
#: metadata): the default, and the real cell (``bt_arrange.ur``, which needs the ``ur`` extra to run).
FALLBACK = {
    DEFAULT_BACKEND: "bt_arrange_sim.pybullet.backend:SimBackend",
    "ur": "bt_arrange.ur.backend:UrBackend",
}


class ObjectReport(Protocol):
    """How one object ended: offsets in millimetres, camera and (where the backend knows it) truth."""

    name: str
    target: tuple[float, float, float]
    placed_offset_mm: float | None
    final_offset_mm: float | None
    final_offset_truth_mm: float | None
    pushes: int
    status: str
    reason: str
    #: Measured minus target yaw (degrees, folded to the part's symmetry); None when not measured.
    final_yaw_error_deg: float | None
    final_yaw_error_truth_deg: float | None


class RunReport(Protocol):
    """A run's outcome, per object and for the whole tree."""

    @property
    def objects(self) -> Sequence[ObjectReport]:
        """One report per object of the plan."""
        ...

    tree_status: str
    threshold_mm: float | None
    sim_seconds: float
    wall_seconds: float
    timed_out: bool
    #: False when the world had no ground truth: the report is camera only (read with a default of True).
    ground_truth: bool

    @property
    def all_within_threshold(self) -> bool:
        """True when every object ended within the threshold, as the camera measured."""
        ...

    def within_text(self) -> str:
        """How many objects are within: ``3 of 4 objects within 1 mm and 1 deg``."""
        ...

    def not_within(self) -> str:
        """Each object not within, with its offset and why (empty when all are)."""
        ...

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` form."""
        ...


class RunSession(Protocol):
    """One tree on one world, as a context manager: ``with backend.open_run(...) as run: run.run()``."""

    tick_hooks: list[Callable[[py_trees.behaviour.Behaviour], object]]
    #: Called with every status change (a ``bt_arrange.runner.Transition``), e.g. by the Groot2 publisher.
    transition_hooks: list[Callable[[Any], object]]
    #: Called with the runner before the first tick (``--groot-wait-s`` waits there).
    runner_hooks: list[Callable[[Any], object]]
    #: The live Foxglove server the run streams to (``--foxglove``; a ``bt_arrange.session.Session`` has it), or None.
    foxglove_live: Any

    def elapsed_s(self) -> float:
        """World time since the tree started."""
        ...

    def run(self) -> RunReport:
        """Tick the tree to the end."""
        ...

    def __enter__(self) -> RunSession: ...

    def __exit__(self, *exc: object) -> None: ...


class Experiment(Protocol):
    """The paper's evaluation on this backend (Table 1 rows as seeded trials)."""

    ROWS: tuple[str, ...]
    ROW_LABELS: Mapping[str, str]

    def parse_rows(self, text: str) -> list[str]:
        """Rows from a comma-separated list, or a ``PlanError``."""
        ...

    def run_experiment(
        self, rows: Iterable[str], trials: int, seed: int, threshold_mm: float, out_dir: Path, **options: Any
    ) -> list[dict[str, Any]]:
        """Run the missing trials into ``out_dir``; the summary rows.

        ``options`` are the backend's own, passed only when not their default: ``workers`` and
        ``on_trial`` always; the sim backend also takes ``cell``, ``strategy``, ``thresholds``,
        ``executor`` and ``scheduler`` and checks them first in ``check_options(**options)``.
        """
        ...

    def markdown_table(self, summary: list[dict[str, Any]]) -> str:
        """Table 1 as Markdown."""
        ...


@runtime_checkable
class Backend(Protocol):
    """What the command line runs trees on."""

    name: str

    def open_run(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
    ) -> RunSession:
        """Check the plan and the scene, build the world, and return the run (not started)."""
        ...

    def check(self) -> Iterator[str]:
        """Lines for ``bt-arrange info``: the backend starts (or a ``BtArrangeError`` saying why not)."""
        ...

    def prepare_out(self, path: Path) -> Path:
        """Make an output folder, or a ``PlanError`` saying why it cannot be used."""
        ...

    @property
    def experiment(self) -> Experiment | None:
        """The paper's evaluation, or None when this backend cannot run it."""
        ...


@runtime_checkable
class InjectingBackend(Protocol):
    """An optional capability of a backend: the paper's Sec. 3 errors put into any run (``run --inject``).

    ``injectable_errors`` are the names it knows (the sim backends: those of ``experiment --rows``
    that inject an error, and ``all``); ``open_run(..., inject=names, inject_seed=seed)`` puts them
    into every part the tree picks, at the experiment's magnitudes, drawn from the seed, and the
    run's report lists what was injected into which part (``injected``). A backend without it (a
    real robot) has nothing to inject into: ``check_inject`` refuses ``--inject`` in one line.
    """

    name: str

    @property
    def injectable_errors(self) -> Sequence[str]:
        """The error names ``open_run(inject=...)`` takes."""
        ...


@runtime_checkable
class ScatteringBackend(Protocol):
    """An optional capability: the backend puts the parts into its world (a simulator), so a run needs a scene.

    ``bt-arrange run`` asks a tree file's ``create_scene(seed)`` (a plan scatters its parts through
    ``scatter``) only on such a backend. A real cell has none: its parts lie where they lie, and a tree
    file needs only ``create_root``.
    """

    name: str

    def scatter(
        self,
        colours: Sequence[str],
        seed: int,
        avoid: Iterable[Any] = (),
        object_types: Sequence[Any] | None = None,
        names: Sequence[str | None] | None = None,
    ) -> list[Any]:
        """Where parts of ``colours`` start for scene ``seed``, clear of ``avoid`` (targets)."""
        ...


@runtime_checkable
class PuzzleBackend(Protocol):
    """An optional capability: the backend breaks a plan's ``[puzzle]`` slab and scatters its pieces (a simulator)."""

    name: str

    def puzzle_scene(
        self, targets: Sequence[Any], puzzles: Sequence[Any], seed: int, *, starts: Sequence[Any] | None = None
    ) -> list[Any]:
        """Each puzzle's slab broken from ``seed``, its pieces scattered (with ``starts`` for the other parts)."""
        ...


@runtime_checkable
class CalibratingBackend(Protocol):
    """An optional capability: ``bt-arrange calibrate``, the ChArUco procedure in the backend's cell."""

    name: str

    def open_calibration(self, **options: Any) -> Any:
        """The calibration run (``views``, ``gui``, ``record_dir``, ``time_limit_s``, the backend's own): not ticked."""
        ...


@runtime_checkable
class TrueCameraRun(Protocol):
    """An optional capability of a calibration run: a simulator's true camera, to grade it (evaluation only)."""

    def true_camera(self) -> tuple[Any, Any]:
        """The true ``(CameraIntrinsics, Pose)`` of the camera the run calibrated."""
        ...


@runtime_checkable
class ConnectingBackend(Protocol):
    """An optional capability: a backend that reaches a real cell (``--robot HOST``, ``--camera SPEC``).

    ``connect_to`` is called before any other method when the command line is given either option;
    a backend without it refuses them in one line.
    """

    name: str

    def connect_to(self, robot_host: str | None, camera_spec: str | None) -> None:
        """Where the robot's controller and the camera are (nothing is opened yet)."""
        ...


@runtime_checkable
class SafetyBackend(Protocol):
    """An optional capability: ``run --speed-fraction F`` (``bt_arrange.motion.safety.MotionSafety``).

    ``open_run(..., speed_fraction=F)``; a backend without it refuses the option in one line.
    """

    name: str

    #: The speed fraction a run uses without ``--speed-fraction`` (a real cell: a conservative one).
    default_speed_fraction: float


@runtime_checkable
class DryRunBackend(Protocol):
    """An optional capability: ``run --dry-run`` plans every motion of the tree without moving the robot.

    ``open_run(..., dry_run=True)``; the report says what was planned and what could not be (``dry_run``).
    """

    name: str

    #: What a dry run on this backend cannot plan, for its summary line.
    dry_run_limits: str


@runtime_checkable
class FoxgloveRun(Protocol):
    """An optional capability of a run: it streams to a live Foxglove server (``run --foxglove``)."""

    foxglove_live: Any


@runtime_checkable
class OptionedExperiment(Protocol):
    """An optional capability of an ``Experiment``: options of its own (``--cell``, ``--strategy``), checked first."""

    def check_options(self, **options: Any) -> None:
        """A one-line ``PlanError`` for an option this backend's campaign cannot take."""
        ...


def require(backend: Any, capability: type, what: str, *, name: str | None = None) -> Any:
    """``backend`` (or a run of it) when it declares ``capability``; a one-line ``BackendError`` otherwise."""
    if not isinstance(backend, capability):
        shown = name if name is not None else getattr(backend, "name", type(backend).__name__)
        raise BackendError(f"backend {shown!r} cannot {what} (it has no {capability.__name__} capability)")
    return backend


def check_inject(backend: Backend, text: str) -> list[str]:
    """The errors of ``--inject ERROR[,ERROR...]`` for ``backend``, checked before anything moves.

    A one-line ``BackendError`` when the backend cannot inject errors; a ``PlanError`` for an empty
    list or an unknown name, naming the known ones. Duplicates are dropped.
    """
    if not isinstance(backend, InjectingBackend):
        raise BackendError(
            f"backend {backend.name!r} cannot inject errors (--inject): it has no simulated world to put them in"
        )
    known = list(backend.injectable_errors)
    names = list(dict.fromkeys(item.strip() for item in text.split(",") if item.strip()))
    if not names:
        raise PlanError(f"--inject is empty; the errors are {', '.join(known)}")
    for name in names:
        if name not in known:
            raise PlanError(
                f"--inject {name}: unknown error{did_you_mean(name, known)}; the errors are {', '.join(known)}"
            )
    return names


_registered: dict[str, Callable[[], Backend]] = {}


def register(name: str, factory: Callable[[], Backend]) -> None:
    """Make a backend available under ``name`` (it takes precedence over an entry point of that name)."""
    _registered[name] = factory


def available() -> list[str]:
    """The names of every backend found: registered, declared by entry points, and the fallback."""
    names = set(_registered) | {ep.name for ep in metadata.entry_points(group=ENTRY_POINT_GROUP)}
    return sorted(names | set(FALLBACK))


def _import(spec: str) -> Any:
    module_name, _, attribute = spec.partition(":")
    module = importlib.import_module(module_name)
    return getattr(module, attribute) if attribute else module


def load(name: str = DEFAULT_BACKEND) -> Backend:
    """The backend called ``name``; a ``BackendError`` names the known ones when there is none."""
    factory: Any = _registered.get(name)
    if factory is None:
        points = [ep for ep in metadata.entry_points(group=ENTRY_POINT_GROUP) if ep.name == name]
        try:
            if points:
                factory = points[0].load()
            elif name in FALLBACK:
                factory = _import(FALLBACK[name])
        except ImportError as error:
            raise BackendError(f"backend {name!r} cannot be loaded: {error}") from error
    if factory is None:
        raise BackendError(f"no backend {name!r}; installed: {', '.join(available())}")
    # A class or a factory function is called; an object that already is a backend is used as it is.
    backend = factory() if isinstance(factory, type) or not isinstance(factory, Backend) else factory
    if not isinstance(backend, Backend):
        raise BackendError(f"backend {name!r} ({type(backend).__name__}) does not provide what bt-arrange needs")
    return backend
