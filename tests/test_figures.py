"""``scripts/figures.py`` ("Figures"): each README figure read from its benchmark's output.

The benchmarks themselves take minutes; here each one's output is given (in the shape the benchmark
prints it) and the line the script makes of it is checked, so a renamed key or a miscount fails
here rather than in a forty-minute reprint. ``benchmarks/irregular.py`` counts "within" by ground
truth itself, beside the camera's count.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _module(path: str, name: str):  # noqa: ANN202
    spec = importlib.util.spec_from_file_location(name, ROOT / path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def figures():  # noqa: ANN201
    return _module("scripts/figures.py", "figures_script")


def _irregular_row(seed: int, part: str, truth_mm: float, yaw_deg: float, status: str) -> dict:
    return {
        "seed": seed,
        "part": part,
        "pushed_truth_mm": truth_mm,
        "yaw_error_truth_deg": yaw_deg,
        "status": status,
        "within_truth": truth_mm < 1.0 and abs(yaw_deg) < 1.0,
        "regrasps_after_placing": 1 if part == "ell" else 0,
        "threshold_mm": 1.0,
        "yaw_threshold_deg": 1.0,
    }


def test_the_irregular_figure_counts_by_ground_truth_and_by_the_camera(figures, monkeypatch) -> None:
    rows = [
        _irregular_row(0, "triangle", 0.5, 0.2, "within"),
        _irregular_row(0, "ell", 1.02, 0.1, "within"),  # the camera says within, the truth does not
        _irregular_row(1, "triangle", 0.3, -0.6, "within"),
        _irregular_row(1, "ell", 0.4, 1.5, "outside"),
    ]
    monkeypatch.setattr(figures, "_run", lambda *argv: json.dumps(rows) + "\n")
    (line,) = figures.irregular()
    assert "2 outlines, 2 seeds: 2 of 4 within 1 mm and 1 deg by ground truth (3 by the camera)" in line
    assert "worst 1.02 mm and 1.50 deg; 2 regrasps after placing" in line


def test_the_fresco_figures_sum_the_runs_plain_and_injected(figures, monkeypatch) -> None:
    def run(*argv: str) -> str:
        injected = "--inject" in argv
        runs = [
            {
                "seed": seed,
                "pieces": 6,
                "gap_mm": 2.0,
                "within": 6 - (injected and seed == 1),
                "within_by_camera": 6,
                "max_final_offset_truth_mm": 0.5 + seed / 10,
                "max_yaw_error_truth_deg": 0.3,
                "min_gap_truth_mm": 1.2 - seed / 10,
                "threshold_mm": 1.0,
                "yaw_threshold_deg": 1.0,
            }
            for seed in (0, 1, 2)
        ]
        return "".join(json.dumps(r) + "\n" for r in runs) + "17 of 18 pieces ... (the summary line)\n"

    monkeypatch.setattr(figures, "_run", run)
    plain, injected = figures.fresco()
    assert "6 pieces with 2 mm gaps, 3 seeds: 18 of 18 within 1 mm and 1 deg by ground truth" in plain
    assert "(18 by the camera)" in plain
    assert "worst 0.70 mm and 0.30 deg; smallest gap at the end 1.00 mm (no two pieces touching)" in plain
    assert "17 of 18" in injected and "--inject pick_translation" in injected


def test_the_tight_gaps_figure_runs_the_fresco_at_its_threshold_and_counts_by_ground_truth(
    figures, monkeypatch
) -> None:
    asked = []

    def run(*argv: str) -> str:
        asked.append(argv)
        runs = [
            {"seed": seed, "pieces": 6, "gap_mm": 0.5, "threshold_mm": 0.25, "yaw_threshold_deg": 0.25,
             "within": 5 + (seed != 1), "within_by_camera": 5, "max_final_offset_truth_mm": 0.5 + seed / 100}
            for seed in (0, 1, 2)
        ]  # fmt: skip
        return "".join(json.dumps(r) + "\n" for r in runs)

    monkeypatch.setattr(figures, "_run", run)
    (line,) = figures.tight_gaps()
    assert asked == [("benchmarks/fresco.py", "--seeds", "0", "1", "2", *figures.TIGHT_GAPS)]
    assert "at a 0.25 mm threshold with 0.5 mm gaps, 3 seeds: 17 of 18 within 0.25 mm and 0.25 deg" in line
    assert "by ground truth (15 by the camera), worst 0.520 mm" in line


def test_the_real_cell_figure_counts_within_by_ground_truth_from_the_trial_records(figures, monkeypatch) -> None:
    def run(*argv: str) -> str:
        if argv[0] == "experiment":
            out = Path(argv[argv.index("--out") + 1])
            threshold = 0.5 if "--threshold-mm" in argv else 1.0
            truths = [0.2, 0.4, threshold + 0.01]  # the last within by the camera, not by the truth
            records = [{"row": "system", "status": "within", "pushed_truth_mm": t} for t in truths]
            records.append({"row": "system", "status": "error", "pushed_truth_mm": None})
            (out / "trials.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
            (out / "summary.json").write_text(json.dumps([{
                "row": "system", "trials": 3, "success_rate": 1.0, "placed_mean_mm": 3.0, "pushed_mean_mm": 0.5,
                "pushed_truth_mean_mm": 0.5, "pushes_mean": 1.0}]))  # fmt: skip
        return ""

    monkeypatch.setattr(figures, "_run", run)
    paper, ours = figures.real_cell()
    assert "2 of 3 within 1 mm by ground truth (3 of 3 by the camera)" in paper
    assert "2 of 3 within 0.5 mm by ground truth (3 of 3 by the camera)" in ours


def test_the_outline_calibration_cycle_time_and_records_figures_read_their_keys(figures, monkeypatch) -> None:
    outputs = {
        "benchmarks/outlines.py": {
            "results": {
                "cell": {
                    "all": {
                        "detections": 500,
                        "misses": 0,
                        "xy_error_mm": {"mean": 0.0181},
                        "yaw_error_deg": {"mean": 0.0212},
                    }
                }
            }
        },
        "benchmarks/calibration.py": {
            "reprojection_error_px": 0.1534,
            "camera_to_base_error_mm": 0.2513,
            "camera_to_base_error_mrad": 0.5921,
            "detection_calibrated": {"mean_mm": 0.1213, "max_mm": 0.3, "found": 36, "cubes": 36},
        },
        "benchmarks/throughput.py": {"world_s_per_object": 3.47, "bound_s_per_object": 2.85, "bound_ratio": 1.2201},
        "benchmarks/campaign_wall.py": {
            "records": 400,
            "identical_records": 399,
            "differing_records": ["orientation #41"],
            "added_fields": ["regrasps_after_placing"],
        },
    }
    monkeypatch.setattr(figures, "_run", lambda *argv: json.dumps(outputs[argv[0]]) + "\n")
    assert "0.018 mm and 0.021 deg mean, 0 misses in 500" in figures.outlines()[0]
    calibration = figures.calibration()[0]
    assert "reprojection 0.153 px, camera pose 0.25 mm and 0.59 mrad off the true one" in calibration
    assert "cubes measured 0.12 mm off" in calibration
    assert "3.5 s of world time per cube, 1.22x the lower bound" in figures.cycle_time()[0]
    records = figures.records()[0]
    assert "399 of 400; differing: orientation #41" in records
    assert "not compared: regrasps_after_placing" in records


def test_every_figure_has_a_name_and_unknown_names_are_refused(figures, capsys) -> None:
    assert figures.main(["--list"]) == 0
    listed = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in listed] == list(figures.FIGURES)
    for name in ("irregular", "fresco", "tight_gaps", "outlines", "calibration", "cycle_time", "records"):
        assert name in figures.FIGURES
    with pytest.raises(SystemExit):
        figures.main(["--skip", "nonsense"])
    assert "unknown figure 'nonsense'" in capsys.readouterr().err


def test_the_memory_benchmark_reads_growth_from_run_two() -> None:
    memory = _module("benchmarks/memory.py", "memory_benchmark")
    assert memory.checkpoints(1000) == [2, 10, 100, 1000]
    assert memory.checkpoints(60) == [2, 10, 60]
    assert memory.growth_pct({2: 100.0, 10: 101.0, 60: 104.0}) == 4.0
    assert memory.growth_pct({1: 100.0}) is None


def test_quick_names_each_campaign_it_leaves_out_and_the_command_it_runs(figures, capsys, monkeypatch) -> None:
    monkeypatch.setattr(figures, "_run", lambda *argv: pytest.fail(f"{argv} was run"))
    others = [name for name in figures.FIGURES if name not in figures.CAMPAIGNS]
    assert figures.main(["--quick", "--skip", ",".join(others)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines] == ["table1", "real_cell", "records"]
    assert "left out by --quick" in lines[2] and f"campaign_wall.py --against {figures.BEFORE_WINDOWS}" in lines[2]
