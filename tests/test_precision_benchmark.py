"""benchmarks/precision.py: the plans it runs and how it counts (no simulation: the runs are the benchmark's)."""

from __future__ import annotations

import pytest
import tomllib
from benchmark_modules import load_benchmark


@pytest.fixture(scope="module")
def precision():
    return load_benchmark("precision.py", "precision_benchmark")


def test_as_shipped_keeps_the_fresco_s_thresholds_and_fracture(precision) -> None:
    shipped = tomllib.loads(precision.PLANS["fresco"].read_text())
    plan = tomllib.loads(precision.plan_text("fresco", 2, None, None, fracture=False))
    assert plan["threshold_mm"] == shipped["threshold_mm"] == 0.8
    assert plan["fresco"] == shipped["fresco"] and plan["fresco"]["tile"]["seed"] == 3, "the fracture as shipped"
    assert plan["scene"]["seed"] == 2


def test_the_default_replaces_thresholds_and_takes_the_fracture_from_the_seed(precision) -> None:
    plan = tomllib.loads(precision.plan_text("fresco", 2, 0.25, 0.25))
    assert plan["threshold_mm"] == 0.25 and plan["yaw_threshold_deg"] == 0.25
    assert plan["fresco"]["tile"]["seed"] == 2, "the fracture from the seed (the shipped one is 3)"
    assert plan["scene"]["seed"] == 2


def test_summary_counts_within_by_each_run_s_own_thresholds(precision) -> None:
    def part(truth_mm: float, yaw_deg: float = 0.0) -> dict:
        return {"truth_mm": truth_mm, "yaw_truth_deg": yaw_deg, "status": "within", "camera_mm": truth_mm}

    runs = [
        {"threshold_mm": 0.8, "yaw_threshold_deg": 0.8, "parts": [part(0.7), part(0.81), part(0.1, yaw_deg=0.9)]},
        {"threshold_mm": 1.0, "yaw_threshold_deg": 1.0, "parts": [part(0.9)]},
    ]
    summary = precision.summary(runs)
    assert summary["within_threshold_truth"] == 2
    assert summary["within_0.3mm_0.3deg_truth"] == 0
    assert summary["parts"] == 4
