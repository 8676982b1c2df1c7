"""A campaign's recordings (``experiment --record DIR``): one MCAP file per trial, and its pointer in the record.

Where a trial's file goes, mirroring ``--out``'s folders (the combination's folder only when the
campaign has one per combination), a folder per row, the trial's number in four digits so the
names sort::

    DIR/[threshold-1mm.../]<row>/trial-0007.mcap

The file is the trial's session's Foxglove streams (``bt_arrange.foxglove``, as ``run --record``
writes them into ``run.mcap``), written by the process that runs the trial, whole at its end.
The parent then points the trial's record at it: ``mcap``, the path relative to the folder of the
``trials.jsonl`` that holds the record (``Path(trials_jsonl).parent / record["mcap"]`` opens it,
and moving ``--out`` and ``DIR`` together keeps it true). A file that could not be written is
``"mcap": null`` with ``mcap_fault`` (its cause, one line) and a fault of the campaign (exit 3,
"the campaign finished, its record did not"); the trial's measurement is kept, as a record the
disk would not take is, and a rerun that records (``--resume --record DIR``) runs that trial again
(the same trial, the same record) to write its file. A finished trial with its file is never run
again, so its file is never rewritten.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from bt_arrange import files
from bt_arrange.errors import PlanError
from bt_arrange_sim.experiment.options import Combination, TrialSpec, check_record

__all__ = ["FAULT_KEY", "MCAP_KEY", "Recording", "check_record", "record_keys", "trial_file"]

#: The record's key naming the trial's MCAP file (relative to its trials.jsonl's folder), or null when not written.
MCAP_KEY = "mcap"
#: The record's key saying why the trial's MCAP file was not written (only then).
FAULT_KEY = "mcap_fault"


def trial_file(record_dir: Path, folder: str | None, row: str, index: int) -> Path:
    """The MCAP file of trial ``index`` of ``row``; ``folder`` is the combination's (None: a flat campaign)."""
    base = record_dir if folder is None else record_dir / folder
    return base / row / f"trial-{index:04d}.mcap"


@dataclass(frozen=True)
class Recording:
    """A campaign's recording into ``record_dir`` (None: the campaign records nothing, every method a no-op).

    ``flat``: the campaign writes its one combination straight into ``--out`` (no combination folder).
    """

    record_dir: Path | None
    flat: bool = True

    def _folder(self, combination: Combination) -> str | None:
        return None if self.flat else combination.folder

    def prepare(self, combos: Iterable[Combination], rows: Iterable[str]) -> None:
        """Make every row's folder (and remove a killed writer's temporary files); a one-line ``PlanError``.

        Done before the first trial: a folder that cannot be made is a refusal, nothing run.
        """
        if self.record_dir is None:
            return
        rows = list(rows)
        for combination in combos:
            for row in rows:
                path = trial_file(self.record_dir, self._folder(combination), row, 0).parent
                try:
                    path.mkdir(parents=True, exist_ok=True)
                except OSError as error:
                    raise PlanError(f"cannot record into {path}: {files.cause(error)}") from error
                files.remove_stale_temps(path)

    def spec(self, combination: Combination, row: str, index: int, seed: int) -> TrialSpec:
        """The trial's spec (``Combination.spec``), with its MCAP file when the campaign records."""
        spec = combination.spec(row, index, seed)
        if self.record_dir is None:
            return spec
        return dataclasses.replace(spec, mcap=str(trial_file(self.record_dir, self._folder(combination), row, index)))

    def again(self, record: dict) -> bool:
        """True for a finished trial to run again: this campaign records, and that trial's file was not written."""
        return self.record_dir is not None and MCAP_KEY in record and record[MCAP_KEY] is None

    @staticmethod
    def point(record: dict, spec: TrialSpec, folder: Path, faults: files.Faults) -> None:
        """Point a recorded trial's ``record`` at its file, relative to ``folder``; a file not written is a fault.

        A record without the key (an errored trial: nothing measured, a rerun runs it again) is left alone.
        """
        if spec.mcap is None or MCAP_KEY not in record:
            return
        if record[MCAP_KEY] is None:
            faults.faults.append(files.WriteFault(Path(spec.mcap), str(record.get(FAULT_KEY) or "not written")))
            return
        record[MCAP_KEY] = Path(os.path.relpath(spec.mcap, folder.absolute())).as_posix()


def record_keys(path: Path, fault: files.WriteFault | None) -> dict:
    """The keys a recorded trial adds to its record: its file (absolute, until ``point``), or null and why."""
    if fault is not None:
        return {MCAP_KEY: None, FAULT_KEY: fault.cause}
    if not path.is_file():
        return {MCAP_KEY: None, FAULT_KEY: "not written"}
    return {MCAP_KEY: str(path)}
