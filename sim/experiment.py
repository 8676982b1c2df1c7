"""The paper's evaluation (Sec. 5.3, Table 1, Fig. 4) as reproducible experiment campaigns.

Each row runs its trials with a single-cube arrangement (a random start and a random target per
trial, both seeded from the experiment's seed, the row and the trial number), with the row's
injected errors. A campaign is the product of its lists (the thresholds and the cells); the part's
type (``--object``: the cube, or a built-in type such as the 80 x 40 x 40 mm bar) is one value
for the whole campaign, like the push strategy: every combination gets its own folder with ``trials.jsonl``, the
summaries and Fig. 4. Each finished trial is appended at once; a rerun into the same folder runs only the
trials missing there. Offsets are the camera's measurements, as in the paper; the simulator's
ground truth is recorded beside them.

Trials run through any ``concurrent.futures.Executor`` (``bt_arrange_sim.executors``: a local
process pool, or a Dask cluster through ``Client.get_executor()``). A trial is a pure function of
its ``TrialSpec``, so the records are the same (order and wall times aside) whatever runs them.
"""

from __future__ import annotations

import contextlib
import csv
import itertools
import json
import math
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bt_arrange.behaviours.pick import SQUARED_FEEDBACK
from bt_arrange.checks import whole_number
from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.objects import ObjectType, built_in_type
from bt_arrange.trees import check_threshold

#: Rows: Table 1's four in the paper's order, then every other error of the paper's Sec. 3 alone,
#: then all of them at once. The position seeds a row's trials: append new rows, never reorder.
ROWS = (
    "system",
    "translation",
    "orientation",
    "grasp-estimator",
    "perception",
    "surface",
    "slip",
    "sticking",
    "release",
    "tilt",
    "all",
)
#: The default rows: the paper's Table 1.
TABLE1_ROWS = ROWS[:4]
#: The rows ``bt-arrange experiment`` runs without ``--rows``.
DEFAULT_ROWS = TABLE1_ROWS
ROW_LABELS = {
    "system": "1) System accuracy",
    "translation": "2) Translation error",
    "orientation": "3) Orientation error",
    "grasp-estimator": "4) Depth-only grasp estimator (substitute for Berscheid et al.)",
    "perception": "Perception error (Fig. 2a)",
    "surface": "Surface error (Fig. 2d)",
    "slip": "Grip error, slip (Fig. 2e)",
    "sticking": "Friction error, sticking (Fig. 2f)",
    "release": "Release error, height (Fig. 2g)",
    "tilt": "Tilting error (Fig. 2h)",
    "all": "All errors at once (Fig. 2a-h)",
}
#: The injectors (``bt_arrange_sim.injection`` specs, default magnitudes) each row attaches, in order:
#: a later picking error is drawn to fit with an earlier one.
ROW_INJECTORS: dict[str, tuple[str, ...]] = {
    "system": (),
    "translation": ("pick_translation",),
    "orientation": ("pick_rotation",),
    "grasp-estimator": (),
    "perception": ("perception_offset",),
    "surface": ("surface_shift",),
    "slip": ("transport_slip",),
    "sticking": ("release_stick",),
    "release": ("release_height",),
    "tilt": ("release_tilt",),
    "all": (
        "perception_offset",
        "pick_translation",
        "pick_rotation",
        "surface_shift",
        "transport_slip",
        "release_stick",
        "release_height",
        "release_tilt",
    ),
}
#: Table 1 a), simulation: mean and std in mm after placing and after pushing (rows the paper ran).
PAPER_SIMULATION_MM = {
    "system": (0.47, 0.29, 0.40, 0.25),
    "translation": (8.54, 5.70, 0.45, 0.41),
    "orientation": (3.03, 4.70, 0.43, 0.25),
    "grasp-estimator": (5.18, 3.83, 0.41, 0.25),
}
#: Targets of the trials: inside the camera's view and the arm's comfortable reach.
TARGET_X_RANGE_M = (0.38, 0.62)
TARGET_Y_RANGE_M = (-0.25, 0.25)
#: One trial at a time per process: py_trees' blackboard is process-wide, so two trials in two
#: threads of one worker (a Dask worker with several threads) would read each other's keys.
_TRIAL_LOCK = threading.Lock()


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
        return TrialSpec(row, index, seed, self.threshold_mm, self.cell, self.strategy, self.object_name)

    def owns(self, record: dict) -> bool:
        """True when ``record`` is a trial of this combination (records before ``cell`` were the ideal cell's)."""
        return (
            record.get("threshold_mm") == self.threshold_mm
            and record.get("cell", "ideal") == self.cell
            and record.get("strategy", "paper") == self.strategy
            and record.get("object", "cube") == self.object_name
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
            raise PlanError(f"unknown row {row!r}; the rows are {', '.join(ROWS)}")
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


def run_trial(spec: TrialSpec) -> dict:
    """Run one trial in a fresh cell and return its record (a JSON-able dict); one per process at a time."""
    with _TRIAL_LOCK:
        return _run_trial(spec)


def _run_trial(spec: TrialSpec) -> dict:
    from bt_arrange.trees import Target, arrangement
    from bt_arrange_sim.runs import SimulatedRun
    from bt_arrange_sim.scenes import scatter

    wall_start = time.perf_counter()
    rng = np.random.default_rng([spec.seed, ROWS.index(spec.row), spec.index])
    kind = parse_object(spec.object_name)
    target = Target(
        "red",
        float(rng.uniform(*TARGET_X_RANGE_M)),
        float(rng.uniform(*TARGET_Y_RANGE_M)),
        float(rng.uniform(-math.pi / 4, math.pi / 4)),
        object_type=kind,
    )
    starts = scatter(["red"], int(rng.integers(2**31)), avoid=[target], object_types=[kind])
    if spec.row == "grasp-estimator":
        root = _depth_grasp_tree(target, spec.threshold_mm, int(rng.integers(2**31)), spec.strategy)
    else:
        root = arrangement([target], threshold_mm=spec.threshold_mm, max_pushes=10, strategy=spec.strategy)
    injectors = row_injectors(spec.row)
    injection_seed = int(rng.integers(2**31))
    with SimulatedRun(root, starts, cell_config=_cell_config(spec)) as run:
        if injectors:
            from bt_arrange_sim.injection import attach_all

            attach_all(run, "red", injectors, injection_seed)
        report = run.run()
    (outcome,) = report.objects
    bad_grasps = [t.feedback for t in report.transitions if t.kind == "Pick" and t.new == "FAILURE"]
    squarings = [
        t for t in report.transitions if t.kind == "Pick" and t.new == "SUCCESS" and SQUARED_FEEDBACK in t.feedback
    ]
    return {
        "row": spec.row,
        "trial": spec.index,
        "seed": spec.seed,
        "threshold_mm": spec.threshold_mm,
        "cell": spec.cell,
        "strategy": spec.strategy,
        "object": spec.object_name,
        "target": [round(v, 6) for v in outcome.target],
        "placed_mm": outcome.placed_offset_mm,
        "pushed_mm": outcome.final_offset_mm,
        "placed_truth_mm": outcome.placed_offset_truth_mm,
        "pushed_truth_mm": outcome.final_offset_truth_mm,
        "pushes": outcome.pushes,
        "regrasps": len(bad_grasps),
        "regrasp_reasons": bad_grasps,
        # Picks that squared a cube pinched across its corners instead of letting go (Pick's "squaring").
        "squarings": len(squarings),
        "status": outcome.status,
        "reason": outcome.reason,
        "injected": {injector.name: injector.record() for injector in injectors},
        "sim_seconds": round(report.sim_seconds, 3),
        "wall_seconds": round(time.perf_counter() - wall_start, 3),
    }


def _cell_config(spec: TrialSpec):  # noqa: ANN202 - a CellConfig (imported lazily: pybullet)
    """The trial's cell; a real cell's per-run errors are seeded from the trial, apart from its draws."""
    from bt_arrange_sim.cell import CellConfig
    from bt_arrange_sim.realcell import parse_cell

    errors = parse_cell(spec.cell)
    if not errors.enabled:
        return CellConfig()
    run_seed = int(np.random.default_rng([spec.seed, ROWS.index(spec.row), spec.index, 12]).integers(2**31))
    return CellConfig(errors=errors.with_run_seed(run_seed))


def check_options(
    cell: str | Sequence[str] = "ideal",
    strategy: str = "paper",
    thresholds: str | Sequence[float] | None = None,
    executor: str | Executor | None = "local",
    workers: int = 1,
    scheduler: str | None = None,
    object_name: str | Sequence[str] = "cube",
    rows: Iterable[str] = (),
) -> None:
    """The options of ``run_experiment`` checked before anything runs; a one-line ``PlanError`` otherwise.

    ``--cell`` (one cell or several), ``--strategy``, ``--thresholds``, ``--object`` (with the
    ``rows`` it runs in), and ``--executor`` with ``--workers`` and ``--scheduler``.
    """
    _plan(1.0, cell, strategy, thresholds, executor, workers, scheduler, object_name)
    check_object_rows(object_name, rows)


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


def row_injectors(row: str) -> list:
    """The errors a row injects (``ROW_INJECTORS``), each at its default magnitude, fresh for one run."""
    specs = ROW_INJECTORS[row]
    if not specs:
        return []
    from bt_arrange_sim.injection import make_injectors

    return make_injectors(specs)


def _depth_grasp_tree(target, threshold_mm: float, seed: int, strategy: str = "paper"):  # noqa: ANN001, ANN202
    """Algorithm 1 with line 6 (pose estimation before picking) done by the depth-only substitute."""
    from bt_arrange.behaviours import MoveHome
    from bt_arrange.trees import Arrangement, arrange_one, by_depth

    arrange = arrange_one(target, threshold_mm, max_pushes=10, locate=by_depth(seed), strategy=strategy)
    return Arrangement("arrangement", [arrange, MoveHome("park the arm")], [target], threshold_mm)


def read_trials(path: Path) -> list[dict]:
    """The records in a trials file; a line cut short by an interruption is ignored."""
    if not path.exists():
        return []
    records = []
    for line in path.read_text().splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return records


class CampaignIncompleteError(BtArrangeError):
    """Some trials did not come back (a worker died, the cluster went away); a rerun completes them.

    ``summary`` holds what ``run_experiment`` would have returned, for the trials that did finish.
    """

    def __init__(self, message: str, *, summary: list[dict] | None = None) -> None:
        super().__init__(message)
        self.summary = summary or []


@dataclass
class CampaignResult:
    """What a campaign produced: one summary per combination, and the trials that did not come back."""

    summaries: dict[Combination, list[dict]]
    folders: dict[Combination, Path]
    lost: list[tuple[TrialSpec, str]]


def run_experiment(
    rows: Iterable[str],
    trials: int,
    seed: int,
    threshold_mm: float,
    out_dir: Path,
    *,
    workers: int = 1,
    executor: str | Executor | None = "local",
    on_trial: Callable[[dict, int, int], None] | None = None,
    cell: str | Sequence[str] = "ideal",
    strategy: str = "paper",
    thresholds: str | Sequence[float] | None = None,
    scheduler: str | None = None,
    object_name: str | Sequence[str] = "cube",
) -> list[dict]:
    """Run the missing trials of an experiment or a campaign into ``out_dir``; return the summary rows.

    - ``thresholds`` (``"0.29,0.5,1"`` or a sequence, in mm) sweeps the threshold and replaces
      ``threshold_mm``; ``cell`` is one cell (``ideal``, ``real``, ``FILE.toml``) or several
      (``"ideal,real"`` or a sequence); ``object_name`` (``--object``) one part's type, a built-in
      type's name (``cube``, ``bar``), or several (``"cube,bar"`` or a sequence). The campaign is
      their product. One threshold, one cell and one type (no ``thresholds``) write straight into
      ``out_dir``; otherwise every combination gets its folder (``Combination.folder``), ``out_dir``
      gets ``campaign.json`` and ``thresholds.png``, and each returned row also names its
      ``threshold_mm``, ``cell``, ``object`` and ``folder``.
    - ``executor``: ``"local"`` (a process pool of ``workers`` processes, each trial in its own
      pybullet world; one worker runs in this process), ``"dask"`` (``bt_arrange_sim.executors``:
      a ``LocalCluster`` of ``workers``, or the cluster at ``scheduler``), or any
      ``concurrent.futures.Executor``.
    - ``on_trial(record, done, total)`` reports progress.

    Raises ``CampaignIncompleteError`` (with the summary of what finished) when a trial did not come
    back, after writing what did.
    """
    whole_number("--seed", seed, style="unit")
    try:
        check_threshold(threshold_mm)
    except PlanError as error:
        raise PlanError(f"--threshold-mm {threshold_mm!r}: {error}") from error
    combos, flat = _plan(threshold_mm, cell, strategy, thresholds, executor, workers, scheduler, object_name)
    rows = list(rows)
    check_object_rows(object_name, rows)
    if executor == "dask":
        from bt_arrange_sim import executors

        opened: contextlib.AbstractContextManager[Executor | None] = executors.open_executor("dask", workers, scheduler)
    else:
        # "local" is this module's own process pool (run_campaign makes it from ``workers``).
        opened = contextlib.nullcontext(None if isinstance(executor, str) else executor)
    with opened as pool:
        result = run_campaign(
            rows, trials, seed, combos, out_dir, workers=workers, executor=pool, on_trial=on_trial, flat=flat
        )
    if flat:
        summary = result.summaries[combos[0]]
    else:
        summary = campaign_rows(result.summaries, result.folders)
    if result.lost:
        spec, reason = result.lost[0]
        raise CampaignIncompleteError(
            f"{len(result.lost)} trial(s) did not finish (first: {spec.row} #{spec.index}: {reason}); "
            "what finished is written: rerun the same command to complete the rest",
            summary=summary,
        )
    return summary


def run_campaign(
    rows: Iterable[str],
    trials: int,
    seed: int,
    combos: Sequence[Combination],
    out_dir: Path,
    *,
    workers: int = 1,
    executor: Executor | None = None,
    on_trial: Callable[[dict, int, int], None] | None = None,
    flat: bool = False,
) -> CampaignResult:
    """Run every missing trial of every combination, each appended to its folder's ``trials.jsonl`` as it ends.

    A combination's folder is ``out_dir/<combination.folder>`` (``out_dir`` itself when ``flat``,
    for a single combination). All trials go to one executor at once, so the workers stay busy
    across combinations. A trial whose future fails (a dead worker) is listed in ``lost`` and the
    others go on; a rerun runs it. Writes each combination's summaries and Fig. 4 and, for more
    than one, the campaign's ``campaign.json`` and ``thresholds.png``.
    """
    rows = list(rows)
    combos = list(combos)
    whole_number("--seed", seed, style="unit")
    if trials < 1:
        raise PlanError(f"--trials must be at least 1, got {trials}")
    if workers < 1:
        raise PlanError(f"--workers must be at least 1, got {workers}")
    for combination in combos:
        try:
            check_threshold(combination.threshold_mm)
        except PlanError as error:
            raise PlanError(f"threshold {combination.threshold_mm:g} mm: {error}") from error
    if flat and len(combos) != 1:
        raise PlanError("a flat experiment folder holds one combination; use a campaign folder for several")
    folders = {c: out_dir if flat else out_dir / c.folder for c in combos}
    specs: list[tuple[Combination, TrialSpec]] = []
    for combination in combos:
        folder = folders[combination]
        folder.mkdir(parents=True, exist_ok=True)
        existing = read_trials(folder / "trials.jsonl")
        for record in existing:
            if record.get("seed") != seed or not combination.owns(record):
                raise PlanError(
                    f"{folder / 'trials.jsonl'} holds trials of another experiment (seed {record.get('seed')}, "
                    f"threshold {record.get('threshold_mm')} mm, cell {record.get('cell', 'ideal')}, strategy "
                    f"{record.get('strategy', 'paper')}, object {record.get('object', 'cube')}); choose another --out "
                    f"for seed {seed}, threshold {combination.threshold_mm:g} mm, cell {combination.cell}, "
                    f"strategy {combination.strategy}, object {combination.object_name}"
                )
        done = {(record["row"], record["trial"]) for record in existing}
        # Trial by trial across the rows: an interrupted campaign has measured every row about as often.
        specs += [
            (combination, combination.spec(row, index, seed))
            for index in range(trials)
            for row in rows
            if (row, index) not in done
        ]
    total = len(rows) * trials * len(combos)
    finished = total - len(specs)
    lost: list[tuple[TrialSpec, str]] = []
    own_executor = executor is None and workers > 1 and len(specs) > 1
    pool: Executor | None = ProcessPoolExecutor(max_workers=workers) if own_executor else executor
    outs = {c: (folders[c] / "trials.jsonl").open("a") for c in combos}
    try:

        def keep(combination: Combination, record: dict) -> None:
            nonlocal finished
            out = outs[combination]
            out.write(json.dumps(record) + "\n")
            out.flush()
            finished += 1
            if on_trial is not None:
                on_trial(record, finished, total)

        if pool is None:
            for combination, spec in specs:
                keep(combination, run_trial(spec))
        else:
            futures: dict[Future, tuple[Combination, TrialSpec]] = {
                pool.submit(run_trial, spec): (combination, spec) for combination, spec in specs
            }
            for future in as_completed(futures):
                combination, spec = futures[future]
                try:
                    record = future.result()
                except Exception as error:  # noqa: BLE001 - a dead worker loses its trial, not the campaign
                    lost.append((spec, f"{type(error).__name__}: {error}".strip()))
                    continue
                keep(combination, record)
    finally:
        for out in outs.values():
            out.close()
        if own_executor and pool is not None:
            pool.shutdown(cancel_futures=True)
    summaries = {}
    for combination in combos:
        folder = folders[combination]
        records = [r for r in read_trials(folder / "trials.jsonl") if r["row"] in rows and r["trial"] < trials]
        summary = summarise(records, rows)
        write_summary(summary, folder)
        plot_fig4(records, rows, folder / "fig4.png")
        summaries[combination] = summary
    if len(combos) > 1:
        write_campaign(summaries, folders, out_dir)
    return CampaignResult(summaries, folders, sorted(lost, key=lambda item: (item[0].row, item[0].index)))


def campaign_rows(summaries: dict[Combination, list[dict]], folders: dict[Combination, Path]) -> list[dict]:
    """Every combination's summary rows, each with its threshold, cell, strategy, part's type and folder name."""
    return [
        {
            "threshold_mm": c.threshold_mm,
            "cell": c.cell,
            "strategy": c.strategy,
            "object": c.object_name,
            "folder": folders[c].name,
            **row,
        }
        for c, summary in summaries.items()
        for row in summary
    ]


def write_campaign(summaries: dict[Combination, list[dict]], folders: dict[Combination, Path], out_dir: Path) -> None:
    """``campaign.json`` (every combination's summary rows, with its folder) and ``thresholds.png``."""
    rows = campaign_rows(summaries, folders)
    (out_dir / "campaign.json").write_text(json.dumps(rows, indent=2) + "\n")
    plot_thresholds(rows, out_dir / "thresholds.png")


def plot_thresholds(rows: list[dict], path: Path) -> None:
    """Final offset (camera, mean and max) and pushes (mean) against the threshold, one line per row."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (offset_ax, pushes_ax) = plt.subplots(1, 2, figsize=(10.5, 4.4))
    cells = list(dict.fromkeys(r.get("cell", "ideal") for r in rows))
    kinds = list(dict.fromkeys(r.get("object", "cube") for r in rows))
    for row_name, cell, kind in itertools.product(dict.fromkeys(r["row"] for r in rows), cells, kinds):
        mine = sorted(
            (
                r
                for r in rows
                if r["row"] == row_name
                and r.get("cell", "ideal") == cell
                and r.get("object", "cube") == kind
                and r["pushed_mean_mm"] is not None
            ),
            key=_threshold,
        )
        if not mine:
            continue
        # One line per row, and per cell and type when the campaign has several.
        extra = ([cell_label(cell)] if len(cells) > 1 else []) + ([kind] if len(kinds) > 1 else [])
        name = row_name if not extra else f"{row_name} ({', '.join(extra)})"
        thresholds = [r["threshold_mm"] for r in mine]
        (line,) = offset_ax.plot(thresholds, [r["pushed_mean_mm"] for r in mine], "o-", label=name)
        offset_ax.plot(thresholds, [r["pushed_max_mm"] for r in mine], "v:", color=line.get_color(), alpha=0.7)
        pushes_ax.plot(thresholds, [r["pushes_mean"] for r in mine], "o-", color=line.get_color(), label=name)
    every = sorted({r["threshold_mm"] for r in rows})
    offset_ax.plot(every, every, "k--", linewidth=1, label="threshold")
    for ax in (offset_ax, pushes_ax):
        ax.set_xscale("log")
        ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        ax.set_xticks(every, [f"{t:g}" for t in every])
        ax.set_xlabel("threshold [mm]")
        ax.grid(True, which="both", alpha=0.3)
    offset_ax.set_yscale("log")
    offset_ax.set_ylabel("offset after pushing [mm] (camera; o mean, v max)")
    pushes_ax.set_ylabel("pushes per trial (mean)")
    pushes_ax.legend(fontsize=7, ncol=2)
    fig.suptitle("Final offset and pushes against the threshold", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _threshold(row: dict) -> float:
    return float(row["threshold_mm"])


def summarise(records: list[dict], rows: list[str]) -> list[dict]:
    """One row of Table 1 per experiment row, with the paper's simulated values beside it."""
    summary = []
    for row in rows:
        mine = [r for r in records if r["row"] == row]
        placed = np.array([r["placed_mm"] for r in mine if r["placed_mm"] is not None])
        pushed = np.array([r["pushed_mm"] for r in mine if r["pushed_mm"] is not None])
        pushed_truth = np.array([r["pushed_truth_mm"] for r in mine if r["pushed_mm"] is not None])
        paper = PAPER_SIMULATION_MM.get(row, (None, None, None, None))
        summary.append(
            {
                "row": row,
                "label": ROW_LABELS[row],
                "trials": len(mine),
                "placed_mean_mm": _stat(placed, np.mean),
                "placed_std_mm": _stat(placed, np.std),
                "pushed_mean_mm": _stat(pushed, np.mean),
                "pushed_std_mm": _stat(pushed, np.std),
                "pushed_max_mm": _stat(pushed, np.max),
                "pushes_mean": _stat(np.array([r["pushes"] for r in mine], dtype=float), np.mean),
                "success_rate": round(sum(r["status"] == "within" for r in mine) / len(mine), 4) if mine else None,
                "pushed_truth_mean_mm": _stat(pushed_truth, np.mean),
                "pushed_truth_max_mm": _stat(pushed_truth, np.max),
                "failed_trials": sum(r["status"] == "failed" for r in mine),
                "regrasp_trials": sum(r.get("regrasps", 0) > 0 for r in mine),
                "squared_trials": sum(r.get("squarings", 0) > 0 for r in mine),
                "paper_placed_mean_mm": paper[0],
                "paper_placed_std_mm": paper[1],
                "paper_pushed_mean_mm": paper[2],
                "paper_pushed_std_mm": paper[3],
            }
        )
    return summary


def _stat(values: np.ndarray, function: Callable[[np.ndarray], float]) -> float | None:
    return round(float(function(values)), 4) if values.size else None


def write_summary(summary: list[dict], out_dir: Path) -> None:
    """``summary.json``, ``summary.csv`` and the Markdown table ``summary.md``."""
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    with (out_dir / "summary.csv").open("w", newline="") as out:
        writer = csv.DictWriter(out, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(summary)
    (out_dir / "summary.md").write_text(markdown_table(summary))


def markdown_table(summary: list[dict]) -> str:
    """Table 1 as Markdown: ours (camera) beside the paper's simulation, mean ± std in mm.

    A campaign's rows (``run_experiment`` with several combinations: each row names its ``folder``)
    give one table per combination, under a heading naming its threshold, cell, strategy, part's type
    (when not the cube) and folder.
    """
    if any("folder" in s for s in summary):
        parts = []
        for folder in dict.fromkeys(s["folder"] for s in summary):
            mine = [s for s in summary if s["folder"] == folder]
            first = mine[0]
            parts.append(
                f"## threshold {first['threshold_mm']:g} mm, cell {cell_label(first['cell'])}, "
                f"strategy {first['strategy']}"
                + (f", object {first['object']}" if first.get("object", "cube") != "cube" else "")
                + f" ({folder})\n\n"
                + _table(mine)
            )
        return "\n".join(parts)
    return _table(summary)


def _table(summary: list[dict]) -> str:

    def pm(mean: float | None, std: float | None) -> str:
        return "-" if mean is None or std is None else f"{mean:.2f} ± {std:.2f}"

    lines = [
        "| row | trials | after placing | after pushing | paper: after placing | paper: after pushing "
        "| pushes (mean) | within threshold | max after pushing | regrasped trials | squared in the grasp "
        "| ground truth after pushing (mean / max) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for s in summary:
        truth = (
            "-"
            if s["pushed_truth_mean_mm"] is None
            else f"{s['pushed_truth_mean_mm']:.2f} / {s['pushed_truth_max_mm']:.2f}"
        )
        success = "-" if s["success_rate"] is None else f"{s['success_rate'] * 100:.0f} %"
        lines.append(
            f"| {s['label']} | {s['trials']} | {pm(s['placed_mean_mm'], s['placed_std_mm'])} "
            f"| {pm(s['pushed_mean_mm'], s['pushed_std_mm'])} "
            f"| {pm(s['paper_placed_mean_mm'], s['paper_placed_std_mm'])} "
            f"| {pm(s['paper_pushed_mean_mm'], s['paper_pushed_std_mm'])} "
            f"| {_mm_or_dash(s['pushes_mean'])} | {success} | {_mm_or_dash(s.get('pushed_max_mm'))} "
            f"| {s.get('regrasp_trials', 0)} | {s.get('squared_trials', 0)} | {truth} |"
        )
    return (
        "Offsets Δd_xy in mm, mean ± std, measured by the top camera (as in the paper); ground truth from the "
        "simulator. Paper: Table 1 a), simulation.\n\n" + "\n".join(lines) + "\n"
    )


def _mm_or_dash(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def plot_fig4(records: list[dict], rows: list[str], path: Path) -> None:
    """Box plots of the offsets after placing and after pushing per row, log axis, median and mean marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(rows), figsize=(max(3.2 * len(rows), 5.5), 4.6), sharey=True, squeeze=False)
    for ax, row in zip(axes[0], rows, strict=True):
        mine = [r for r in records if r["row"] == row]
        data = [
            [max(r["placed_mm"], 1e-3) for r in mine if r["placed_mm"] is not None],
            [max(r["pushed_mm"], 1e-3) for r in mine if r["pushed_mm"] is not None],
        ]
        if all(data):
            ax.boxplot(
                data,
                tick_labels=["after\nplacing", "after\npushing"],
                showmeans=True,
                patch_artist=True,
                medianprops={"color": "white", "linewidth": 2},
                meanprops={"marker": "o", "markerfacecolor": "black", "markeredgecolor": "black"},
                boxprops={"facecolor": "tab:blue"},
            )
        ax.set_yscale("log")
        ax.set_title(ROW_LABELS[row].replace(" (substitute", "\n(substitute"), fontsize=9)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    axes[0][0].set_ylabel("offset Δd_xy [mm] (camera)")
    fig.suptitle("Offsets after placing and after pushing\n(white line: median, black dot: mean)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
