"""Running many trials: every missing trial of every combination, on one executor.

Each finished trial is appended to its folder's ``trials.jsonl`` as it ends (a whole line, or
nothing), then the summaries are written. The campaign's specification is kept in
``specification.json`` of ``--out``; ``resume=True`` (``--resume``) continues a campaign only when
it is the same. Any rerun (resumed or not) keeps the trials already recorded and runs the missing
ones and the errored ones; a line torn by a kill is dropped and its trial run again.

A trial that fails (an exception, a worker that dies) is a record with ``status = "error"`` and the
exception's one line; the campaign goes on. A file that cannot be written (a full disk, a folder
removed) does not stop it either: what was measured is returned inside a ``RecordError``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import signal
import tempfile
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_arrange import files
from bt_arrange.checks import whole_number
from bt_arrange.errors import PlanError, RecordError, TrialsErroredError
from bt_arrange.trees import check_threshold
from bt_arrange_sim.experiment import recording
from bt_arrange_sim.experiment.engines import DEFAULT_ENGINE, trial_engine
from bt_arrange_sim.experiment.options import Combination, TrialSpec, _plan, check_calibration, check_object_rows
from bt_arrange_sim.experiment.specification import SPECIFICATION, check_resume, specification
from bt_arrange_sim.experiment.summaries import campaign_rows, plot_fig4, summarise, write_campaign, write_summary
from bt_arrange_sim.experiment.trial import run_trial

#: The status of a trial that gave no measurement (an exception, a dead worker); a rerun runs it again.
ERROR = "error"


def read_trials(path: Path) -> list[dict]:
    """The records in a trials file, errored ones included; a line cut short by an interruption is ignored."""
    if not path.exists():
        return []
    records = []
    for line in path.read_text().splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return records


class CampaignIncompleteError(TrialsErroredError):
    """Some trials errored (an exception, a worker that died, the cluster gone); ``--resume`` reruns them.

    ``summary`` holds what ``run_experiment`` would have returned, for the trials that did finish
    (the command line exits 4, ``bt_arrange.cli_common.EXIT_TRIALS_ERRORED``).
    """


@dataclass
class CampaignResult:
    """What a campaign produced: one summary per combination, the trials that errored, the files not written.

    ``lost`` are the trials of this run that gave no measurement (recorded with ``status = "error"``)
    with their one line; ``faults`` the files that could not be written (``bt_arrange.files.WriteFault``).
    """

    summaries: dict[Combination, list[dict]]
    folders: dict[Combination, Path]
    lost: list[tuple[TrialSpec, str]]
    faults: list[files.WriteFault] = field(default_factory=list)


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
    resume: bool = False,
    engine: str = DEFAULT_ENGINE,
    record: str | Path | None = None,
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
    - ``engine``: the physics engine of every trial's cell, a backend's entry point name
      (``engines.trial_engine``; a backend's ``experiment`` passes its own).
    - ``resume`` (``--resume``): continue the campaign in ``out_dir``, refused (a ``PlanError``
      naming what differs) when its ``specification.json`` is another campaign's.
    - ``record`` (``--record DIR``): one MCAP file per trial in that folder (``recording``); a
      missing Foxglove SDK is a one-line error before anything runs.

    Raises ``CampaignIncompleteError`` (with the summary, ``summary``) when a trial errored, after
    recording it; ``RecordError`` (with the summary, ``result``) when a file could not be written.
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
    if engine != DEFAULT_ENGINE:
        trial_engine(engine).check_cells(list(dict.fromkeys(c.cell for c in combos)))
        combos = [dataclasses.replace(c, engine=engine) for c in combos]
    rows = list(rows)
    check_object_rows(object_name, rows)
    record_dir = recording.check_record(record)
    if executor == "dask":
        from bt_arrange_sim import executors

        opened: contextlib.AbstractContextManager[Executor | None] = executors.open_executor("dask", workers, scheduler)
    else:
        # "local" is this module's own process pool (run_campaign makes it from ``workers``).
        opened = contextlib.nullcontext(None if isinstance(executor, str) else executor)
    with opened as pool:
        result = run_campaign(
            rows,
            trials,
            seed,
            combos,
            out_dir,
            workers=workers,
            executor=pool,
            on_trial=on_trial,
            flat=flat,
            resume=resume,
            record_dir=record_dir,
        )
    if flat:
        summary = result.summaries[combos[0]]
    else:
        summary = campaign_rows(result.summaries, result.folders)
    errored = ""
    if result.lost:
        spec, reason = result.lost[0]
        errored = (
            f"{len(result.lost)} trial(s) errored (first: {spec.row} #{spec.index}: {reason}); "
            "the others are recorded: --resume reruns them"
        )
    if result.faults:
        message = f"{files.Faults(result.faults).message()}; the campaign finished, its record did not"
        raise RecordError(message + (f"; {errored}" if errored else ""), faults=result.faults, result=summary)
    if errored:
        raise CampaignIncompleteError(errored, summary=summary)
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
    resume: bool = False,
    record_dir: Path | None = None,
) -> CampaignResult:
    """Run every missing trial of every combination, each appended to its folder's ``trials.jsonl`` as it ends.

    A combination's folder is ``out_dir/<combination.folder>`` (``out_dir`` itself when ``flat``,
    for a single combination). All trials go to one executor at once, so the workers stay busy
    across combinations. A trial that raises, or whose worker dies, is recorded with ``status =
    "error"`` and its one line (listed in ``lost``) and the others go on; a rerun runs it again. On
    this module's own pool (``executor`` None, ``workers`` > 1) a dead worker costs only its own
    trial: the pool is started again for the others. Writes each combination's summaries and Fig. 4
    and, for more than one, the campaign's ``campaign.json`` and ``thresholds.png``; a file that
    cannot be written is a fault in ``faults``, not an exception.

    ``resume``: ``out_dir``'s ``specification.json`` (rows, trials, seed, thresholds, cells,
    strategies, types and the folders' layout) must be this campaign's; a ``PlanError`` names what
    differs. Without it a rerun may also grow a campaign (more trials, more rows). ``record_dir``:
    each trial run records its MCAP there (``recording``; finished trials are not run, so not rewritten).
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
    faults = files.Faults()
    wanted = specification(rows, trials, seed, combos, flat)
    check_resume(out_dir, wanted, resume=resume)
    folders = {c: out_dir if flat else out_dir / c.folder for c in combos}
    recorder = recording.Recording(record_dir, flat)
    recorder.prepare(combos, rows)
    logs: dict[Combination, TrialLog] = {}
    specs: list[tuple[Combination, TrialSpec]] = []
    for combination in combos:
        folder = folders[combination]
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise PlanError(f"cannot write into {folder}: {files.cause(error)}") from error
        files.remove_stale_temps(folder)
        log = logs[combination] = TrialLog.open(folder / "trials.jsonl", again=recorder.again)
        for record in log.records:
            if record.get("seed") != seed or not combination.owns(record):
                raise PlanError(
                    f"{log.path} holds trials of another experiment (seed {record.get('seed')}, "
                    f"threshold {record.get('threshold_mm')} mm, cell {record.get('cell', 'ideal')}, strategy "
                    f"{record.get('strategy', 'paper')}, object {record.get('object', 'cube')}); choose another --out "
                    f"for seed {seed}, threshold {combination.threshold_mm:g} mm, cell {combination.cell}, "
                    f"strategy {combination.strategy}, object {combination.object_name}"
                )
        done = {(record["row"], record["trial"]) for record in log.records}
        # Trial by trial across the rows: an interrupted campaign has measured every row about as often.
        specs += [
            (combination, recorder.spec(combination, row, index, seed))
            for index in range(trials)
            for row in rows
            if (row, index) not in done
        ]
    if not flat:
        files.remove_stale_temps(out_dir)
    # The specification first: a campaign killed from here on can be resumed.
    with faults.guard(out_dir / SPECIFICATION):
        files.write_json(out_dir / SPECIFICATION, wanted)
    total = len(rows) * trials * len(combos)
    finished = total - len(specs)
    lost: list[tuple[TrialSpec, str]] = []

    def keep(combination: Combination, spec: TrialSpec, record: dict) -> None:
        nonlocal finished
        recorder.point(record, spec, folders[combination], faults)
        logs[combination].append(record, faults)
        if record.get("status") == ERROR:
            lost.append((spec, str(record.get("reason", ""))))
        finished += 1
        if on_trial is not None:
            on_trial(record, finished, total)

    if executor is None and workers > 1 and len(specs) > 1:
        _run_on_own_pool(specs, workers, keep)
    elif executor is None:
        for combination, spec in specs:
            try:
                record = run_trial(spec)
            except Exception as error:  # noqa: BLE001 - a trial's exception is its record, not the campaign's end
                record = error_record(spec, one_line(error))
            keep(combination, spec, record)
    else:
        futures: dict[Future, tuple[Combination, TrialSpec]] = {
            executor.submit(run_trial, spec): (combination, spec) for combination, spec in specs
        }
        for future in as_completed(futures):
            combination, spec = futures[future]
            try:
                record = future.result()
            except Exception as error:  # noqa: BLE001 - a dead worker (a Dask KilledWorker) errs its trial only
                record = error_record(spec, one_line(error))
            keep(combination, spec, record)
    summaries = {}
    for combination in combos:
        folder = folders[combination]
        logs[combination].finish(faults)
        records = [r for r in logs[combination].records if r["row"] in rows and r["trial"] < trials]
        summary = summarise(records, rows)
        write_summary(summary, folder, faults)
        with faults.guard(folder / "fig4.png"):
            plot_fig4(measured(records), rows, folder / "fig4.png")
        summaries[combination] = summary
    if len(combos) > 1:
        write_campaign(summaries, folders, out_dir, faults)
    return CampaignResult(
        summaries, folders, sorted(lost, key=lambda item: (item[0].row, item[0].index)), list(faults.faults)
    )


# ----------------------------------------------------------------------------------------------
# trials.jsonl
# ----------------------------------------------------------------------------------------------


@dataclass
class TrialLog:
    """A folder's ``trials.jsonl``: the records kept (one per trial, none errored), and appending.

    ``open`` reads it and, when it has to, writes it again (whole, by a rename) without a torn last
    line, errored records or repeats; if the disk cannot take that, it only cuts the torn line off.
    A record that cannot be appended stays in ``records``, and ``finish`` tries once more to write
    the whole file.
    """

    path: Path
    records: list[dict] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    unwritten: bool = False

    @classmethod
    def open(cls, path: Path, again: Callable[[dict], bool] | None = None) -> TrialLog:
        """The log at ``path``, mended for a rerun (see the class); a record ``again`` picks is run again too."""
        log = cls(path)
        if not path.exists():
            return log
        raw = path.read_bytes()
        mend = bool(raw) and not raw.endswith(b"\n")
        seen: set[tuple[Any, Any]] = set()
        for line in raw.decode("utf-8", errors="replace").splitlines():
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                mend = True
                continue
            key = (record.get("row"), record.get("trial")) if isinstance(record, dict) else None
            if key is None or record.get("status") == ERROR or key in seen or (again is not None and again(record)):
                # An errored trial runs again (and one whose MCAP a recording campaign lacks); a repeat is dropped.
                mend = True
                continue
            seen.add(key)
            log.records.append(record)
            log.lines.append(line)
        if mend:
            try:
                files.write_text(path, "".join(line + "\n" for line in log.lines))
            except OSError:
                try:
                    files.repair_lines(path)  # needs no space: the file only gets shorter
                except OSError as error:
                    raise PlanError(f"cannot continue {path}: {files.cause(error)}") from error
        return log

    def append(self, record: dict, faults: files.Faults) -> None:
        """Keep ``record`` and append it as one whole line; a failed write is a fault, the record stays kept."""
        line = json.dumps(record)
        self.records.append(record)
        self.lines.append(line)
        try:
            files.append_lines(self.path, [line])
        except OSError as error:
            faults.add(self.path, error)
            self.unwritten = True

    def finish(self, faults: files.Faults) -> None:
        """After a failed append: write the whole file once more (by a rename); if that works, no fault is left."""
        if not self.unwritten:
            return
        try:
            files.write_text(self.path, "".join(line + "\n" for line in self.lines))
        except OSError:
            return
        faults.faults[:] = [fault for fault in faults.faults if fault.path != self.path]
        self.unwritten = False


def measured(records: Iterable[dict]) -> list[dict]:
    """The records that measured something (not errored)."""
    return [r for r in records if r.get("status") != ERROR]


# ----------------------------------------------------------------------------------------------
# Errored trials, and a pool that outlives a dead worker
# ----------------------------------------------------------------------------------------------


def one_line(error: BaseException) -> str:
    """An exception's type and the first line of its message."""
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0][:300]}" if text else type(error).__name__


def error_record(spec: TrialSpec, reason: str) -> dict:
    """The record of a trial that measured nothing: its spec, ``status = "error"`` and the reason."""
    return {
        **spec.record_fields(),
        "target": None,
        "placed_mm": None,
        "pushed_mm": None,
        "placed_truth_mm": None,
        "pushed_truth_mm": None,
        "pushes": None,
        "status": ERROR,
        "reason": reason,
    }


def _traced_trial(spec: TrialSpec, number: int, trace_dir: str | None) -> dict:
    """``run_trial`` in a pool worker, noting first which trial this process runs (for a death)."""
    if trace_dir is not None:
        with contextlib.suppress(OSError):
            Path(trace_dir, str(os.getpid())).write_text(str(number))
    return run_trial(spec)


def _death(exitcode: int | None) -> str:
    if exitcode is not None and exitcode < 0:
        with contextlib.suppress(ValueError):
            return f"killed by {signal.Signals(-exitcode).name}"
    return f"exit status {exitcode}"


def _run_on_own_pool(
    specs: list[tuple[Combination, TrialSpec]],
    workers: int,
    keep: Callable[[Combination, TrialSpec, dict], None],
) -> None:
    """The trials on a process pool of ``workers``; a worker that dies errs its own trial only.

    A dead worker breaks a ``ProcessPoolExecutor`` (every unfinished future fails): the trial the
    dead process was running (each worker notes its trial in a scratch folder) is recorded as an
    error, the pool is started again and the other unfinished trials go to it. When the dead one
    cannot be told (it died another way than the pool's own stop), every trial that was running errs.
    """
    remaining = list(enumerate(specs))
    try:
        scratch: contextlib.AbstractContextManager[str | None] = tempfile.TemporaryDirectory(
            prefix="bt-arrange-workers-", dir=_scratch(), ignore_cleanup_errors=True
        )
    except OSError:  # no room even for a scratch folder: a dead worker then errs every running trial
        scratch = contextlib.nullcontext(None)
    with scratch as trace_dir:
        while remaining:
            pool = ProcessPoolExecutor(max_workers=min(workers, len(remaining)))
            broken: list[tuple[int, tuple[Combination, TrialSpec]]] = []
            processes: dict[int, Any] = {}
            try:
                futures = {
                    pool.submit(_traced_trial, item[1], number, trace_dir): (number, item) for number, item in remaining
                }
                processes = getattr(pool, "_processes", None) or {}
                for future in as_completed(futures):
                    number, (combination, spec) = futures[future]
                    try:
                        record = future.result()
                    except BrokenProcessPool:
                        broken.append((number, (combination, spec)))
                        continue
                    except Exception as error:  # noqa: BLE001 - a trial's exception is its record
                        record = error_record(spec, one_line(error))
                    keep(combination, spec, record)
            finally:
                pool.shutdown(wait=True, cancel_futures=True)
            if not broken:
                return
            running: dict[int, str] = {}  # trial number -> how its worker ended
            for pid, process in dict(processes).items():
                with contextlib.suppress(OSError, ValueError, TypeError):
                    running[int(Path(str(trace_dir), str(pid)).read_text())] = _death(process.exitcode)
            dead = {n: how for n, how in running.items() if how != f"killed by {signal.SIGTERM.name}"}
            unfinished = {number for number, _ in broken}
            culprits = {n: how for n, how in dead.items() if n in unfinished} or {
                n: how for n, how in running.items() if n in unfinished
            }
            if not culprits:  # nothing tells which: every unfinished trial errs, so the loop ends
                culprits = {n: "the pool broke" for n in unfinished}
            remaining = []
            for number, (combination, spec) in broken:
                if number in culprits:
                    reason = f"BrokenProcessPool: the worker process running it died ({culprits[number]})"
                    keep(combination, spec, error_record(spec, reason))
                else:
                    remaining.append((number, (combination, spec)))
            for entry in Path(trace_dir).iterdir() if trace_dir is not None else ():
                with contextlib.suppress(OSError):
                    entry.unlink()


def _scratch() -> str | None:
    """Where workers note their trials: memory (``/dev/shm``) when there is one, not the campaign's disk."""
    return "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
