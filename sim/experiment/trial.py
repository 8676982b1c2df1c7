"""One trial: a seeded single-part arrangement in a fresh cell, with its row's errors; its JSON-able record.

A trial is a pure function of its ``TrialSpec``: the start, the target, the injected errors and a
real cell's per-run errors are all drawn from the experiment's seed, the row and the trial number.
"""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

import numpy as np

from bt_arrange.errors import RecordError
from bt_arrange.files import WriteFault
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.experiment.engines import trial_engine
from bt_arrange_sim.experiment.options import TrialSpec, parse_object
from bt_arrange_sim.experiment.raised import SupportWatch, raised_plan
from bt_arrange_sim.experiment.recording import record_keys
from bt_arrange_sim.experiment.rows import RAISED_ROWS, ROWS, row_injectors
from bt_arrange_sim.realcell import parse_cell

#: Targets of the trials: inside the camera's view and the arm's comfortable reach.
TARGET_X_RANGE_M = (0.38, 0.62)


TARGET_Y_RANGE_M = (-0.25, 0.25)


#: One trial at a time per process: py_trees' blackboard is process-wide, so two trials in two
#: threads of one worker (a Dask worker with several threads) would read each other's keys.
_TRIAL_LOCK = threading.Lock()


def run_trial(spec: TrialSpec) -> dict:
    """Run one trial in a fresh cell and return its record (a JSON-able dict); one per process at a time."""
    with _TRIAL_LOCK:
        return _run_trial(spec)


def _run_trial(spec: TrialSpec) -> dict:
    from bt_arrange.trees import Target, arrangement
    from bt_arrange_sim.scenes import scatter

    wall_start = time.perf_counter()
    rng = np.random.default_rng([spec.seed, ROWS.index(spec.row), spec.index])
    kind = parse_object(spec.object_name)
    target = Target(
        "red",
        float(rng.uniform(*TARGET_X_RANGE_M)),
        float(rng.uniform(*TARGET_Y_RANGE_M)),
        float(rng.uniform(-math.pi / 4, math.pi / 4)),
        object_type=kind,
    )
    plan = raised_plan(target, rng) if spec.row in RAISED_ROWS else [target]
    starts = scatter([t.colour for t in plan], int(rng.integers(2**31)), avoid=plan, object_types=[kind] * len(plan))
    if spec.row == "grasp-estimator":
        root = _depth_grasp_tree(target, spec.threshold_mm, int(rng.integers(2**31)), spec.strategy)
    else:
        root = arrangement(plan, threshold_mm=spec.threshold_mm, max_pushes=10, strategy=spec.strategy)
        target = plan[-1]
    injectors = row_injectors(spec.row)
    injection_seed = int(rng.integers(2**31))
    calibration = None
    if spec.calibration is not None:
        from bt_arrange.calibration import read_calibration

        calibration = read_calibration(spec.calibration)
    engine = trial_engine(spec.engine)
    mcap_path, mcap_fault = _recording(spec)
    recording = {"mcap_path": mcap_path} if mcap_path is not None else {}
    with engine.open_trial_run(
        root, starts, cell_config=_cell_config(spec), calibration=calibration, **recording
    ) as run:
        if injectors:
            from bt_arrange_sim.injection import attach_all

            attach_all(run, "red", injectors, injection_seed)
        below = SupportWatch(run, *plan) if len(plan) > 1 else None
        try:
            report = run.run()
        except RecordError as error:  # the trial's MCAP only (a trial records nothing else): its measurement stands
            report = error.result
            mcap_fault = error.faults[0] if error.faults else WriteFault(Path(str(spec.mcap)), str(error))
    outcome = next(o for o in report.objects if o.name == target.obj)
    bad_grasps = [t.feedback for t in report.transitions if t.kind == "Pick" and t.new == "FAILURE"]
    # Pick states what its grip was as facts (``Pick.facts``), not only in its feedback text.
    squarings = [t for t in report.transitions if t.kind == "Pick" and t.new == "SUCCESS" and t.facts.get("squared")]
    return {
        **spec.record_fields(),
        "target": [round(v, 6) for v in outcome.target],
        "placed_mm": outcome.placed_offset_mm,
        "pushed_mm": outcome.final_offset_mm,
        "placed_truth_mm": outcome.placed_offset_truth_mm,
        "pushed_truth_mm": outcome.final_offset_truth_mm,
        "pushes": outcome.pushes,
        "regrasps": len(bad_grasps),
        "regrasp_reasons": bad_grasps,
        # Picked up again after it was placed (turned, pushes stalled): "placed_mm" stays the first placing's.
        "regrasps_after_placing": outcome.regrasps_after_placing,
        "placed_again_mm": outcome.placed_again_offset_mm,
        "placed_again_truth_mm": outcome.placed_again_offset_truth_mm,
        # Picks that squared a cube pinched across its corners instead of letting go (Pick's "squaring").
        "squarings": len(squarings),
        "status": outcome.status,
        "reason": outcome.reason,
        "injected": {injector.name: injector.record() for injector in injectors},
        **(below.fields(report) if below is not None else {}),
        "sim_seconds": round(report.sim_seconds, 3),
        "wall_seconds": round(time.perf_counter() - wall_start, 3),
        **(record_keys(Path(spec.mcap), mcap_fault) if spec.mcap is not None else {}),
    }


def _recording(spec: TrialSpec) -> tuple[Path | None, WriteFault | None]:
    """Where the trial records its MCAP (``experiment --record``), or a fault when this process cannot."""
    if spec.mcap is None:
        return None, None
    from bt_arrange.foxglove import streams

    if not streams.sdk_available():  # a Dask worker installed without the extra
        return None, WriteFault(Path(spec.mcap), f"this worker has no Foxglove SDK ({streams.INSTALL_HINT})")
    return Path(spec.mcap), None


def _cell_config(spec: TrialSpec) -> CellConfig:
    """The trial's cell; a real cell's per-run errors are seeded from the trial, apart from its draws."""
    errors = parse_cell(spec.cell)
    if not errors.enabled:
        return CellConfig()
    run_seed = int(np.random.default_rng([spec.seed, ROWS.index(spec.row), spec.index, 12]).integers(2**31))
    return CellConfig(errors=errors.with_run_seed(run_seed))


def _depth_grasp_tree(target, threshold_mm: float, seed: int, strategy: str = "paper"):  # noqa: ANN001, ANN202
    """Algorithm 1 with line 6 (pose estimation before picking) done by the depth-only substitute."""
    from bt_arrange.behaviours import MoveHome
    from bt_arrange.plan import ArrangementPlan, PartStep, PushStrategy, Tolerance
    from bt_arrange.trees import Arrangement, by_depth, render_part

    plan = ArrangementPlan(
        targets=(target,),
        tolerance=Tolerance(threshold_mm, 1.0),
        strategy=PushStrategy.parse(strategy, "strategy"),
        max_pushes=10,
    )
    arrange = render_part(PartStep.free(target), plan, by_depth(seed))
    return Arrangement("arrangement", [arrange, MoveHome("park the arm")], [target], threshold_mm)
