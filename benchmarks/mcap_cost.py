"""What ``run.mcap`` costs: its size per minute of world time, and its share of a recorded run's wall time.

    python benchmarks/mcap_cost.py [--json] [--pairs 3] [--tree trees/four_cubes.py]
    python benchmarks/mcap_cost.py --campaign [--rows system,translation] [--trials 5] [--pairs 2] [--json]

Runs, in one process, ``--pairs`` pairs of the same simulated trial (same seed), each recorded
(``record_dir``: the images, the transitions, the replay page) once with the Foxglove streams and
once without them (``bt_arrange.foxglove.streams.start`` returning None), the order alternating
inside a pair so that a machine warming up does not favour one side. Each run's wall time is the
session's own (``report.wall_seconds``) plus the writing of the record at the end.

Key figures: ``mb_per_world_minute`` (the file's size over the run's world time), ``overhead_ratio``
(summed wall time with the streams over without them; the target is under 1.10), ``median_pair_ratio``
(the median of the pairs' ratios: one slow run on a busy machine moves it less), ``cpu_ratio`` (the
process's CPU time, every thread, with over without: what other jobs on the machine move least) and
``observer_share``, the time spent in the observer's own hooks and in finishing the file over the
recorded runs' wall time: what the recording costs the tree's thread, free of the machine's noise.
Per topic: messages and bytes before the file's compression.

``--campaign``: the same for ``experiment --record DIR`` (one MCAP per trial), after an unmeasured
warm-up campaign of one trial each way: ``--pairs`` pairs of one campaign (``--rows`` x ``--trials``,
one worker, in this process) recorded and not, the order alternating; the files' size per trial
(mean and largest) and per minute of world time, the campaigns' wall and CPU ratios, the
observer's share, and whether every trial's record is the same with and without the recording
(wall time and the ``mcap`` key aside).
"""

from __future__ import annotations

import argparse
import functools
import json
import statistics
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

from mcap.reader import make_reader

from bt_arrange import treefile
from bt_arrange.foxglove import streams
from bt_arrange.foxglove.observer import RunObserver
from bt_arrange_sim.pybullet.runs import SimulatedRun

ROOT = Path(__file__).resolve().parent.parent

#: Seconds spent in the observer's hooks and in finishing the file, summed over a run.
SPENT = {"s": 0.0}


def _timed(method: Any) -> Any:
    @functools.wraps(method)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            SPENT["s"] += time.perf_counter() - start

    return wrapper


for _name in ("on_runner", "on_transition", "on_tick", "on_frame"):
    setattr(RunObserver, _name, _timed(getattr(RunObserver, _name)))
streams.RunStreams.finish = _timed(streams.RunStreams.finish)  # type: ignore[method-assign]
streams.RunStreams.mcap_bytes = _timed(streams.RunStreams.mcap_bytes)  # type: ignore[method-assign]
_START = streams.start


def one_run(tree: str, folder: Path, with_mcap: bool) -> dict[str, float]:
    """One recorded run; its wall time (the run and the writing of its record) and world time."""
    module = treefile.load(tree)
    streams.start = _START if with_mcap else (lambda session: None)  # type: ignore[assignment]
    SPENT["s"] = 0.0
    try:
        with SimulatedRun(treefile.build_root(module), treefile.scene(module, 0), record_dir=folder) as run:
            start, cpu_start = time.perf_counter(), time.process_time()
            report = run.run()
            wall_s, cpu_s = time.perf_counter() - start, time.process_time() - cpu_start
    finally:
        streams.start = _START  # type: ignore[assignment]
    return {"wall_s": wall_s, "cpu_s": cpu_s, "world_s": report.sim_seconds, "observer_s": SPENT["s"]}


def topics(path: Path) -> dict[str, dict[str, int]]:
    """Messages and bytes (before compression) per topic."""
    found: dict[str, dict[str, int]] = defaultdict(lambda: {"messages": 0, "bytes": 0})
    with open(path, "rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages():
            found[channel.topic]["messages"] += 1
            found[channel.topic]["bytes"] += len(message.data)
    return dict(sorted(found.items(), key=lambda item: -item[1]["bytes"]))


def one_campaign(rows: list[str], trials: int, out: Path, record_dir: Path | None) -> dict[str, Any]:
    """One campaign in this process (one worker): its wall and CPU time, the observer's time, its records."""
    from bt_arrange_sim.experiment import read_trials, run_experiment

    SPENT["s"] = 0.0
    start, cpu_start = time.perf_counter(), time.process_time()
    run_experiment(rows, trials, 0, 1.0, out, record=record_dir)
    wall_s, cpu_s = time.perf_counter() - start, time.process_time() - cpu_start
    records = {(r["row"], r["trial"]): r for r in read_trials(out / "trials.jsonl")}
    return {"wall_s": wall_s, "cpu_s": cpu_s, "observer_s": SPENT["s"], "records": records}


def campaign(args: argparse.Namespace) -> dict[str, Any]:
    """The ``--campaign`` figures (see the module's text)."""
    rows = [row.strip() for row in args.rows.split(",") if row.strip()]
    with_runs, without_runs, sizes, world_s = [], [], [], 0.0
    with tempfile.TemporaryDirectory() as scratch:
        # Unmeasured: the imports and first uses (pybullet, the SDK, matplotlib) would fall on the first campaign.
        for recorded in (False, True):
            one_campaign(
                rows[:1], 1, Path(scratch) / f"warm-{int(recorded)}", Path(scratch) / "warm" if recorded else None
            )
        for pair in range(args.pairs):
            for recorded in (pair % 2 == 0, pair % 2 == 1):
                base = Path(scratch) / f"{pair}-{int(recorded)}"
                result = one_campaign(rows, args.trials, base / "out", base / "mcap" if recorded else None)
                (with_runs if recorded else without_runs).append(result)
                if recorded and not sizes:
                    for record in result["records"].values():
                        sizes.append((base / "out" / record["mcap"]).stat().st_size)
                        world_s += record["sim_seconds"]

    def outcome(records: dict) -> dict:
        return {key: {k: v for k, v in r.items() if k not in ("wall_seconds", "mcap")} for key, r in records.items()}

    reference = outcome(without_runs[0]["records"])
    identical = all(outcome(run["records"]) == reference for run in with_runs + without_runs)
    wall_with = sum(r["wall_s"] for r in with_runs)
    wall_without = sum(r["wall_s"] for r in without_runs)
    return {
        "rows": rows,
        "trials_per_row": args.trials,
        "pairs": args.pairs,
        "trials": len(sizes),
        "records_identical": identical,
        "world_s_per_trial": round(world_s / len(sizes), 2),
        "kb_per_trial_mean": round(statistics.mean(sizes) / 1e3, 1),
        "kb_per_trial_max": round(max(sizes) / 1e3, 1),
        "mb_per_world_minute": round(sum(sizes) / 1e6 / (world_s / 60), 2),
        "wall_s_with": round(statistics.median(r["wall_s"] for r in with_runs), 2),
        "wall_s_without": round(statistics.median(r["wall_s"] for r in without_runs), 2),
        "overhead_ratio": round(wall_with / wall_without, 3),
        "cpu_ratio": round(sum(r["cpu_s"] for r in with_runs) / sum(r["cpu_s"] for r in without_runs), 3),
        "observer_share": round(sum(r["observer_s"] for r in with_runs) / wall_with, 4),
    }


def print_campaign(figures: dict[str, Any]) -> None:
    """The ``--campaign`` figures for people."""
    print(
        f"campaign {','.join(figures['rows'])} x {figures['trials_per_row']} trials ({figures['trials']} trials, "
        f"{figures['world_s_per_trial']} s of world time each), {figures['pairs']} pair(s) with and without --record"
    )
    print(
        f"size per trial: {figures['kb_per_trial_mean']} kB mean, {figures['kb_per_trial_max']} kB largest; "
        f"{figures['mb_per_world_minute']} MB per minute of world time"
    )
    print(
        f"wall time (median): {figures['wall_s_with']} s with, {figures['wall_s_without']} s without; "
        f"ratio {figures['overhead_ratio']}; CPU ratio {figures['cpu_ratio']}"
    )
    print(f"the observer's own share of the recorded campaigns' wall time: {figures['observer_share'] * 100:.1f} %")
    print(f"every trial's record the same with and without --record: {'yes' if figures['records_identical'] else 'NO'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--tree", default=str(ROOT / "trees" / "four_cubes.py"))
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--campaign", action="store_true", help="experiment --record: one MCAP per trial")
    parser.add_argument("--rows", default="system,translation", help="with --campaign: the rows")
    parser.add_argument("--trials", type=int, default=5, help="with --campaign: trials per row")
    args = parser.parse_args()
    if args.campaign:
        figures = campaign(args)
        if args.json:
            print(json.dumps(figures))
        else:
            print_campaign(figures)
        return
    with_runs, without_runs, size_bytes, per_topic = [], [], 0, {}
    with tempfile.TemporaryDirectory() as scratch:
        for pair in range(args.pairs):
            for with_mcap in (pair % 2 == 0, pair % 2 == 1):
                folder = Path(scratch) / f"{pair}-{int(with_mcap)}"
                result = one_run(args.tree, folder, with_mcap)
                (with_runs if with_mcap else without_runs).append(result)
                if with_mcap:
                    size_bytes = (folder / streams.MCAP_NAME).stat().st_size
                    per_topic = topics(folder / streams.MCAP_NAME)
    world_s = with_runs[0]["world_s"]
    wall_with = sum(r["wall_s"] for r in with_runs)
    wall_without = sum(r["wall_s"] for r in without_runs)
    figures = {
        "tree": Path(args.tree).name,
        "pairs": args.pairs,
        "world_s": round(world_s, 2),
        "mcap_bytes": size_bytes,
        "mb_per_world_minute": round(size_bytes / 1e6 / (world_s / 60), 2),
        "wall_s_with": round(statistics.median(r["wall_s"] for r in with_runs), 3),
        "wall_s_without": round(statistics.median(r["wall_s"] for r in without_runs), 3),
        "overhead_ratio": round(wall_with / wall_without, 3),
        "median_pair_ratio": round(
            statistics.median(a["wall_s"] / b["wall_s"] for a, b in zip(with_runs, without_runs, strict=True)), 3
        ),
        "cpu_ratio": round(sum(r["cpu_s"] for r in with_runs) / sum(r["cpu_s"] for r in without_runs), 3),
        "observer_share": round(sum(r["observer_s"] for r in with_runs) / wall_with, 4),
        "topics": per_topic,
    }
    if args.json:
        print(json.dumps(figures))
        return
    print(f"{figures['tree']}: {figures['world_s']} s of world time, run.mcap {size_bytes / 1e6:.2f} MB")
    print(f"size: {figures['mb_per_world_minute']} MB per minute of world time")
    print(
        f"wall time (median of {args.pairs}): {figures['wall_s_with']} s with the streams, "
        f"{figures['wall_s_without']} s without; overhead ratio {figures['overhead_ratio']}, "
        f"median pair ratio {figures['median_pair_ratio']}"
    )
    print(f"CPU time of the process (every thread) with over without the streams: {figures['cpu_ratio']}")
    print(f"the observer's own share of the recorded runs' wall time: {figures['observer_share'] * 100:.1f} %")
    for topic, counts in per_topic.items():
        print(f"  {topic:22s} {counts['messages']:6d} messages {counts['bytes'] / 1e3:9.1f} kB before compression")


if __name__ == "__main__":
    main()
