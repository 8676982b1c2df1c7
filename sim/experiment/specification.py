"""A campaign's specification (``specification.json`` in ``--out``) and the check of ``--resume``.

What makes a campaign the same campaign: its rows, trials, seed, thresholds, cells, strategies,
types, folder layout, engine and camera calibration (the file's path and a digest of its content,
so a ``camera.toml`` changed in place is another campaign). ``check_resume`` refuses, in one line
naming what differs, a folder that holds another one.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bt_arrange.errors import PlanError
from bt_arrange.filelimits import read_limited
from bt_arrange_sim.experiment.engines import DEFAULT_ENGINE
from bt_arrange_sim.experiment.options import Combination

#: The campaign's specification in ``--out``: what ``--resume`` compares with the command's options.
SPECIFICATION = "specification.json"
#: The parts of a specification that name the camera calibration (checked by every rerun, resumed or not).
CALIBRATION_KEYS = ("calibration", "calibration_sha256")


def specification(rows: Sequence[str], trials: int, seed: int, combos: Sequence[Combination], flat: bool) -> dict:
    """What makes a campaign the same campaign: ``specification.json``, compared by ``--resume``."""
    return {
        "rows": list(rows),
        "trials": trials,
        "seed": seed,
        "thresholds_mm": list(dict.fromkeys(c.threshold_mm for c in combos)),
        "cells": list(dict.fromkeys(c.cell for c in combos)),
        "strategies": list(dict.fromkeys(c.strategy for c in combos)),
        "objects": list(dict.fromkeys(c.object_name for c in combos)),
        # One folder (one threshold, cell and type, no --thresholds) or a folder per combination.
        "folder_per_combination": not flat,
        # The engine, named only when not pybullet's (specifications of before a second engine read the same).
        **({"engine": combos[0].engine} if combos and combos[0].engine != DEFAULT_ENGINE else {}),
        # The calibration, named only with --calibration: its path and what the file held when the campaign began.
        **calibration_fields(combos[0].calibration if combos else None),
    }


def calibration_fields(path: str | None) -> dict[str, str]:
    """``calibration`` (the path as given) and ``calibration_sha256`` (its content's digest); {} without one."""
    if path is None:
        return {}
    text = read_limited(path, "the calibration file", PlanError)  # checked already: within the limits
    return {"calibration": path, "calibration_sha256": hashlib.sha256(text.encode("utf-8")).hexdigest()}


#: How ``--resume``'s refusal names each part of a specification.
_SPEC_NAMES = {
    "rows": "--rows",
    "trials": "--trials",
    "seed": "--seed",
    "thresholds_mm": "thresholds (mm)",
    "cells": "--cell",
    "strategies": "--strategy",
    "objects": "--object",
    "folder_per_combination": "a folder per combination (--thresholds)",
    "engine": "--backend",
    "calibration": "--calibration",
    "calibration_sha256": "the calibration file's content (sha256)",
}


def _same(key: str, there: Any, asked: Any) -> bool:
    if isinstance(there, list) and isinstance(asked, list):
        # The order of a list changes no record (a trial's seed is its row's, not its place in --rows).
        return sorted(map(str, there)) == sorted(map(str, asked))
    return bool(there == asked)


def _text(value: Any) -> str:
    if isinstance(value, list):
        return ",".join(_text(v) for v in value) or "none"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:g}"
    if value is None:
        return "none"
    if isinstance(value, str) and len(value) == 64 and all(c in "0123456789abcdef" for c in value):
        return value[:12]  # a digest: its first 12 digits tell two files apart
    return str(value)


def differences(there: dict, asked: dict) -> list[str]:
    """What differs between a folder's specification and the asked one, one phrase each.

    A calibration the folder names and the asked one does not is a difference too (no calibration is
    not left out of the specification the way the default engine is).
    """
    keys = list(asked) + [key for key in CALIBRATION_KEYS if key in there and key not in asked]
    return [
        f"{_SPEC_NAMES.get(key, key)} {_text(there.get(key))} there, {_text(asked.get(key))} asked"
        for key in keys
        if not _same(key, there.get(key), asked.get(key))
    ]


def check_resume(out_dir: Path, wanted: dict, *, resume: bool = True) -> None:
    """A one-line ``PlanError`` when ``out_dir`` holds another campaign than ``wanted`` (``--resume``).

    A folder without ``specification.json`` (empty, new, or from before it was written) is resumed:
    its records are still checked one by one against the campaign. A rerun without ``resume`` may
    grow a campaign (more trials, more rows) but never mixes two calibrations: it compares only
    ``CALIBRATION_KEYS``.
    """
    path = out_dir / SPECIFICATION
    if not path.exists():
        return
    option = "--resume" if resume else f"--out {out_dir}"
    try:
        there = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        raise PlanError(f"{option}: cannot read {path}: {error}") from error
    if not isinstance(there, dict):
        raise PlanError(f"{option}: {path} is not a campaign's specification")
    if not resume:
        wanted = {key: wanted.get(key) for key in CALIBRATION_KEYS if key in wanted or key in there}
    found = differences(there, wanted)
    if found:
        raise PlanError(
            f"{option}: {out_dir} holds another campaign: {'; '.join(found)}; "
            "give its options, or another --out for a new campaign"
        )
