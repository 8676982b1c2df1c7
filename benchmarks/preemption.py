"""A campaign killed at random moments and resumed each time ends with the records of an uninterrupted one.

    python benchmarks/preemption.py --trials 40 --row system --workers 2 --kills 5 [--signal KILL] [--seed 0]

Runs ``bt-arrange experiment --rows ROW --trials N --workers W`` once to the end (the reference),
then the same command with ``--resume`` into another folder, killing it (the whole process group:
the command and its pool workers, as a preempted job is) at a random moment of its run, ``--kills``
times, and once more to the end. Each kill's moment is drawn uniformly between 0.3 s and 1.5 s (the
start) plus twice the remaining trials' time over the kills left plus one (from the reference's
pace), so the kills spread over the campaign and land anywhere: while workers start, mid-trial,
mid-write, while the summary and Fig. 4 are written. Prints, per kill, the moment
and what the folder then held (whole records, a torn last line, temporary files left), then checks
the resumed campaign's ``trials.jsonl`` against the reference: the same records (wall times aside),
none lost, none twice, none errored. Exit status 0 when they match, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _records(folder: Path) -> tuple[dict, list[tuple[str, int]], bool]:
    """The records by (row, trial), wall time aside; every key as often as it appears; a torn last line."""
    path = folder / "trials.jsonl"
    if not path.exists():
        return {}, [], False
    data = path.read_bytes()
    records, keys = {}, []
    for line in data.splitlines():
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            continue
        keys.append((record["row"], record["trial"]))
        records[keys[-1]] = {k: v for k, v in record.items() if k != "wall_seconds"}
    return records, keys, bool(data) and not data.endswith(b"\n")


def _command(args: argparse.Namespace, out: Path, resume: bool) -> list[str]:
    command = [sys.executable, "-m", "bt_arrange.cli", "experiment", "--rows", args.row, "--trials", str(args.trials)]
    command += ["--seed", str(args.seed), "--workers", str(args.workers), "--out", str(out)]
    return command + (["--resume"] if resume else [])


def _run(command: list[str], kill_after_s: float | None, sig: signal.Signals) -> tuple[int, float]:
    """Run ``command`` in its own process group; kill the group after ``kill_after_s``. Exit code, seconds."""
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        process.wait(timeout=kill_after_s)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, sig)
        process.wait()
    took = time.perf_counter() - start
    # No pool worker may outlive the kill (it would write into the folder the next run resumes).
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.killpg(process.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        os.killpg(process.pid, signal.SIGKILL)
    return process.returncode, took


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--row", default="system")
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--kills", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0, help="the campaign's seed (and the kill moments')")
    parser.add_argument("--signal", default="KILL", help="the signal of the kills: KILL (default), TERM or INT")
    parser.add_argument("--out", type=Path, help="where the two folders go (default: a temporary folder)")
    args = parser.parse_args()
    sig = signal.Signals[f"SIG{args.signal.upper().removeprefix('SIG')}"]
    base = args.out or Path(tempfile.mkdtemp(prefix="bt-arrange-preemption-"))
    reference, resumed = base / "uninterrupted", base / "resumed"
    code, reference_s = _run(_command(args, reference, resume=False), None, sig)
    want, _, _ = _records(reference)
    print(f"uninterrupted: exit {code}, {len(want)} records in {reference_s:.1f} s ({reference})")
    if code != 0 or len(want) != args.trials:
        print("the uninterrupted campaign did not finish")
        return 1
    per_trial_s = reference_s / args.trials
    draw = random.Random(args.seed)
    for kill in range(1, args.kills + 1):
        _, before, _ = _records(resumed)
        # Spread over the campaign: on average each kill lets a share of what is left run (kills left + 1 shares).
        remaining_s = per_trial_s * (args.trials - len(set(before)))
        moment = draw.uniform(0.3, 1.5 + 2 * remaining_s / (args.kills - kill + 2))
        code, took = _run(_command(args, resumed, resume=True), moment, sig)
        got, keys, torn = _records(resumed)
        temps = sorted(p.name for p in resumed.iterdir() if p.name.endswith(".tmp")) if resumed.exists() else []
        errored = sum(r.get("status") == "error" for r in got.values())
        print(
            f"kill {kill}: SIG{sig.name.removeprefix('SIG')} at {moment:.2f} s (exit {code}, ran {took:.2f} s): "
            f"{len(set(keys))} trials recorded ({len(keys) - len(set(before))} new), "
            f"{'a torn last line' if torn else 'no torn line'}, {errored} errored, "
            f"{len(temps)} temporary file(s) left {temps if temps else ''}".rstrip()
        )
    code, took = _run(_command(args, resumed, resume=True), None, sig)
    got, keys, torn = _records(resumed)
    print(f"final resume: exit {code} in {took:.1f} s")
    same = got == want
    twice = len(keys) - len(set(keys))
    lost = sorted(set(want) - set(got))
    errored = sum(r.get("status") == "error" for r in got.values())
    differing = sorted(key for key in set(want) & set(got) if want[key] != got[key])
    print(
        f"records identical to the uninterrupted campaign's: {same}; lost {len(lost)}, twice {twice}, "
        f"errored {errored}, differing {len(differing)}, torn {torn}"
    )
    return 0 if same and not twice and not torn and code == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
