"""Speed-up of a campaign on 1 and 2 workers, local process pool and Dask LocalCluster, in one run.

    python benchmarks/scaling.py --trials 8 --row system [--json]

Runs the same trials (one row, ``--trials`` of them, seed ``--seed``) four times into fresh
folders: local with 1 and 2 workers, Dask with 1 and 2 workers; times each from submitting the
first trial to writing the last one's record (cluster start-up excluded, timed apart; the summary
and Fig. 4 written after the last trial, a fixed cost of one process, timed apart too), checks that
the four ``trials.jsonl`` hold the same records (wall times aside) and prints the speed-ups of two
workers over one. Absolute times depend on the machine and what else runs on it: compare the ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from bt_arrange_sim.executors import open_executor
from bt_arrange_sim.experiment import ROWS, read_trials, run_experiment


def _records(folder: Path) -> dict:
    return {
        (r["row"], r["trial"]): {k: v for k, v in r.items() if k != "wall_seconds"}
        for r in read_trials(folder / "trials.jsonl")
    }


def _warm_up(hold_s: float, worker: int) -> int:
    """Import what a trial imports, then hold the worker a moment so the next warm-up lands on another one.

    ``worker`` only makes each call distinct: Dask runs identical calls once.
    """
    import pybullet  # noqa: F401

    import bt_arrange_sim.experiment  # noqa: F401  (placo, the URDF, the injectors)

    time.sleep(hold_s)
    return os.getpid()


@contextmanager
def _executor(kind: str, workers: int) -> Iterator[Executor]:
    if kind == "local":
        with ProcessPoolExecutor(max_workers=workers) as pool:
            yield pool
        return
    with open_executor("dask", workers=workers) as executor:
        assert executor is not None
        yield executor


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=8, help="trials per configuration (default 8)")
    parser.add_argument("--row", default="system", choices=ROWS, help="the row to run (default system)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()

    results = []
    with tempfile.TemporaryDirectory(prefix="bt-arrange-scaling-") as tmp:
        for kind in ("local", "dask"):
            for workers in (1, 2):
                folder = Path(tmp) / f"{kind}-{workers}"
                started = time.perf_counter()
                # Local with one worker runs in a pool too (not in this process), so both sides pay the same hops.
                with _executor(kind, workers) as executor:
                    # Every worker process is up and has imported the simulator before the clock starts:
                    # a campaign pays that once, and it is reported apart as startup_seconds.
                    pids = {f.result() for f in [executor.submit(_warm_up, 0.5, worker) for worker in range(workers)]}
                    assert len(pids) == workers, f"warm-up reached {len(pids)} of {workers} workers"
                    ready = time.perf_counter()
                    last_record = [ready]

                    def written(record: dict, done: int, total: int, last_record: list[float] = last_record) -> None:
                        last_record[0] = time.perf_counter()

                    run_experiment([args.row], args.trials, args.seed, 1.0, folder, executor=executor, on_trial=written)
                    seconds = last_record[0] - ready
                    summary_seconds = time.perf_counter() - last_record[0]
                results.append(
                    {
                        "executor": kind,
                        "workers": workers,
                        "trials": args.trials,
                        "seconds": round(seconds, 2),
                        "startup_seconds": round(ready - started, 2),
                        "summary_seconds": round(summary_seconds, 2),
                        "records": _records(folder),
                    }
                )
    reference = results[0]["records"]
    same = all(r["records"] == reference for r in results)
    for r in results:
        del r["records"]
    speedups = {
        kind: round(
            next(r["seconds"] for r in results if r["executor"] == kind and r["workers"] == 1)
            / next(r["seconds"] for r in results if r["executor"] == kind and r["workers"] == 2),
            2,
        )
        for kind in ("local", "dask")
    }
    machine = f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.1f} at the end"
    if args.json:
        print(json.dumps({"runs": results, "speedup_2_over_1": speedups, "same_records": same, "machine": machine}))
    else:
        for r in results:
            print(
                f"{r['executor']:5s} {r['workers']} worker(s): {r['trials']} trials of {args.row} in "
                f"{r['seconds']:.1f} s ({r['seconds'] / r['trials']:.2f} s per trial)"
            )
        for kind, ratio in speedups.items():
            print(f"{kind}: 2 workers are {ratio:.2f}x as fast as 1")
        print(f"same trials.jsonl records (wall times aside) on all four: {same}")
        print(f"machine: {machine}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
