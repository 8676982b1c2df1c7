"""Measure the detector on synthetic frames: corner, position and yaw errors, and runtime.

Run ``python -m bt_arrange.perception.evaluate`` (``--help`` for the options). Each trial
renders one cube at a random pose over the visible table (any yaw, 45..100 % brightness),
detects it, and compares with the ground truth; the numbers in docs/perception.md come from
here.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, replace

import numpy as np

from bt_arrange.geometry import fold_yaw
from bt_arrange.perception.corners import CornerRefinement
from bt_arrange.perception.detection import DetectorConfig, PartDetector
from bt_arrange.perception.pose import PoseModel
from bt_arrange.perception.synthetic import (
    SyntheticCube,
    project_points,
    random_cubes,
    render_frame,
    sim_intrinsics,
    top_down_camera_pose,
)
from bt_arrange.robot import CameraFrame


@dataclass(frozen=True)
class Trial:
    """One synthetic frame with a single cube, and its ground truth."""

    frame: CameraFrame
    cube: SyntheticCube


@dataclass(frozen=True)
class Summary:
    """Errors over a set of trials; ``found`` counts FOUND outcomes out of ``trials``."""

    trials: int
    found: int
    corner_mean_px: float
    corner_max_px: float
    xy_mean_mm: float
    xy_p95_mm: float
    xy_max_mm: float
    yaw_mean_deg: float
    yaw_max_deg: float
    ms_per_detection: float

    def row(self, label: str) -> str:
        """One line of the results table."""
        return (
            f"| {label} | {self.found}/{self.trials} "
            f"| {self.corner_mean_px:.3f} / {self.corner_max_px:.3f} | "
            f"{self.xy_mean_mm:.3f} / {self.xy_p95_mm:.3f} / {self.xy_max_mm:.3f} | "
            f"{self.yaw_mean_deg:.3f} / {self.yaw_max_deg:.3f} | {self.ms_per_detection:.1f} |"
        )


HEADER = (
    "| setting | found | corner error mean / max (px) | xy error mean / p95 / max (mm) "
    "| yaw error mean / max (deg) | ms per detection |\n|---|---|---|---|---|---|"
)


def make_trials(
    count: int,
    width_px: int = 1920,
    height_px: int = 1080,
    supersample: int = 8,
    noise_sigma: float = 0.0,
    blur_sigma_px: float = 0.0,
    seed: int = 0,
    yaw_rad: float | None = None,
    top_plate_m: float = 0.0,
) -> list[Trial]:
    """``count`` frames of one randomly placed cube each, seen by the simulated camera.

    ``yaw_rad`` fixes every cube's yaw (0: square to the image axes, the worst case for an
    aliased render); by default the yaw is random.
    """
    rng = np.random.default_rng(seed)
    intrinsics = sim_intrinsics(width_px, height_px)
    camera = top_down_camera_pose()
    cubes = random_cubes(rng, count, intrinsics, camera)
    if yaw_rad is not None:
        cubes = [replace(cube, yaw_rad=yaw_rad) for cube in cubes]
    cubes = [replace(cube, top_plate_m=top_plate_m) for cube in cubes]
    return [
        Trial(
            render_frame(
                [cube],
                intrinsics,
                camera,
                supersample=supersample,
                noise_sigma=noise_sigma,
                blur_sigma_px=blur_sigma_px,
                seed=seed + i,
            ),
            cube,
        )
        for i, cube in enumerate(cubes)
    ]


def _corner_error_px(found: np.ndarray, truth: np.ndarray) -> float:
    """Largest distance from a found corner to its nearest true corner."""
    distances = np.linalg.norm(found[:, None, :] - truth[None, :, :], axis=2)
    return float(distances.min(axis=1).max())


def evaluate(trials: list[Trial], detector: PartDetector) -> Summary:
    """Detect every trial's cube and summarise the errors of the FOUND ones."""
    corner_px, xy_mm, yaw_deg, seconds = [], [], [], []
    for trial in trials:
        start = time.perf_counter()
        detection = detector.detect(trial.frame, trial.cube.colour)
        seconds.append(time.perf_counter() - start)
        if detection.pose_world is None or detection.corners_px is None:
            continue
        truth_px = project_points(trial.frame.intrinsics, trial.frame.camera_pose_world, trial.cube.top_corners_world())
        corner_px.append(_corner_error_px(detection.corners_px, truth_px))
        pose = detection.pose_world
        xy_mm.append(1000.0 * math.hypot(pose.x_m - trial.cube.x_m, pose.y_m - trial.cube.y_m))
        yaw_deg.append(abs(math.degrees(fold_yaw(pose.yaw_rad - trial.cube.yaw_rad))))
    if not xy_mm:
        nan = float("nan")
        return Summary(len(trials), 0, nan, nan, nan, nan, nan, nan, nan, 1000.0 * float(np.median(seconds)))
    return Summary(
        trials=len(trials),
        found=len(xy_mm),
        corner_mean_px=float(np.mean(corner_px)),
        corner_max_px=float(np.max(corner_px)),
        xy_mean_mm=float(np.mean(xy_mm)),
        xy_p95_mm=float(np.percentile(xy_mm, 95)),
        xy_max_mm=float(np.max(xy_mm)),
        yaw_mean_deg=float(np.mean(yaw_deg)),
        yaw_max_deg=float(np.max(yaw_deg)),
        ms_per_detection=1000.0 * float(np.median(seconds)),
    )


def runtime_ms(repeats: int = 20) -> dict[str, float]:
    """Median wall time of ``detect`` and ``detect_all`` on a 1920x1080 frame with four cubes."""
    cubes = [
        SyntheticCube("red", 0.40, 0.25, 0.1, 0.9),
        SyntheticCube("green", 0.62, 0.20, -0.3, 0.5),
        SyntheticCube("blue", 0.38, -0.22, 0.7, 0.7),
        SyntheticCube("yellow", 0.60, -0.30, 0.0, 0.45),
    ]
    frame = render_frame(cubes, sim_intrinsics(), top_down_camera_pose())
    detector = PartDetector()
    calls = {
        "detect (one colour)": lambda: detector.detect(frame, "red"),
        "detect_all (four cubes)": lambda: detector.detect_all(frame),
    }
    result = {}
    for label, call in calls.items():
        call()  # warm up
        seconds = []
        for _ in range(repeats):
            start = time.perf_counter()
            call()
            seconds.append(time.perf_counter() - start)
        result[label] = 1000.0 * float(np.median(seconds))
    return result


def main(argv: list[str] | None = None) -> None:
    """Print Markdown tables of the detector's errors on synthetic frames, and its runtime."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=100, help="trials per row, 1 or more (default 100)")
    parser.add_argument("--seed", type=int, default=0, help="seed, 0 or more (default 0)")
    args = parser.parse_args(argv)
    n, seed = args.trials, args.seed
    if n < 1:
        parser.error(f"--trials {n}: at least 1")
    if seed < 0:
        parser.error(f"--seed {seed}: 0 or more")
    renders: dict[str, dict[str, float | None]] = {
        "1920x1080 anti-aliased": {},
        "1920x1080 anti-aliased, yaw 0": {"yaw_rad": 0.0},
        "1920x1080 aliased (TinyRenderer-like)": {"supersample": 1},
        "1920x1080 aliased, yaw 0": {"supersample": 1, "yaw_rad": 0.0},
        "1920x1080 noise 4, blur 0.8 px": {"noise_sigma": 4.0, "blur_sigma_px": 0.8},
        "1920x1080 anti-aliased, 0.5 mm coloured top plate": {"top_plate_m": 0.0005},
        "1280x720 anti-aliased": {"width_px": 1280, "height_px": 720},
        "1280x720 aliased": {"width_px": 1280, "height_px": 720, "supersample": 1},
    }
    comparisons: dict[str, dict[str, float | None]] = {"anti-aliased": {}, "aliased": {"supersample": 1}}
    rows_total = len(renders) + len(comparisons) * len(PoseModel) * len(CornerRefinement)
    rows_done = 0

    def progress(label: str) -> None:
        # A sign of life on stderr before each row: a row takes several seconds at 100 trials.
        nonlocal rows_done
        rows_done += 1
        print(f"evaluate: row {rows_done} of {rows_total}, {n} trials: {label}", file=sys.stderr, flush=True)

    print(f"Default detector (edge_lines, resting), {n} trials per row, seed {seed}\n", flush=True)
    print(HEADER, flush=True)
    for label, render in renders.items():
        progress(label)
        trials = make_trials(n, seed=seed, **render)  # type: ignore[arg-type]
        print(evaluate(trials, PartDetector()).row(label), flush=True)

    print(f"\nMethods compared, 1920x1080, {n} trials per row, seed {seed}\n")
    print(HEADER)
    for label, render in comparisons.items():
        trials = make_trials(n, seed=seed, **render)  # type: ignore[arg-type]
        for pose_model in PoseModel:
            for method in CornerRefinement:
                config = DetectorConfig(corner_refinement=method, pose_model=pose_model)
                row = f"{label}; {method.value}, {pose_model.value}"
                if method is not CornerRefinement.EDGE_LINES:
                    # Coarser corners fail the default quality gates: relax them, to compare
                    # the accuracy of every detection rather than count rejections.
                    config = replace(config, max_reprojection_error_px=5.0, max_edge_error_fraction=0.1)
                    row += " (relaxed gates)"
                progress(row)
                print(evaluate(trials, PartDetector(config=config)).row(row), flush=True)

    print("\nRuntime, 1920x1080, median of 20 calls\n", flush=True)
    print("evaluate: timing detection and rendering, 20 calls each", file=sys.stderr, flush=True)
    for label, ms in runtime_ms().items():
        print(f"- {label}: {ms:.1f} ms")


if __name__ == "__main__":
    main()
