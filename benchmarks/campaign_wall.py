"""Wall time of a campaign against an earlier revision, measured back to back on this machine.

    python benchmarks/campaign_wall.py --against f7bbbaf [--trials 100] [--rows ROWS] [--repeats 1] [--json]

Runs ``bt-arrange experiment --workers 1`` with the same rows, trials and seed twice per repeat:
once with the code of ``--against`` (a git revision, checked out into a temporary worktree) and
once with this checkout, alternating, each in a fresh process. Prints each run's wall and CPU time
(the child's user + system), the ratio this / reference of each, and how many trial records are
identical (all the reference's fields but the wall time; fields added since are named, not
compared). The default revision ``f7bbbaf`` is the code before the
cycle-time work (Table 1 wall time target: this / reference <= 0.6).

Wall time depends on the machine and on what else runs on it: read the ratio of one run, and
the CPU ratio beside it when the machine is shared.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The last commit before the cycle-time work: Table 1's "today" of that work.
BEFORE_CYCLE_TIME = "f7bbbaf"
#: Fields of a trial record that measure the machine, not the trial.
MACHINE_FIELDS = ("wall_seconds",)


def _packages(source: Path, into: Path) -> Path:
    """A folder that imports ``bt_arrange`` and ``bt_arrange_sim`` from ``source`` (as the wheel maps them).

    It also holds the distribution's metadata with ``source``'s own backend entry points: first on
    the import path, it hides the installed checkout's, whose modules may be elsewhere in ``source``.
    """
    into.mkdir(parents=True, exist_ok=True)
    (into / "bt_arrange").symlink_to(source / "bt_arrange")
    (into / "bt_arrange_sim").symlink_to(source / "sim")
    info = into / "bt_arrange-0.0.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: bt-arrange\nVersion: 0.0.0\n")
    (info / "entry_points.txt").write_text(_entry_points(source / "pyproject.toml"))
    return into


def _entry_points(pyproject: Path) -> str:
    """The ``[project.entry-points.*]`` tables of ``pyproject`` as an ``entry_points.txt``."""
    import tomllib

    tables = tomllib.loads(pyproject.read_text()).get("project", {}).get("entry-points", {})
    lines = []
    for group, points in tables.items():
        lines += [f"[{group}]", *(f"{name} = {value}" for name, value in points.items()), ""]
    return "\n".join(lines)


def _campaign(packages: Path, out: Path, args: argparse.Namespace) -> dict:
    """One campaign in a fresh process; its wall and CPU seconds."""
    command = [sys.executable, "-m", "bt_arrange.cli", "experiment", "--rows", args.rows, "--trials", str(args.trials)]
    command += ["--seed", str(args.seed), "--workers", "1", "--out", str(out)]
    env = {**os.environ, "PYTHONPATH": str(packages)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    # From the packages' folder: ``python -m`` puts the working directory first on the import path.
    subprocess.run(command, env=env, cwd=packages, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": round(wall, 2), "cpu_s": round(cpu, 2), "out": str(out)}


def _records(out: Path) -> dict[tuple[str, int], dict]:
    """The campaign's trial records by (row, trial), without the fields that measure the machine."""
    from bt_arrange_sim.experiment.campaign import read_trials

    return {
        (record["row"], record["trial"]): {k: v for k, v in record.items() if k not in MACHINE_FIELDS}
        for record in read_trials(out / "trials.jsonl")
    }


def _same(ours: dict, theirs: dict | None) -> bool:
    """Equal in every field of the reference's record: a field the record gained since is new, not different."""
    return theirs is not None and all(key in ours and ours[key] == value for key, value in theirs.items())


def _by_row(records: dict[tuple[str, int], dict]) -> dict[str, dict]:
    """Per row: trials, mean offset after pushing (camera, mm) and trials within the threshold."""
    rows: dict[str, list[dict]] = {}
    for (row, _), record in records.items():
        rows.setdefault(row, []).append(record)
    return {
        row: {
            "trials": len(rs),
            "pushed_mean_mm": round(sum(r["pushed_mm"] for r in rs if r.get("pushed_mm") is not None) / len(rs), 3),
            "within": sum(1 for r in rs if r.get("status") == "within"),
        }
        for row, rs in rows.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default=BEFORE_CYCLE_TIME, help="git revision to compare with")
    parser.add_argument("--rows", default="system,translation,orientation,grasp-estimator")
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="bt-arrange-wall-") as scratch:
        base = Path(scratch)
        reference = base / "reference"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(reference), args.against],
            check=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            sides = {
                "reference": _packages(reference, base / "reference-packages"),
                "this": _packages(ROOT, base / "this-packages"),
            }
            runs: dict[str, list[dict]] = {"reference": [], "this": []}
            for repeat in range(args.repeats):
                for side, packages in sides.items():
                    runs[side].append(_campaign(packages, base / f"{side}-{repeat}", args))
            ours, theirs = _records(Path(runs["this"][0]["out"])), _records(Path(runs["reference"][0]["out"]))
            differing = sorted(key for key in ours if not _same(ours[key], theirs.get(key)))
            added = sorted({k for record in ours.values() for k in record} - {k for r in theirs.values() for k in r})
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(reference)], check=False)

    best = {side: min(r["wall_s"] for r in rs) for side, rs in runs.items()}
    cpu = {side: min(r["cpu_s"] for r in rs) for side, rs in runs.items()}
    result = {
        "benchmark": "campaign_wall",
        "note": "wall and CPU seconds on this machine, back to back; compare the ratios",
        "against": args.against,
        "rows": args.rows,
        "trials_per_row": args.trials,
        "seed": args.seed,
        "runs": {side: [{k: v for k, v in r.items() if k != "out"} for r in rs] for side, rs in runs.items()},
        "wall_ratio": round(best["this"] / best["reference"], 3),
        "cpu_ratio": round(cpu["this"] / cpu["reference"], 3),
        "records": len(ours),
        "identical_records": len(ours) - len(differing),
        "differing_records": [f"{row} #{trial}" for row, trial in differing][:20],
        "added_fields": added,
        "by_row": {"reference": _by_row(theirs), "this": _by_row(ours)},
    }
    if args.json:
        print(json.dumps(result))
        return
    print(f"Campaign wall time against {args.against}: {args.rows}, {args.trials} trials per row, seed {args.seed}")
    for side, rs in runs.items():
        shown = ", ".join(f"{r['wall_s']:.1f} s wall / {r['cpu_s']:.1f} s CPU" for r in rs)
        print(f"  {side:9s} {shown}")
    print(f"  this / reference: wall {result['wall_ratio']:.3f}, CPU {result['cpu_ratio']:.3f}")
    print(f"  trial records identical: {result['identical_records']} of {result['records']}")
    if added:
        print(f"  fields added since (not compared): {', '.join(added)}")
    if differing:
        print(f"  differing (first 20): {', '.join(result['differing_records'])}")
    print("  after pushing, mean mm and trials within (reference / this):")
    for row, theirs_row in result["by_row"]["reference"].items():
        ours_row = result["by_row"]["this"][row]
        print(
            f"    {row:16s} {theirs_row['pushed_mean_mm']:.3f} / {ours_row['pushed_mean_mm']:.3f} mm, "
            f"{theirs_row['within']} / {ours_row['within']} of {ours_row['trials']}"
        )


if __name__ == "__main__":
    main()
