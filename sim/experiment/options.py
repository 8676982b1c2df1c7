"""The campaign's specification: one trial's spec, the combinations (thresholds x cells x types), the options.

``--rows``, ``--thresholds``, ``--cell``, ``--object`` and ``--strategy`` parsed and checked here,
before anything runs, each failing with a one-line ``PlanError``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path

from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectType, built_in_type
from bt_arrange.suggest import did_you_mean
from bt_arrange.trees import check_threshold
from bt_arrange_sim.experiment.engines import DEFAULT_ENGINE
from bt_arrange_sim.experiment.rows import ROWS


@dataclass(frozen=True)
class TrialSpec:
    """One trial: which row, which number, and the experiment's settings."""

    row: str
    index: int
    seed: int
    threshold_mm: float
    #: The cell: ``ideal``, ``real`` or a ``.toml`` file (``bt_arrange_sim.realcell.parse_cell``).
    cell: str = "ideal"
    #: The push strategy: ``paper`` (Table 1's), ``learned`` or ``diagonal`` (``bt_arrange.behaviours.Push``).
    strategy: str = "paper"
    #: The part's type: a name of ``bt_arrange.objects.BUILT_IN_TYPES`` (``cube``, ``bar``).
    object_name: str = "cube"
    #: A camera calibration file (``bt-arrange calibrate``) the detector uses; None: the cell's nominal camera.
    calibration: str | None = None
    #: The physics engine the trial's cell runs in: a backend's entry point name (``engines.trial_engine``).
    engine: str = DEFAULT_ENGINE
    #: Where the trial records its MCAP (an absolute path, ``experiment --record``), or None; not in its record.
    mcap: str | None = None

    def record_fields(self) -> dict[str, object]:
        """What names the trial in its record (``trials.jsonl``), in the records' order."""
        return {
            "row": self.row,
            "trial": self.index,
            "seed": self.seed,
            "threshold_mm": self.threshold_mm,
            "cell": self.cell,
            "strategy": self.strategy,
            "object": self.object_name,
            **({"calibration": self.calibration} if self.calibration is not None else {}),
            # Named only when not pybullet's, so the records of before a second engine read the same.
            **({"engine": self.engine} if self.engine != DEFAULT_ENGINE else {}),
        }


@dataclass(frozen=True)
class Combination:
    """One point of a campaign's product of lists: a threshold, a cell and a part's type.

    The push strategy is one value for the whole campaign; it is carried here so every trial and
    every folder's records name it.
    """

    threshold_mm: float
    #: ``ideal``, ``real`` or a ``.toml`` file, as given to ``--cell``.
    cell: str = "ideal"
    strategy: str = "paper"
    object_name: str = "cube"
    #: The campaign's camera calibration file, or None (``--calibration``).
    calibration: str | None = None
    #: The engine of the campaign's cells (``TrialSpec.engine``).
    engine: str = DEFAULT_ENGINE

    @property
    def folder(self) -> str:
        """The combination's folder name inside the campaign folder (the ideal cell is not named)."""
        name = f"threshold-{self.threshold_mm:g}mm"
        if self.cell != "ideal":
            name += f"-cell-{cell_label(self.cell)}"
        # The cube is not named either, so a campaign's folders read as before types were a list.
        return name if self.object_name == "cube" else f"{name}-object-{self.object_name}"

    def spec(self, row: str, index: int, seed: int) -> TrialSpec:
        """The trial ``index`` of ``row`` under this combination."""
        return TrialSpec(
            row, index, seed, self.threshold_mm, self.cell, self.strategy, self.object_name, self.calibration,
            self.engine,
        )  # fmt: skip

    def owns(self, record: dict) -> bool:
        """True when ``record`` is a trial of this combination (records before ``cell`` were the ideal cell's)."""
        return (
            record.get("threshold_mm") == self.threshold_mm
            and record.get("cell", "ideal") == self.cell
            and record.get("strategy", "paper") == self.strategy
            and record.get("object", "cube") == self.object_name
            and record.get("calibration") == self.calibration
            and record.get("engine", DEFAULT_ENGINE) == self.engine
        )


def cell_label(cell: str) -> str:
    """A cell's short name for folders and headings: ``ideal``, ``real``, or a TOML file's stem."""
    return Path(cell).stem if cell.endswith(".toml") else cell


def combinations(
    thresholds_mm: Sequence[float],
    cells: Sequence[str] = ("ideal",),
    strategy: str = "paper",
    object_names: Sequence[str] = ("cube",),
) -> list[Combination]:
    """The campaign: the product of the lists (thresholds, cells, then types), in order, duplicates removed."""
    seen: list[Combination] = []
    for threshold_mm, cell, object_name in itertools.product(thresholds_mm, cells, object_names):
        combination = Combination(float(threshold_mm), cell, strategy, object_name)
        if combination not in seen:
            seen.append(combination)
    return seen


def parse_rows(text: str) -> list[str]:
    """Rows from a comma-separated list; a ``PlanError`` names an unknown one and the known ones."""
    rows = [row.strip() for row in text.split(",") if row.strip()]
    if not rows:
        raise PlanError(f"--rows is empty; choose from {', '.join(ROWS)}")
    for row in rows:
        if row not in ROWS:
            raise PlanError(f"unknown row {row!r}{did_you_mean(row, ROWS)}; the rows are {', '.join(ROWS)}")
    return list(dict.fromkeys(rows))


def parse_thresholds(text: str) -> list[float]:
    """Thresholds in mm from a comma-separated list (``0.29,0.5,1,2``); a ``PlanError`` names a bad one."""
    values = []
    for item in (part.strip() for part in text.split(",")):
        if not item:
            continue
        try:
            value = float(item)
        except ValueError:
            raise PlanError(f"--thresholds: {item!r} is not a number of millimetres") from None
        if not (math.isfinite(value) and value > 0):
            raise PlanError(f"--thresholds: {item} must be a positive number of millimetres")
        try:
            check_threshold(value)
        except PlanError as error:
            raise PlanError(f"--thresholds {item}: {error}") from error
        values.append(value)
    if not values:
        raise PlanError("--thresholds is empty; give millimetres such as 0.29,0.5,1,2")
    return values


def parse_cells(cells: str | Sequence[str]) -> list[str]:
    """Cells from ``--cell`` (``ideal``, ``real``, ``FILE.toml``, or several: ``ideal,real``), each checked."""
    from bt_arrange_sim.realcell import parse_cell

    items = [part.strip() for part in cells.split(",")] if isinstance(cells, str) else [str(c) for c in cells]
    items = [item for item in items if item]
    if not items:
        raise PlanError(
            f"--cell {cells!r} is empty; choose ideal or real, or give a .toml file (or several: ideal,real)"
        )
    for item in items:
        try:
            parse_cell(item)
        except PlanError as error:
            raise PlanError(f"--cell {item}: {error}") from error
    return list(dict.fromkeys(items))


def parse_object(name: str) -> ObjectType:
    """The part's type for ``--object``: a built-in type's name; a one-line ``PlanError`` otherwise."""
    try:
        return built_in_type(name)
    except PlanError as error:
        raise PlanError(f"--object {name!r}: {error}") from None


def parse_objects(names: str | Sequence[str]) -> list[str]:
    """Types from ``--object`` (``cube``, ``bar``, or several: ``cube,bar``), each checked; duplicates dropped."""
    items = [part.strip() for part in names.split(",")] if isinstance(names, str) else [str(n) for n in names]
    items = [item for item in items if item]
    if not items:
        raise PlanError(f"--object {names!r} is empty; give a type such as cube, or several: cube,bar")
    for item in items:
        parse_object(item)
    return list(dict.fromkeys(items))


def check_options(
    cell: str | Sequence[str] = "ideal",
    strategy: str = "paper",
    thresholds: str | Sequence[float] | None = None,
    executor: str | Executor | None = "local",
    workers: int = 1,
    scheduler: str | None = None,
    object_name: str | Sequence[str] = "cube",
    rows: Iterable[str] = (),
    calibration: str | Path | None = None,
    resume: bool = False,
    record: str | Path | None = None,
) -> None:
    """The options of ``run_experiment`` checked before anything runs; a one-line ``PlanError`` otherwise.

    ``--cell`` (one cell or several), ``--strategy``, ``--thresholds``, ``--object`` (with the
    ``rows`` it runs in), ``--executor`` with ``--workers`` and ``--scheduler`` (with ``dask``:
    installed, and the scheduler's port taking a connection), and ``--record``. ``resume`` needs
    nothing checked here: ``run_experiment`` compares the folder's specification.
    """
    _plan(1.0, cell, strategy, thresholds, executor, workers, scheduler, object_name)
    check_object_rows(object_name, rows)
    check_calibration(calibration)
    check_record(record)
    if executor == "dask":
        from bt_arrange_sim.executors import check_dask

        # Last: the only check that may wait (a few seconds, for a scheduler that does not answer).
        check_dask(scheduler)


def check_record(record: str | Path | None) -> Path | None:
    """The ``--record`` folder, absolute (a Dask worker elsewhere writes there too), or None without one.

    A one-line error when the Foxglove SDK (the ``foxglove`` extra) is missing, or the folder is a file.
    """
    if record is None:
        return None
    from bt_arrange.foxglove import streams

    if not streams.sdk_available():
        raise streams.FoxgloveError(f"--record needs the Foxglove SDK: {streams.INSTALL_HINT}")
    folder = Path(record).absolute()
    if folder.exists() and not folder.is_dir():
        raise PlanError(f"--record {record}: it is a file, not a folder")
    return folder


def check_calibration(calibration: str | Path | None) -> str | None:
    """The ``--calibration`` file checked (``read_calibration``), as a string for the trials; None without one."""
    if calibration is None:
        return None
    from bt_arrange.calibration.file import read_calibration_option
    from bt_arrange_sim.config import CameraConfig

    # Every engine's cell has the same camera (``config.CameraConfig``): the calibration must be for its images.
    camera = CameraConfig()
    read_calibration_option(calibration, camera.width_px, camera.height_px)
    return str(calibration)


def check_object_rows(object_name: str | Sequence[str], rows: Iterable[str]) -> None:
    """A ``PlanError`` when a row cannot run a type: the depth-only estimator knows the cube only."""
    rows = list(rows)
    for name in parse_objects(object_name):
        if name != "cube" and "grasp-estimator" in rows:
            raise PlanError(
                f"--object {name}: the grasp-estimator row's depth-only estimator knows the paper's 5 cm cube only"
            )


def _plan(
    threshold_mm: float,
    cell: str | Sequence[str],
    strategy: str,
    thresholds: str | Sequence[float] | None,
    executor: str | Executor | None,
    workers: int,
    scheduler: str | None,
    object_name: str | Sequence[str] = "cube",
) -> tuple[list[Combination], bool]:
    """The campaign's combinations, and whether its one combination is written straight into ``out_dir``."""
    from bt_arrange.trees import check_strategy
    from bt_arrange_sim.executors import check_choice

    try:
        check_strategy(strategy)
    except PlanError as error:
        raise PlanError(f"--strategy {strategy!r}: {error}") from error
    object_names = parse_objects(object_name)
    cells = parse_cells(cell)
    if thresholds is None:
        sweep = [threshold_mm]
    elif isinstance(thresholds, str):
        sweep = parse_thresholds(thresholds)
    else:
        sweep = parse_thresholds(",".join(repr(float(t)) for t in thresholds))
    if isinstance(executor, str) or executor is None:
        check_choice(executor or "local", workers, scheduler)
    elif scheduler is not None:
        raise PlanError("--scheduler needs --executor dask")
    # A sweep, several cells or several types keep one folder per combination; one of each writes into out_dir.
    flat = thresholds is None and len(cells) == 1 and len(object_names) == 1
    return combinations(sweep, cells, strategy, object_names), flat
