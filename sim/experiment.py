"""The paper's evaluation (Sec. 5.3, Table 1, Fig. 4) as reproducible experiment campaigns.

Each row runs its trials with a single-cube arrangement (a random start and a random target per
trial, both seeded from the experiment's seed, the row and the trial number), with the row's
injected errors. A campaign is the product of its lists (today the thresholds; cells and objects
join the same way): every combination gets its own folder with ``trials.jsonl``, the summaries
and Fig. 4. Each finished trial is appended at once; a rerun into the same folder runs only the
trials missing there. Offsets are the camera's measurements, as in the paper; the simulator's
ground truth is recorded beside them.

Trials run through any ``concurrent.futures.Executor`` (``bt_arrange_sim.executors``: a local
process pool, or a Dask cluster through ``Client.get_executor()``). A trial is a pure function of
its ``TrialSpec``, so the records are the same (order and wall times aside) whatever runs them.
"""

from __future__ import annotations

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

from bt_arrange.errors import BtArrangeError, PlanError

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


@dataclass(frozen=True)
class Combination:
    """One point of a campaign's product of lists (today: the threshold; cells and objects join here)."""

    threshold_mm: float

    @property
    def folder(self) -> str:
        """The combination's folder name inside the campaign folder."""
        return f"threshold-{self.threshold_mm:g}mm"

    def spec(self, row: str, index: int, seed: int) -> TrialSpec:
        """The trial ``index`` of ``row`` under this combination."""
        return TrialSpec(row, index, seed, self.threshold_mm)

    def owns(self, record: dict) -> bool:
        """True when ``record`` is a trial of this combination."""
        return record.get("threshold_mm") == self.threshold_mm


def combinations(thresholds_mm: Sequence[float]) -> list[Combination]:
    """The campaign: the product of the lists (one list today), in order, duplicates removed."""
    seen: list[Combination] = []
    for (threshold_mm,) in itertools.product(thresholds_mm):
        combination = Combination(float(threshold_mm))
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
    """Thresholds in mm from a comma-separated list (``0.25,0.5,1,2``); a ``PlanError`` names a bad one."""
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
        values.append(value)
    if not values:
        raise PlanError("--thresholds is empty; give millimetres such as 0.25,0.5,1,2")
    return values


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
    target = Target(
        "red",
        float(rng.uniform(*TARGET_X_RANGE_M)),
        float(rng.uniform(*TARGET_Y_RANGE_M)),
        float(rng.uniform(-math.pi / 4, math.pi / 4)),
    )
    starts = scatter(["red"], int(rng.integers(2**31)), avoid=[target])
    if spec.row == "grasp-estimator":
        root = _depth_grasp_tree(target, spec.threshold_mm, int(rng.integers(2**31)))
    else:
        root = arrangement([target], threshold_mm=spec.threshold_mm, max_pushes=10)
    injectors = row_injectors(spec.row)
    injection_seed = int(rng.integers(2**31))
    with SimulatedRun(root, starts) as run:
        if injectors:
            from bt_arrange_sim.injection import attach_all

            attach_all(run, "red", injectors, injection_seed)
        report = run.run()
    (outcome,) = report.objects
    bad_grasps = [t.feedback for t in report.transitions if t.kind == "Pick" and t.new == "FAILURE"]
    return {
        "row": spec.row,
        "trial": spec.index,
        "seed": spec.seed,
        "threshold_mm": spec.threshold_mm,
        "target": [round(v, 6) for v in outcome.target],
        "placed_mm": outcome.placed_offset_mm,
        "pushed_mm": outcome.final_offset_mm,
        "placed_truth_mm": outcome.placed_offset_truth_mm,
        "pushed_truth_mm": outcome.final_offset_truth_mm,
        "pushes": outcome.pushes,
        "regrasps": len(bad_grasps),
        "regrasp_reasons": bad_grasps,
        "status": outcome.status,
        "reason": outcome.reason,
        "injected": {injector.name: injector.record() for injector in injectors},
        "sim_seconds": round(report.sim_seconds, 3),
        "wall_seconds": round(time.perf_counter() - wall_start, 3),
    }


def row_injectors(row: str) -> list:
    """The errors a row injects (``ROW_INJECTORS``), each at its default magnitude, fresh for one run."""
    specs = ROW_INJECTORS[row]
    if not specs:
        return []
    from bt_arrange_sim.injection import make_injectors

    return make_injectors(specs)


def _depth_grasp_tree(target, threshold_mm: float, seed: int):  # noqa: ANN001, ANN202 - py_trees types
    """Algorithm 1 with line 6 (pose estimation before picking) done by the depth-only substitute."""
    import py_trees

    from bt_arrange.behaviours import Inspect, MoveHome
    from bt_arrange.behaviours.grasp_estimation import transfer_with_depth_grasp
    from bt_arrange.trees import Arrangement, correction, set_target

    arrange = py_trees.composites.Sequence(
        name=f"arrange {target.obj}",
        memory=True,
        children=[
            set_target(target),
            transfer_with_depth_grasp(target, seed=seed),
            Inspect(f"inspect {target.obj} after placing", target.obj, target.colour, after_placing=True),
            correction(target, threshold_mm, max_pushes=10),
        ],
    )
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
    """Some trials did not come back (a worker died, the cluster went away); a rerun completes them."""


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
    executor: Executor | None = None,
    on_trial: Callable[[dict, int, int], None] | None = None,
) -> list[dict]:
    """One combination written straight into ``out_dir``: run the missing trials, return the summary.

    ``executor`` (any ``concurrent.futures.Executor``) runs the trials; by default a process pool
    of ``workers`` processes, each trial in its own pybullet world. ``on_trial(record, done, total)``
    reports progress. Raises ``CampaignIncompleteError`` when a trial did not come back (after
    writing what did).
    """
    combination = Combination(float(threshold_mm))
    result = run_campaign(
        rows, trials, seed, [combination], out_dir, workers=workers, executor=executor, on_trial=on_trial, flat=True
    )
    _raise_if_lost(result)
    return result.summaries[combination]


def _raise_if_lost(result: CampaignResult) -> None:
    if result.lost:
        spec, error = result.lost[0]
        raise CampaignIncompleteError(
            f"{len(result.lost)} trial(s) did not finish (first: {spec.row} #{spec.index}: {error}); "
            "what finished is written: rerun the same command to complete the rest"
        )


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
    if trials < 1:
        raise PlanError(f"--trials must be at least 1, got {trials}")
    if workers < 1:
        raise PlanError(f"--workers must be at least 1, got {workers}")
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
                    f"threshold {record.get('threshold_mm')} mm); choose another --out for seed {seed}, "
                    f"threshold {combination.threshold_mm:g} mm"
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


def write_campaign(summaries: dict[Combination, list[dict]], folders: dict[Combination, Path], out_dir: Path) -> None:
    """``campaign.json`` (every combination's summary rows, with its folder) and ``thresholds.png``."""
    rows = [
        {"threshold_mm": c.threshold_mm, "folder": folders[c].name, **row}
        for c, summary in summaries.items()
        for row in summary
    ]
    (out_dir / "campaign.json").write_text(json.dumps(rows, indent=2) + "\n")
    plot_thresholds(rows, out_dir / "thresholds.png")


def plot_thresholds(rows: list[dict], path: Path) -> None:
    """Final offset (camera, mean and max) and pushes (mean) against the threshold, one line per row."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (offset_ax, pushes_ax) = plt.subplots(1, 2, figsize=(10.5, 4.4))
    for name in dict.fromkeys(r["row"] for r in rows):
        mine = sorted((r for r in rows if r["row"] == name and r["pushed_mean_mm"] is not None), key=_threshold)
        if not mine:
            continue
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
    """Table 1 as Markdown: ours (camera) beside the paper's simulation, mean ± std in mm."""

    def pm(mean: float | None, std: float | None) -> str:
        return "-" if mean is None or std is None else f"{mean:.2f} ± {std:.2f}"

    lines = [
        "| row | trials | after placing | after pushing | paper: after placing | paper: after pushing "
        "| pushes (mean) | within threshold | max after pushing | regrasped trials "
        "| ground truth after pushing (mean / max) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
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
            f"| {s.get('regrasp_trials', 0)} | {truth} |"
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
