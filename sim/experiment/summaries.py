"""What the trials add up to: Table 1's rows, the summary files, Fig. 4, the campaign's figure.

``summary.json``, ``summary.csv`` and ``summary.md`` per folder; ``campaign.json`` and
``thresholds.png`` for a campaign of several combinations.
"""

from __future__ import annotations

import csv
import io
import itertools
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bt_arrange import files
from bt_arrange_sim.experiment.options import Combination, cell_label
from bt_arrange_sim.experiment.rows import PAPER_REAL_MM, PAPER_SIMULATION_MM, ROW_LABELS


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


def write_campaign(
    summaries: dict[Combination, list[dict]],
    folders: dict[Combination, Path],
    out_dir: Path,
    faults: files.Faults | None = None,
) -> None:
    """``campaign.json`` (every combination's summary rows, with its folder) and ``thresholds.png``.

    Each file whole or absent; with ``faults``, one that cannot be written is noted there and the next is tried.
    """
    rows = campaign_rows(summaries, folders)
    faults = faults if faults is not None else _Raising()
    with faults.guard(out_dir / "campaign.json"):
        files.write_json(out_dir / "campaign.json", rows)
    with faults.guard(out_dir / "thresholds.png"):
        plot_thresholds(rows, out_dir / "thresholds.png")


class _Raising(files.Faults):
    """Faults that are raised at once (for callers that hand in none)."""

    def add(self, path: Path | str, error: OSError) -> files.WriteFault:
        raise error


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
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)


def _threshold(row: dict) -> float:
    return float(row["threshold_mm"])


def summarise(records: list[dict], rows: list[str]) -> list[dict]:
    """One row of Table 1 per experiment row, with the paper's values beside it.

    The paper's simulated column, or its real robot's for trials in a model of the real cell
    (``--cell real``); ``paper_column`` says which. Errored trials (``status = "error"``: no
    measurement) are counted apart, in ``errored_trials``.
    """
    summary = []
    for row in rows:
        errored = sum(r["row"] == row and r.get("status") == "error" for r in records)
        mine = [r for r in records if r["row"] == row and r.get("status") != "error"]
        placed = np.array([r["placed_mm"] for r in mine if r["placed_mm"] is not None])
        pushed = np.array([r["pushed_mm"] for r in mine if r["pushed_mm"] is not None])
        pushed_truth = np.array([r["pushed_truth_mm"] for r in mine if r["pushed_mm"] is not None])
        real = bool(mine) and all(r.get("cell", "ideal") != "ideal" for r in mine)
        paper = (PAPER_REAL_MM if real else PAPER_SIMULATION_MM).get(row, (None, None, None, None))
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
                "errored_trials": errored,
                "paper_placed_mean_mm": paper[0],
                "paper_placed_std_mm": paper[1],
                "paper_pushed_mean_mm": paper[2],
                "paper_pushed_std_mm": paper[3],
                "paper_column": "real robot" if real else "simulation",
            }
        )
    return summary


def _stat(values: np.ndarray, function: Callable[[np.ndarray], float]) -> float | None:
    return round(float(function(values)), 4) if values.size else None


def write_summary(summary: list[dict], out_dir: Path, faults: files.Faults | None = None) -> None:
    """``summary.json``, ``summary.csv`` and the Markdown table ``summary.md``, each whole or absent.

    With ``faults``, a file that cannot be written is noted there and the next one is tried.
    """
    faults = faults if faults is not None else _Raising()
    with faults.guard(out_dir / "summary.json"):
        files.write_json(out_dir / "summary.json", summary)
    table = io.StringIO(newline="")
    writer = csv.DictWriter(table, fieldnames=list(summary[0]))
    writer.writeheader()
    writer.writerows(summary)
    with faults.guard(out_dir / "summary.csv"):
        files.write_text(out_dir / "summary.csv", table.getvalue())
    with faults.guard(out_dir / "summary.md"):
        files.write_text(out_dir / "summary.md", markdown_table(summary))


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
    errored = sum(s.get("errored_trials", 0) for s in summary)
    if errored:
        lines.append(
            f"\n{errored} trial(s) errored and are not counted above "
            "(trials.jsonl gives each one's reason; --resume reruns them)."
        )
    columns = sorted({s.get("paper_column", "simulation") for s in summary})
    return (
        "Offsets Δd_xy in mm, mean ± std, measured by the top camera (as in the paper); ground truth from the "
        f"simulator. Paper: Table 1, {' and '.join(columns)} column.\n\n" + "\n".join(lines) + "\n"
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
                tick_labels=[f"after\nplacing\nn = {len(data[0])}", f"after\npushing\nn = {len(data[1])}"],
                showmeans=True,
                patch_artist=True,
                medianprops={"color": "white", "linewidth": 2},
                meanprops={"marker": "o", "markerfacecolor": "black", "markeredgecolor": "black"},
                boxprops={"facecolor": "tab:blue"},
            )
        thresholds = sorted({float(r["threshold_mm"]) for r in mine if r.get("threshold_mm") is not None})
        for threshold in thresholds:
            ax.axhline(threshold, color="tab:red", linestyle="--", linewidth=1, label=f"threshold {threshold:g} mm")
        if thresholds:
            ax.legend(loc="upper right", fontsize=7)
        ax.set_yscale("log")
        ax.set_title(ROW_LABELS[row].replace(" (substitute", "\n(substitute"), fontsize=9)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    axes[0][0].set_ylabel("offset Δd_xy [mm] (camera)")
    fig.suptitle(
        "Offsets after placing and after pushing\n(white line: median, black dot: mean, n: trials per box)",
        fontsize=10,
    )
    fig.tight_layout()
    files.save_figure(fig, path, dpi=120)
    plt.close(fig)
