"""benchmarks/throughput.py's table of where world time goes: each tick counted once (no simulation)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from benchmark_modules import load_benchmark

from bt_arrange.settings import ManipulationSettings


@pytest.fixture(scope="module")
def throughput():
    return load_benchmark("throughput.py", "throughput_benchmark")


def motion(to_q: float, handed_on: bool = False) -> SimpleNamespace:
    return SimpleNamespace(target_positions_rad=np.full(6, to_q), handed_on=handed_on)


def test_a_stage_that_ends_two_chains_is_counted_once_in_each(throughput) -> None:
    # A look's move out of the view follows a retreat (handed on) and, later, a push's lift (handed on):
    # its 0.6 s after the retreat and its 0.5 s after the lift belong to their own chains only.
    recorder = throughput.BoundRecorder(SimpleNamespace(settings=ManipulationSettings()))
    retreat, out1, lift, out2 = motion(0.1, True), motion(0.5), motion(0.6, True), motion(1.0)
    recorder.motions = [
        ("Place: retreat", retreat, np.zeros(6)),
        ("Inspect: move out", out1, np.full(6, 0.1)),
        ("Push: lift", lift, np.full(6, 0.5)),
        ("Inspect: move out", out2, np.full(6, 0.6)),
    ]
    for item, seconds in ((retreat, 0.2), (out1, 0.6), (lift, 0.2), (out2, 0.5)):
        recorder.world_by_motion[id(item)] = seconds
    recorder.world_elsewhere["Place: release"] = 0.15
    rows = {label: world for label, world, _ in recorder.rows()}
    assert rows == pytest.approx(
        {"Place: retreat + Inspect: move out": 0.8, "Push: lift + Inspect: move out": 0.7, "Place: release": 0.15}
    )
    assert sum(rows.values()) == pytest.approx(1.65), "every tick once"
