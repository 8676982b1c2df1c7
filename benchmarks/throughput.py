"""Throughput benchmark: where the wall time and the world time of an arrangement go.

    python benchmarks/throughput.py --json [--seed 0]

Runs, in one process and one after the other: the bare robot (the URDF with nothing on the
table, holding its home pose) stepped for a few seconds of world time, for reference; a
single-cube trial (``trees/single_cube.py``); the four-cube tree (``trees/four_cubes.py``); and
the shipped examples of irregular parts (``--examples``, default ``irregular_parts,fresco``:
``bt-arrange run irregular_parts``, ``bt-arrange run fresco``).
For each trial the wall time of the run is split into exclusive sections: ``render`` (camera
captures), ``physics`` (inside the world's stepping), ``perception`` (the detector, and the
fits a behaviour calls beside it: the held look, touching parts, a standing part's top face),
``planning`` (inverse kinematics and trajectories), ``tree`` (the rest of the ticks) and
``rest`` (the runner's loop, logging, hooks). Timers wrap the objects' methods in this
benchmark only (``bt_arrange.timing``): an ordinary run is not instrumented.

World time is attributed per tick to what the running behaviour was doing: following a motion,
letting the arm settle after one, waiting for the fingers, or braking. The table (without
``--json``; ``stage_rows`` with it) lists each stage, or chain of motions handed on without
stopping, with its world time and bound, each tick counted once: a stage ending two kinds of chain
(a look's move out of the view after a retreat and after a push) counts in each only its own ticks.

Beside it, a lower bound for the same waypoints (``BoundRecorder``, ``bt_arrange.motion.bounds``):
every motion the run planned, as the time-optimal jerk-limited trajectory between the same joint
vectors at the UR5's joint speeds (the URDF's) and the project's fastest acceleration and jerk
(``ManipulationSettings.free_joint_limits``), a line no faster than its path at 1 m/s; motions
handed on at speed bounded together, from the first one's start to the last one's end; the fingers'
travel at the 2F-85's 150 mm/s; settling, looking and ticks between behaviours at nothing.

Key figures (``--json`` keys; the last three a contract): ``render_share`` (rendering's fraction of
the single-cube trial's wall time), ``floor_ratio`` (that trial's wall time over the time spent
stepping its physics: 1.0 would mean nothing but physics costs anything), and for the four-cube
tree ``world_s_per_object``, ``bound_s_per_object`` and ``bound_ratio`` (world time over the bound).
``examples`` holds the same keys per example, with ``real_time_factor`` (world time over wall
time), ``real_time_factor_cpu`` (over the process's CPU time, which other jobs on a shared machine
do not stretch), ``perception_share`` (perception's fraction of the wall time) and
``perception_share_cpu`` (its fraction of the CPU time: the detector's OpenCV and NumPy may use
several threads, so on a shared machine its wall share moves with the other jobs); every trial
has them.
Wall-clock figures depend on the machine and on what else runs on it: compare ratios from one run.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import math
import sys
import time
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange import examples, treefile
from bt_arrange.behaviours import Context
from bt_arrange.behaviours.base import GripperStage, MoveStage, OnlyIf, StagedBehaviour
from bt_arrange.motion import LinearMotion
from bt_arrange.motion.bounds import finger_bound_s, joint_move_bound_s, line_bound_s
from bt_arrange.perception import PartDetector
from bt_arrange.runner import Runner
from bt_arrange.timing import SectionTimers
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.runs import SimulatedRun

TREES = Path(__file__).resolve().parent.parent / "trees"
SECTIONS = ("render", "physics", "perception", "planning", "tree", "rest")
#: The shipped examples of irregular parts measured beside the cubes (``bt-arrange examples``).
EXAMPLES = ("irregular_parts", "fresco")
#: The detector's entry points: timed on the class, so the copies a look makes for one part type
#: (``PartDetector.for_object``) are timed too.
DETECTOR_METHODS = ("detect", "detect_all", "locate")
#: The perception a behaviour calls outside the detector, timed where the behaviour's module holds
#: it: (module, name). The held look's fit is most of it in a fresco.
PERCEPTION_FUNCTIONS = (
    ("bt_arrange.behaviours.held", "measure_held"),
    ("bt_arrange.behaviours.looking", "touching_pixels"),
    ("bt_arrange.behaviours.separate", "touching_clusters"),
    ("bt_arrange.behaviours.standing", "measure_top_face"),
    ("bt_arrange.behaviours.puzzle", "measure_unknown_outlines"),
)


@contextlib.contextmanager
def timed_on_class(timers: SectionTimers, cls: type, methods: tuple[str, ...], section: str) -> Iterator[None]:
    """Time ``methods`` of every instance of ``cls`` as ``section`` while inside; the class restored after."""
    own = {name: cls.__dict__[name] for name in methods if name in cls.__dict__}
    try:
        for name, function in own.items():
            setattr(cls, name, timers.wrap(section, function))
        yield
    finally:
        for name, function in own.items():
            setattr(cls, name, function)


@contextlib.contextmanager
def timed_functions(timers: SectionTimers, functions: tuple[tuple[str, str], ...], section: str) -> Iterator[None]:
    """Time each module-level ``(module, name)`` as ``section`` while inside; the modules restored after."""
    saved = []
    try:
        for module_name, name in functions:
            module = importlib.import_module(module_name)
            if hasattr(module, name):
                saved.append((module, name, getattr(module, name)))
                setattr(module, name, timers.wrap(section, getattr(module, name)))
        yield
    finally:
        for module, name, function in saved:
            setattr(module, name, function)


def bare_stepping(seconds: float = 4.0) -> dict:
    """Stepping rate of the robot alone: nothing on the table, holding its home pose."""
    with WorkCell() as cell:
        cell.settle(0.2)
        periods = max(1, round(seconds / cell.config.physics.control_period_s))
        start = time.perf_counter()
        cell.step(periods)
        wall = time.perf_counter() - start
        world = periods * cell.config.physics.control_period_s
        steps = periods * cell.config.physics.substeps
    return {
        "world_s": round(world, 3),
        "wall_s": round(wall, 3),
        "physics_steps_per_s": round(steps / wall, 1),
        "real_time_factor": round(world / wall, 1),
    }


def _stage_of(root: py_trees.behaviour.Behaviour, context: Context) -> tuple[str, str]:
    """(category, stage name) of what the innermost running staged behaviour is doing."""
    running = [n for n in root.iterate() if isinstance(n, StagedBehaviour) and n.status == Status.RUNNING]
    if not running:
        return "tree", "between behaviours"
    node = running[-1]
    if context.brake.active:
        return "braking", f"{type(node).__name__}: waiting for the arm to stop"
    stages = node._stages  # noqa: SLF001 - a benchmark looks inside
    if node._index >= len(stages):  # noqa: SLF001
        return "tree", type(node).__name__
    stage = stages[node._index]  # noqa: SLF001
    inner = stage._stage if isinstance(stage, OnlyIf) else stage  # noqa: SLF001
    label = f"{type(node).__name__}: {stage.name}"
    if isinstance(inner, MoveStage):
        moving = inner.motion is not None and not inner.motion.done
        return ("motion" if moving else "settle"), label
    if isinstance(inner, GripperStage):
        return "gripper", label
    return "other", label


class BoundRecorder:
    """The motions and finger travel of a run, by stage, and their lower bounds (``bt_arrange.motion.bounds``).

    Every motion a stage plans is bounded by the time-optimal rest-to-rest trajectory between the
    same joint vectors at the UR5's joint speeds and the project's fastest acceleration and jerk
    (and, for a line, its path at 1 m/s); the fingers by their travel at the 2F-85's top speed.
    A motion handed on to the next without stopping (``Motion.handed_on``) is bounded together with
    it, from the first one's start to the last one's end: passing through a waypoint at speed is not
    bounded by stopping there. Settling, looking and the ticks between behaviours are bounded by 0.
    """

    def __init__(self, context: Context) -> None:
        self.settings = context.settings
        self.motions: list[tuple[str, object, np.ndarray]] = []
        self._seen: set[int] = set()
        self.finger_travel_m: dict[str, float] = defaultdict(float)
        self._width_m: float | None = None
        #: World time (s) of the ticks spent on each motion (following it or settling after it), by the
        #: motion's id; the other ticks by stage label. A stage that follows several motions (a look's
        #: move out of the view after a retreat or after a push) is so counted once, in each chain.
        self.world_by_motion: dict[int, float] = defaultdict(float)
        self.world_elsewhere: dict[str, float] = defaultdict(float)

    def on_tick(
        self,
        category: str,
        stage: str,
        node: py_trees.behaviour.Behaviour | None,
        context: Context,
        period_s: float = 0.0,
    ) -> None:
        """Record a newly planned motion, or the fingers' travel in a gripper stage, and the tick's world time."""
        width = context.robot.gripper.width()
        if category == "gripper" and self._width_m is not None:
            self.finger_travel_m[stage] += abs(width - self._width_m)
        self._width_m = width
        inner = _inner_stage(node) if isinstance(node, StagedBehaviour) else None
        motion = getattr(inner, "motion", None)
        if not isinstance(inner, MoveStage) or motion is None:
            self.world_elsewhere[stage] += period_s
            return
        self.world_by_motion[id(motion)] += period_s
        if id(motion) not in self._seen:
            self._seen.add(id(motion))
            self.motions.append((stage, motion, np.asarray(getattr(inner, "start_q", motion.target_positions_rad))))

    def rows(self) -> list[tuple[str, float, float]]:
        """(stage or chain of handed-on stages, world time, bound) of the run, each tick counted once, longest first."""
        bounds = self.bounds_by_stage()
        world: dict[str, float] = defaultdict(float)
        chain: list[tuple[str, object, np.ndarray]] = []
        for entry in self.motions:
            chain.append(entry)
            if getattr(entry[1], "handed_on", False):
                continue
            label = " + ".join(dict.fromkeys(stage for stage, _, _ in chain))
            world[label] += sum(self.world_by_motion[id(motion)] for _, motion, _ in chain)
            chain = []
        for stage, seconds in self.world_elsewhere.items():
            world[stage] += seconds
        labels = set(world) | set(bounds)
        return sorted(((label, world.get(label, 0.0), bounds.get(label, 0.0)) for label in labels), key=lambda r: -r[1])

    def bounds_by_stage(self) -> dict[str, float]:
        """Seconds of lower bound per stage label; a chain of handed-on motions under its stages joined by " + "."""
        s = self.settings
        joint_limits, line_limits = s.free_joint_limits, s.free_line_limits
        bounds: dict[str, float] = defaultdict(float)
        chain: list[tuple[str, object, np.ndarray]] = []
        for entry in self.motions:
            chain.append(entry)
            _, motion, _ = entry
            if getattr(motion, "handed_on", False):
                continue
            first_stage, first, start_q = chain[0]
            label = " + ".join(dict.fromkeys(stage for stage, _, _ in chain))
            target_q = motion.target_positions_rad  # type: ignore[attr-defined]
            if len(chain) == 1 and isinstance(first, LinearMotion):
                bound = line_bound_s(start_q, target_q, first.length_m, joint_limits, line_limits)
            else:
                bound = joint_move_bound_s(start_q, target_q, joint_limits)
            bounds[label] += bound
            chain = []
        top_speed = s.gripper.speed_range_m_s[1]
        for stage, travel in self.finger_travel_m.items():
            bounds[stage] += finger_bound_s(travel, top_speed)
        return dict(bounds)


def _inner_stage(node: StagedBehaviour) -> object | None:
    stages = node._stages  # noqa: SLF001 - a benchmark looks inside
    if node._index >= len(stages):  # noqa: SLF001
        return None
    stage = stages[node._index]  # noqa: SLF001
    return stage._stage if isinstance(stage, OnlyIf) else stage  # noqa: SLF001


def _running_node(root: py_trees.behaviour.Behaviour) -> StagedBehaviour | None:
    running = [n for n in root.iterate() if isinstance(n, StagedBehaviour) and n.status == Status.RUNNING]
    return running[-1] if running else None


def run_trial(tree_file: Path, seed: int) -> dict:
    """One tree in a fresh cell, instrumented; returns its time split, its lower bound and its outcome."""
    module = treefile.load(tree_file)
    root = treefile.build_root(module)
    timers = SectionTimers()
    # The detector's CPU time too: a share of wall time depends on what else the machine runs.
    cpu_timers = SectionTimers(clock=time.process_time)
    world_by_category: dict[str, float] = defaultdict(float)
    world_by_stage: dict[str, float] = defaultdict(float)
    with (
        timed_on_class(timers, PartDetector, DETECTOR_METHODS, "perception"),
        timed_on_class(cpu_timers, PartDetector, DETECTOR_METHODS, "perception"),
        timed_functions(timers, PERCEPTION_FUNCTIONS, "perception"),
        timed_functions(cpu_timers, PERCEPTION_FUNCTIONS, "perception"),
        SimulatedRun(root, treefile.scene(module, seed)) as run,
    ):
        cell, context = run.cell, run.context
        period_s = cell.config.physics.control_period_s
        timers.wrap_method(cell, "step", "physics")
        timers.wrap_method(cell.camera, "capture", "render")
        for method in ("move_joints", "move_to_pose", "move_line"):
            timers.wrap_method(context.planner, method, "planning")

        recorder = BoundRecorder(context)
        #: The bookkeeping's own CPU seconds, left out of the trial's CPU time as its wall time is of the wall.
        bookkeeping_cpu_s = [0.0]

        def on_tick(tree_root: py_trees.behaviour.Behaviour) -> None:
            started_cpu = time.process_time()
            category, stage = _stage_of(tree_root, context)
            world_by_category[category] += period_s
            world_by_stage[stage] += period_s
            recorder.on_tick(category, stage, _running_node(tree_root), context, period_s)
            bookkeeping_cpu_s[0] += time.process_time() - started_cpu

        def time_ticks(runner: Runner) -> None:
            timers.wrap_method(runner, "tick_tree", "tree")

        # The benchmark's own bookkeeping is timed apart and left out of the trial's wall time.
        run.tick_hooks.append(timers.wrap("benchmark", on_tick))
        run.runner_hooks.append(time_ticks)
        start, start_cpu = time.perf_counter(), time.process_time()
        report = run.run()
        wall_s = time.perf_counter() - start - timers.seconds.get("benchmark", 0.0)
        # The process's CPU time, which other jobs on a shared machine do not stretch, without the
        # benchmark's bookkeeping (its CPU time: its wall time, stretched by other jobs, could exceed it).
        cpu_s = time.process_time() - start_cpu - bookkeeping_cpu_s[0]
        captures = timers.calls.get("render", 0)
    bound_by_stage = recorder.bounds_by_stage()
    bound_s = sum(bound_by_stage.values())
    seconds = {name: timers.seconds.get(name, 0.0) for name in SECTIONS[:-1]}
    seconds["rest"] = max(0.0, wall_s - sum(seconds.values()))
    physics_s = seconds["physics"]
    objects = report.objects
    return {
        "tree": tree_file.name,
        "seed": seed,
        "status": report.tree_status,
        "objects": len(objects),
        "all_within": report.all_within_threshold,
        "final_offset_mm": [o.final_offset_mm for o in objects],
        "final_offset_truth_mm": [o.final_offset_truth_mm for o in objects],
        "pushes": [o.pushes for o in objects],
        "world_s": round(report.sim_seconds, 3),
        "world_s_per_object": round(report.sim_seconds / max(1, len(objects)), 3),
        "bound_s": round(bound_s, 3),
        "bound_s_per_object": round(bound_s / max(1, len(objects)), 3),
        "bound_ratio": round(report.sim_seconds / bound_s, 3) if bound_s > 0 else None,
        "wall_s": round(wall_s, 3),
        "real_time_factor": round(report.sim_seconds / wall_s, 2) if wall_s > 0 else None,
        "cpu_s": round(cpu_s, 3),
        "real_time_factor_cpu": round(report.sim_seconds / cpu_s, 2) if cpu_s > 0 else None,
        "perception_share": round(seconds["perception"] / wall_s, 4) if wall_s > 0 else None,
        "perception_share_cpu": round(cpu_timers.seconds.get("perception", 0.0) / cpu_s, 4) if cpu_s > 0 else None,
        "wall_s_by_section": {name: round(value, 3) for name, value in seconds.items()},
        "share_by_section": {name: round(value / wall_s, 4) for name, value in seconds.items()},
        "floor_ratio": round(wall_s / physics_s, 3) if physics_s > 0 else math.inf,
        "captures": captures,
        "render_ms_per_capture": round(1000 * seconds["render"] / captures, 1) if captures else None,
        "world_s_by_activity": {k: round(v, 3) for k, v in sorted(world_by_category.items())},
        "world_s_by_stage": {k: round(v, 3) for k, v in sorted(world_by_stage.items(), key=lambda kv: -kv[1])},
        "bound_s_by_stage": {k: round(v, 3) for k, v in sorted(bound_by_stage.items(), key=lambda kv: -kv[1])},
        "stage_rows": [[label, round(world, 3), round(bound, 3)] for label, world, bound in recorder.rows()],
    }


def _stage_rows(trial: dict) -> list[tuple[str, float, float]]:
    """(stage or chain of stages, world time, bound) for the table, longest first: each tick counted once."""
    return [(label, world_s, bound_s) for label, world_s, bound_s in trial["stage_rows"]]


def _example_summary(trial: dict) -> dict:
    """The four-cube figures' keys for one example, and its speed and perception share."""
    keys = (
        "world_s_per_object",
        "bound_s_per_object",
        "bound_ratio",
        "real_time_factor",
        "real_time_factor_cpu",
        "perception_share",
        "perception_share_cpu",
    )
    return {key: trial[key] for key in ("status", "all_within", *keys)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=0, help="scene seed of both trials (default 0)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--examples",
        default=",".join(EXAMPLES),
        help=f"shipped examples measured after the cubes, comma-separated, or 'none' (default {','.join(EXAMPLES)})",
    )
    args = parser.parse_args(argv)
    names = [] if args.examples == "none" else [n for n in args.examples.split(",") if n]
    unknown = [n for n in names if examples.path_of(n) is None]
    if unknown:
        parser.error(f"no example {', '.join(unknown)} (bt-arrange examples lists them)")

    bare = bare_stepping()
    single = run_trial(TREES / "single_cube.py", args.seed)
    four = run_trial(TREES / "four_cubes.py", args.seed)
    measured = {name: run_trial(examples.path_of(name), args.seed) for name in names}  # type: ignore[arg-type]
    summary = {
        "benchmark": "throughput",
        "note": "wall times on this machine (shared with other jobs if so): compare the ratios",
        "render_share": single["share_by_section"]["render"],
        "floor_ratio": single["floor_ratio"],
        "world_s_per_object": four["world_s_per_object"],
        "bound_s_per_object": four["bound_s_per_object"],
        "bound_ratio": four["bound_ratio"],
        "bare_robot": bare,
        "single_cube": single,
        "four_cubes": four,
        "examples": {name: _example_summary(trial) for name, trial in measured.items()},
        "example_trials": measured,
    }
    if args.json:
        print(json.dumps(summary))
    else:
        for trial in (single, four, *measured.values()):
            split = ", ".join(f"{k} {v:.0%}" for k, v in trial["share_by_section"].items())
            print(
                f"{trial['tree']}: {trial['world_s']} s of world time ({trial['world_s_per_object']} s per object) "
                f"in {trial['wall_s']} s of wall time ({trial['real_time_factor']}x real time; "
                f"{trial['real_time_factor_cpu']}x by CPU time): {split}; "
                f"wall / physics {trial['floor_ratio']}"
            )
            print(f"  world time by activity: {trial['world_s_by_activity']}")
            print(
                f"  lower bound {trial['bound_s']} s ({trial['bound_s_per_object']} s per object): "
                f"world time / bound {trial['bound_ratio']}"
            )
            for label, world_s, bound_s in _stage_rows(trial):
                print(f"    {label:85s} {world_s:6.3f} s  bound {bound_s:6.3f} s")
        print(
            f"bare robot: {bare['physics_steps_per_s']} physics steps per second "
            f"({bare['real_time_factor']}x real time)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
