"""Running many trials: every missing trial of every combination, on one executor.

Each finished trial is appended to its folder's ``trials.jsonl`` as it ends, then the summaries
are written; a rerun runs only the missing trials, and trials that did not come back are listed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from bt_arrange.checks import whole_number
from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.trees import check_threshold
from bt_arrange_sim.experiment.options import Combination, TrialSpec, _plan, check_calibration, check_object_rows
from bt_arrange_sim.experiment.summaries import campaign_rows, plot_fig4, summarise, write_campaign, write_summary
from bt_arrange_sim.experiment.trial import run_trial


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
    calibration: str | Path | None = None,
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
    calibration_file = check_calibration(calibration)
    if calibration_file is not None:
        combos = [dataclasses.replace(c, calibration=calibration_file) for c in combos]
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
