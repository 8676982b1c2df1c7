"""The paper's evaluation (Sec. 5.3, Table 1, Fig. 4) as one reproducible experiment.

Each row runs its trials with a single-cube arrangement (a random start and a random target per
trial, both seeded from the experiment's seed, the row and the trial number), with the row's
injected error. Each finished trial is appended to ``trials.jsonl`` at once; a rerun into the
same folder skips the trials already there. Offsets are the camera's measurements, as in the
paper; the simulator's ground truth is recorded beside them.
"""

from __future__ import annotations

import csv
import json
import math
import time
from collections.abc import Callable, Iterable
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bt_arrange.checks import whole_number
from bt_arrange.errors import PlanError
from bt_arrange.trees import check_threshold

#: Rows of Table 1, in the paper's order.
ROWS = ("system", "translation", "orientation", "grasp-estimator")
ROW_LABELS = {
    "system": "1) System accuracy",
    "translation": "2) Translation error",
    "orientation": "3) Orientation error",
    "grasp-estimator": "4) Depth-only grasp estimator (substitute for Berscheid et al.)",
}
#: Table 1 a), simulation: mean and std in mm after placing and after pushing.
PAPER_SIMULATION_MM = {
    "system": (0.47, 0.29, 0.40, 0.25),
    "translation": (8.54, 5.70, 0.45, 0.41),
    "orientation": (3.03, 4.70, 0.43, 0.25),
    "grasp-estimator": (5.18, 3.83, 0.41, 0.25),
}
#: Targets of the trials: inside the camera's view and the arm's comfortable reach.
TARGET_X_RANGE_M = (0.38, 0.62)
TARGET_Y_RANGE_M = (-0.25, 0.25)


@dataclass(frozen=True)
class TrialSpec:
    """One trial: which row, which number, and the experiment's settings."""

    row: str
    index: int
    seed: int
    threshold_mm: float
    #: The cell: ``ideal``, ``real`` or a ``.toml`` file (``bt_arrange_sim.realcell.parse_cell``).
    cell: str = "ideal"
    #: The push strategy: ``paper`` (Table 1's) or ``learned`` (``bt_arrange.behaviours.Push``).
    strategy: str = "paper"


def parse_rows(text: str) -> list[str]:
    """Rows from a comma-separated list; a ``PlanError`` names an unknown one and the known ones."""
    rows = [row.strip() for row in text.split(",") if row.strip()]
    if not rows:
        raise PlanError(f"--rows is empty; choose from {', '.join(ROWS)}")
    for row in rows:
        if row not in ROWS:
            raise PlanError(f"unknown row {row!r}; the rows are {', '.join(ROWS)}")
    return rows


def run_trial(spec: TrialSpec) -> dict:
    """Run one trial in a fresh cell and return its record (a JSON-able dict)."""
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
    return {
        "row": spec.row,
        "trial": spec.index,
        "seed": spec.seed,
        "threshold_mm": spec.threshold_mm,
        "cell": spec.cell,
        "strategy": spec.strategy,
        "target": [round(v, 6) for v in outcome.target],
        "placed_mm": outcome.placed_offset_mm,
        "pushed_mm": outcome.final_offset_mm,
        "placed_truth_mm": outcome.placed_offset_truth_mm,
        "pushed_truth_mm": outcome.final_offset_truth_mm,
        "pushes": outcome.pushes,
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


def check_options(cell: str = "ideal", strategy: str = "paper") -> None:
    """``--cell`` and ``--strategy``, checked before anything runs; a one-line ``PlanError`` otherwise."""
    from bt_arrange.trees import check_strategy
    from bt_arrange_sim.realcell import parse_cell

    try:
        check_strategy(strategy)
    except PlanError as error:
        raise PlanError(f"--strategy {strategy!r}: {error}") from error
    try:
        parse_cell(cell)
    except PlanError as error:
        raise PlanError(f"--cell {cell}: {error}") from error


def row_injectors(row: str) -> list:
    """The errors a row injects: the paper's picking errors, right after detection, before the grasp."""
    if row == "translation":
        from bt_arrange_sim.injection import PickTranslation

        return [PickTranslation()]
    if row == "orientation":
        from bt_arrange_sim.injection import PickRotation

        return [PickRotation()]
    return []


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
    cell: str = "ideal",
    strategy: str = "paper",
) -> list[dict]:
    """Run every missing trial, appending each to ``out_dir/trials.jsonl`` as it ends; return the summary.

    ``executor`` (any ``concurrent.futures.Executor``) runs the trials; by default a process pool
    of ``workers`` processes, each trial in its own pybullet world. ``on_trial(record, done, total)``
    reports progress.
    """
    rows = list(rows)
    whole_number("--seed", seed, style="unit")
    try:
        check_threshold(threshold_mm)
    except PlanError as error:
        raise PlanError(f"--threshold-mm {threshold_mm!r}: {error}") from error
    if trials < 1:
        raise PlanError(f"--trials must be at least 1, got {trials}")
    if workers < 1:
        raise PlanError(f"--workers must be at least 1, got {workers}")
    check_options(cell, strategy)
    out_dir.mkdir(parents=True, exist_ok=True)
    trials_path = out_dir / "trials.jsonl"
    existing = read_trials(trials_path)
    for record in existing:
        if (
            record.get("seed") != seed
            or record.get("threshold_mm") != threshold_mm
            or record.get("cell", "ideal") != cell
            or record.get("strategy", "paper") != strategy
        ):
            raise PlanError(
                f"{trials_path} holds trials of another experiment (seed {record.get('seed')}, threshold "
                f"{record.get('threshold_mm')} mm, cell {record.get('cell', 'ideal')}, strategy "
                f"{record.get('strategy', 'paper')}); choose another --out for seed {seed}, "
                f"threshold {threshold_mm} mm, cell {cell}, strategy {strategy}"
            )
    done = {(record["row"], record["trial"]) for record in existing}
    specs = [
        TrialSpec(row, index, seed, threshold_mm, cell, strategy)
        for row in rows
        for index in range(trials)
        if (row, index) not in done
    ]
    total = len(rows) * trials
    finished = total - len(specs)
    own_executor = executor is None and workers > 1 and len(specs) > 1
    pool: Executor | None = ProcessPoolExecutor(max_workers=workers) if own_executor else executor
    try:
        with trials_path.open("a") as out:

            def keep(record: dict) -> None:
                nonlocal finished
                out.write(json.dumps(record) + "\n")
                out.flush()
                finished += 1
                if on_trial is not None:
                    on_trial(record, finished, total)

            if pool is None:
                for spec in specs:
                    keep(run_trial(spec))
            else:
                futures: list[Future] = [pool.submit(run_trial, spec) for spec in specs]
                for future in as_completed(futures):
                    keep(future.result())
    finally:
        if own_executor and pool is not None:
            pool.shutdown(cancel_futures=True)
    records = [r for r in read_trials(trials_path) if r["row"] in rows and r["trial"] < trials]
    summary = summarise(records, rows)
    write_summary(summary, out_dir)
    plot_fig4(records, rows, out_dir / "fig4.png")
    return summary


def summarise(records: list[dict], rows: list[str]) -> list[dict]:
    """One row of Table 1 per experiment row, with the paper's simulated values beside it."""
    summary = []
    for row in rows:
        mine = [r for r in records if r["row"] == row]
        placed = np.array([r["placed_mm"] for r in mine if r["placed_mm"] is not None])
        pushed = np.array([r["pushed_mm"] for r in mine if r["pushed_mm"] is not None])
        pushed_truth = np.array([r["pushed_truth_mm"] for r in mine if r["pushed_mm"] is not None])
        paper = PAPER_SIMULATION_MM[row]
        summary.append(
            {
                "row": row,
                "label": ROW_LABELS[row],
                "trials": len(mine),
                "placed_mean_mm": _stat(placed, np.mean),
                "placed_std_mm": _stat(placed, np.std),
                "pushed_mean_mm": _stat(pushed, np.mean),
                "pushed_std_mm": _stat(pushed, np.std),
                "pushes_mean": _stat(np.array([r["pushes"] for r in mine], dtype=float), np.mean),
                "success_rate": round(sum(r["status"] == "within" for r in mine) / len(mine), 4) if mine else None,
                "pushed_truth_mean_mm": _stat(pushed_truth, np.mean),
                "pushed_truth_max_mm": _stat(pushed_truth, np.max),
                "failed_trials": sum(r["status"] == "failed" for r in mine),
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
        "| pushes (mean) | within threshold | ground truth after pushing (mean / max) |",
        "|---|---|---|---|---|---|---|---|---|",
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
            f"| {s['pushes_mean']} | {success} | {truth} |"
        )
    return (
        "Offsets Δd_xy in mm, mean ± std, measured by the top camera (as in the paper); ground truth from the "
        "simulator. Paper: Table 1 a), simulation.\n\n" + "\n".join(lines) + "\n"
    )


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
