"""Memory benchmark: resident memory of one process over many runs, and of a campaign worker over many trials.

    nice -n 10 python benchmarks/memory.py [--runs 1000] [--trials 200] [--trim] [--json]

``runs``: the four-cube tree (``trees/four_cubes.py``, scene seed = run number) run again and again
in this process, each in a fresh pybullet cell, closed after; the resident memory (``VmRSS``) is
printed after runs 2, 10, 100, 1,000 (those within ``--runs``) and the last (on stderr as they come). ``worker``: one
worker process of a campaign's pool (``ProcessPoolExecutor``, as ``bt-arrange experiment`` runs
them) runs ``--trials`` trials of the Table 1 "system" row one after the other and reports its
resident memory after each. The first run of a process loads what every run uses (libraries,
the URDF, the renderer's buffers): growth is counted from run 2.

Key figures (``--json``): ``growth_pct`` of each, the resident memory after the last run over the
one after run 2, in percent (target: under 5 % at a thousand runs). Nothing is trimmed or
collected by hand between runs: the figure is what a user's loop or a campaign worker sees.
``--trim`` asks glibc to hand its free memory back (``malloc_trim(0)``) before each reading: then
the figure is the live heap, without what the allocator keeps for reuse.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

TREES = Path(__file__).resolve().parent.parent / "trees"
CHECKPOINTS = (2, 10, 100, 1000)


#: Set by ``--trim`` (and handed to the worker): glibc's free memory handed back before a reading.
TRIM = False


def resident_mb() -> float:
    """The resident memory of this process (``VmRSS``), MB; first trimmed with ``--trim``."""
    if TRIM:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS in /proc/self/status (Linux only)")


def checkpoints(total: int) -> list[int]:
    """The run numbers whose resident memory is printed: 2, 10, 100, 1,000 (within ``total``) and the last."""
    return sorted({n for n in CHECKPOINTS if n <= total} | {total})


def growth_pct(figures: dict[int, float]) -> float | None:
    """Resident memory after the last run over the one after run 2, in percent (None with fewer than 2 runs)."""
    if 2 not in figures:
        return None
    last = max(figures)
    return round((figures[last] / figures[2] - 1.0) * 100, 2)


def four_cube_runs(runs: int, progress: bool = True) -> dict:
    """The four-cube tree ``runs`` times in this process; the resident memory at the checkpoints."""
    from bt_arrange import treefile
    from bt_arrange_sim.pybullet.runs import SimulatedRun

    module = treefile.load(TREES / "four_cubes.py")
    wanted = set(checkpoints(runs))
    figures: dict[int, float] = {}
    within = 0
    start = time.perf_counter()
    for number in range(1, runs + 1):
        root = treefile.build_root(module)
        with SimulatedRun(root, treefile.scene(module, number)) as run:
            report = run.run()
        within += report.all_within_threshold
        if number in wanted:
            figures[number] = round(resident_mb(), 1)
            if progress:
                print(f"  run {number}: {figures[number]:.1f} MB", file=sys.stderr, flush=True)
    return {
        "runs": runs,
        "all_within": within,
        "resident_mb": {str(n): mb for n, mb in figures.items()},
        "growth_pct": growth_pct(figures),
        "wall_s": round(time.perf_counter() - start, 1),
    }


def _trial_in_worker(index: int, trim: bool = False) -> tuple[str, float]:
    """One Table 1 "system" trial in the pool's worker; its status and the worker's resident memory after it."""
    global TRIM  # noqa: PLW0603
    TRIM = trim
    from bt_arrange_sim.experiment.options import TrialSpec
    from bt_arrange_sim.experiment.trial import run_trial

    record = run_trial(TrialSpec(row="system", index=index, seed=0, threshold_mm=1.0))
    return str(record.get("status")), resident_mb()


def worker_trials(trials: int, progress: bool = True) -> dict:
    """``trials`` trials one after the other in one worker of a process pool; its resident memory at the checkpoints."""
    wanted = set(checkpoints(trials))
    figures: dict[int, float] = {}
    statuses: dict[str, int] = {}
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=1) as pool:
        trial = functools.partial(_trial_in_worker, trim=TRIM)
        for number, (status, mb) in enumerate(pool.map(trial, range(trials)), start=1):
            statuses[status] = statuses.get(status, 0) + 1
            if number in wanted:
                figures[number] = round(mb, 1)
                if progress:
                    print(f"  trial {number}: {figures[number]:.1f} MB", file=sys.stderr, flush=True)
    return {
        "trials": trials,
        "statuses": statuses,
        "resident_mb": {str(n): mb for n, mb in figures.items()},
        "growth_pct": growth_pct(figures),
        "wall_s": round(time.perf_counter() - start, 1),
    }


def positive(text: str) -> int:
    """An argparse type: a whole number of 1 or more."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} must be 1 or more")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=positive, default=1000, help="four-cube runs in this process (default 1000)")
    parser.add_argument(
        "--trials", type=int, default=200, help="trials in one campaign worker (default 200; 0 skips the worker)"
    )
    parser.add_argument("--trim", action="store_true", help="malloc_trim(0) before each reading (glibc)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    global TRIM  # noqa: PLW0603
    TRIM = args.trim
    if args.trials < 0:
        parser.error(f"--trials {args.trials} must be 0 or more")
    result: dict = {"trimmed": args.trim, "runs": four_cube_runs(args.runs)}
    if args.trials:
        result["worker"] = worker_trials(args.trials)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    for name, figures in result.items():
        if not isinstance(figures, dict):
            continue
        count = figures.get("runs", figures.get("trials"))
        memory = ", ".join(f"{mb:.1f} MB after {n}" for n, mb in figures["resident_mb"].items())
        print(f"{name}: {count} in one process ({figures['wall_s']} s): {memory}; growth {figures['growth_pct']} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
