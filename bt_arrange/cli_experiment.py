"""``bt-arrange experiment``: a campaign of the paper's rows on a backend, and its summary."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from bt_arrange import backends
from bt_arrange.backends import Backend, Experiment
from bt_arrange.cli_common import (
    EXIT_OK,
    _check_threshold_option,
    _note_uncalibrated,
)
from bt_arrange.errors import BackendError, BtArrangeError, RecordError


def _experiment_of(backend: Backend) -> Experiment:
    experiment = backend.experiment
    if experiment is None:
        raise BackendError(f"backend {backend.name!r} cannot run the experiment")
    return experiment


#: The experiment's options beyond the Protocol's arguments, with their defaults: only a value other
#: than its default is passed on, so a backend that has not these options need not know them.
EXPERIMENT_OPTIONS = (
    ("cell", "ideal"),
    ("strategy", "paper"),
    ("thresholds", None),
    ("object_name", "cube"),
    ("executor", "local"),
    ("scheduler", None),
    ("calibration", None),
    ("resume", False),
    ("record", None),
)


def _experiment_options(
    backend: Backend, experiment: Experiment, args: argparse.Namespace, rows: list[str]
) -> dict[str, Any]:
    """The experiment's options (``EXPERIMENT_OPTIONS``), checked by the backend's ``check_options``.

    Only non-defaults are passed on; ``--workers`` is one of the Protocol's own arguments. With
    ``--object``, the check also gets the rows (a row may not know every type).
    """
    options = {key: getattr(args, key) for key, default in EXPERIMENT_OPTIONS if getattr(args, key) != default}
    check = experiment.check_options if isinstance(experiment, backends.OptionedExperiment) else None
    if options and check is None:
        raise BackendError(f"backend {backend.name!r} has no {', '.join('--' + key for key in options)}")
    if check is not None:
        check(
            cell=args.cell,
            strategy=args.strategy,
            workers=args.workers,
            **({"rows": rows} if "object_name" in options else {}),
            **{key: value for key, value in options.items() if key not in ("cell", "strategy")},
        )
    _note_uncalibrated(args.cell, args.calibration)
    return options


def _print_experiment(
    experiment: Experiment, summary: list[dict[str, Any]], out: Path, *, recorded: bool = True
) -> None:
    print(experiment.markdown_table(summary), end="")
    if not recorded:
        print(f"the record in {out} is incomplete (the line on stderr says which file and why)")
    elif any("folder" in row for row in summary):
        print(
            f"trials.jsonl, summary.json, summary.csv, summary.md and fig4.png in each folder of {out}; "
            f"campaign.json and thresholds.png (final offset and pushes against the threshold) in {out}"
        )
    else:
        print(f"trials.jsonl, summary.json, summary.csv, summary.md and fig4.png in {out}")


def backend_names(text: str) -> list[str]:
    """``--backend``'s names: one, or several comma-separated (``sim,mujoco``), each once."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise BtArrangeError("--backend is empty; give a backend's name, or several comma-separated (sim,mujoco)")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise BtArrangeError(f"--backend names {', '.join(repeated)} more than once")
    return names


def _experiment(args: argparse.Namespace) -> int:
    names = backend_names(args.backend)
    if len(names) == 1:
        args.backend = names[0]
        return _experiment_on_one(args)
    return _experiment_side_by_side(args, names)


def _experiment_side_by_side(args: argparse.Namespace, names: list[str]) -> int:
    """``--backend sim,mujoco``: the same campaign on each backend, one folder each, then a side-by-side summary.

    Every backend and its options are checked before the first trial runs; each backend's campaign
    goes into ``--out/NAME`` (resumable on its own), and ``--out`` gets ``engines.md`` and
    ``engines.json``: each row's figures in every engine, side by side.
    """
    import copy

    checked = []
    for name in names:
        backend = backends.load(name)
        experiment = _experiment_of(backend)
        one = copy.copy(args)
        one.backend, one.out = name, args.out / name
        one.record = args.record / name if args.record is not None else None
        rows = experiment.parse_rows(args.rows)
        if args.thresholds is not None and args.threshold_mm is not None:
            raise BtArrangeError("give --threshold-mm or --thresholds, not both")
        _check_threshold_option(args.threshold_mm)
        _experiment_options(backend, experiment, one, rows)
        checked.append(one)
    try:
        backends.load(names[0]).prepare_out(args.out)
    except BtArrangeError as error:
        raise BtArrangeError(f"--out {args.out}: {error}") from error
    summaries: dict[str, list[dict[str, Any]]] = {}
    for one in checked:
        print(f"## {one.backend} ({one.out})")
        summaries[one.backend] = _campaign_on_one(one)
    from bt_arrange import files

    table = side_by_side_markdown(summaries)
    files.write_text(args.out / "engines.md", table)
    files.write_json(args.out / "engines.json", side_by_side_rows(summaries))
    print("## side by side")
    print(table, end="")
    folders = ", ".join(str(one.out) for one in checked)
    print(f"each backend's campaign in {folders}; engines.md and engines.json in {args.out}")
    return EXIT_OK


def _experiment_on_one(args: argparse.Namespace) -> int:
    """One backend's campaign, its table printed."""
    _campaign_on_one(args)
    return EXIT_OK


def _campaign_on_one(args: argparse.Namespace) -> list[dict[str, Any]]:
    """One backend's campaign, its table printed; the summary rows."""
    from tqdm import tqdm

    backend = backends.load(args.backend)
    experiment = _experiment_of(backend)
    # Every option is checked before the progress bar is drawn or a worker starts.
    rows = experiment.parse_rows(args.rows)
    if args.thresholds is not None and args.threshold_mm is not None:
        raise BtArrangeError("give --threshold-mm or --thresholds, not both")
    _check_threshold_option(args.threshold_mm)
    options = _experiment_options(backend, experiment, args, rows)
    try:
        backend.prepare_out(args.out)
    except BtArrangeError as error:
        raise BtArrangeError(f"--out {args.out}: {error}") from error
    # The total grows to the campaign's size (thresholds x cells) with the first finished trial.
    bar = tqdm(total=len(rows) * args.trials, unit="trial", desc="trials", file=sys.stderr, dynamic_ncols=True)

    def progress(record: dict, done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        where = f"{record['threshold_mm']:g} mm" + (
            f", {record['cell']} cell" if record.get("cell", "ideal") != "ideal" else ""
        )
        bar.set_postfix_str(f"{record['row']} #{record['trial']} at {where}: {record['status']}", refresh=False)
        bar.refresh()

    try:
        summary = experiment.run_experiment(
            rows,
            args.trials,
            args.seed,
            1.0 if args.threshold_mm is None else args.threshold_mm,
            args.out,
            workers=args.workers,
            on_trial=progress,
            **options,
        )
    except BtArrangeError as error:
        # Trials that errored, or files that could not be written: the summary is printed, then the one line.
        finished = error.result if isinstance(error, RecordError) else getattr(error, "summary", None)
        if finished:
            bar.close()
            _print_experiment(experiment, finished, args.out, recorded=not isinstance(error, RecordError))
        raise
    finally:
        bar.close()
    _print_experiment(experiment, summary, args.out)
    if args.record is not None:
        where = "ROW/trial-NNNN.mcap" if all("folder" not in row for row in summary) else "COMBINATION/ROW/..."
        print(f"one MCAP per trial in {args.record} ({where}; each record's mcap key names its file)")
    return summary


# ----------------------------------------------------------------------------------------------
# Several backends' summaries side by side (--backend sim,mujoco)
# ----------------------------------------------------------------------------------------------
# The summary rows an ``Experiment`` returns (``row``, ``label``, ``trials``, the means and standard
# deviations after placing and after pushing, pushes, the within-threshold rate and, where the
# backend has ground truth, its figures); a figure a backend does not give is shown as ``-``.
# Engines whose means after pushing differ by more than the larger of their standard deviations
# are marked: the difference is larger than the trials' spread.

#: What names one line of a campaign besides its row (a campaign of several thresholds or cells).
_KEYS = ("row", "threshold_mm", "cell", "object")


def _key(row: Mapping[str, Any]) -> tuple:
    return tuple(row.get(k) for k in _KEYS)


def _number(value: Any, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def _mean_std(row: Mapping[str, Any], stem: str) -> str:
    mean, std = row.get(f"{stem}_mean_mm"), row.get(f"{stem}_std_mm")
    return "-" if mean is None else f"{mean:.2f} ± {_number(std)}"


def side_by_side_rows(summaries: Mapping[str, Sequence[Mapping[str, Any]]]) -> list[dict[str, Any]]:
    """One dict per campaign line: its row (and threshold, cell, type) and each engine's summary by name.

    ``differ_after_pushing`` is True when two engines' means after pushing are further apart than
    the larger of their standard deviations (None with fewer than two engines or figures).
    """
    order: list[tuple] = []
    by_key: dict[tuple, dict[str, Any]] = {}
    for engine, rows in summaries.items():
        for row in rows:
            key = _key(row)
            if key not in by_key:
                order.append(key)
                by_key[key] = {k: v for k, v in zip(_KEYS, key, strict=True) if v is not None}
                by_key[key]["label"] = row.get("label", row.get("row"))
                by_key[key]["engines"] = {}
            by_key[key]["engines"][engine] = dict(row)
    lines = []
    for key in order:
        line = by_key[key]
        figures = [
            (r.get("pushed_mean_mm"), r.get("pushed_std_mm") or 0.0)
            for r in line["engines"].values()
            if r.get("pushed_mean_mm") is not None
        ]
        differ = None
        if len(figures) >= 2:
            means = [m for m, _ in figures]
            differ = bool(max(means) - min(means) > max(s for _, s in figures))
        line["differ_after_pushing"] = differ
        lines.append(line)
    return lines


def side_by_side_markdown(summaries: Mapping[str, Sequence[Mapping[str, Any]]]) -> str:
    """The campaign's lines, each engine's figures under one another: a Markdown table."""
    header = (
        "| row | engine | trials | after placing | after pushing | pushes (mean) | within threshold "
        "| ground truth after pushing (mean / max) | engines differ beyond the spread |\n"
        "|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for line in side_by_side_rows(summaries):
        extra = [f"{line[k]:g} mm" if k == "threshold_mm" else str(line[k]) for k in _KEYS[1:] if k in line]
        label = str(line["label"]) + (f" ({', '.join(extra)})" if extra else "")
        for k, (engine, row) in enumerate(line["engines"].items()):
            rate = row.get("success_rate")
            truth = (
                "-"
                if row.get("pushed_truth_mean_mm") is None
                else f"{row['pushed_truth_mean_mm']:.2f} / {_number(row.get('pushed_truth_max_mm'))}"
            )
            differ = "" if k else {None: "-", True: "yes", False: "no"}[line["differ_after_pushing"]]
            lines.append(
                f"| {label if k == 0 else ''} | {engine} | {row.get('trials', '-')} | {_mean_std(row, 'placed')} "
                f"| {_mean_std(row, 'pushed')} | {_number(row.get('pushes_mean'))} "
                f"| {'-' if rate is None else f'{rate * 100:.0f} %'} | {truth} | {differ} |"
            )
    note = (
        "\nOffsets in mm, mean ± std over the trials, as each backend's camera measured them; the trials of "
        "one seed are the same starts, targets and injected errors in every engine.\n"
    )
    return header + "\n".join(lines) + "\n" + note
