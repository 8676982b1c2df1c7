"""``bt-arrange experiment``: a campaign of the paper's rows on a backend, and its summary."""

from __future__ import annotations

import argparse
import sys
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
)


def _experiment_options(
    backend: Backend, experiment: Experiment, args: argparse.Namespace, rows: list[str]
) -> dict[str, Any]:
    """The experiment's options (``EXPERIMENT_OPTIONS``), checked by the backend's ``check_options``.

    Only non-defaults are passed on; ``--workers`` is one of the Protocol's own arguments. With
    ``--object``, the check also gets the rows (a row may not know every type).
    """
    options = {key: getattr(args, key) for key, default in EXPERIMENT_OPTIONS if getattr(args, key) != default}
    check = getattr(experiment, "check_options", None)
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


def _experiment(args: argparse.Namespace) -> int:
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
    return EXIT_OK
