"""The calibration's error budget: what each source costs on the table, measured by swapping in the truth.

    python benchmarks/calibration_budget.py --cell real --views 28 [--procedure lens|table] [--json]

Runs the calibration procedure once in the cell and keeps, beside each view the procedure used
(the corners and the controller's TCP pose), the simulator's true TCP pose at that moment
(evaluation only: the procedure never sees it). Then re-solves the same views with one input
replaced by the truth at a time: the intrinsics and lens, the TCP poses, their positions only,
their orientations only. Each answer is judged by its camera-to-base error against the true
camera (mm, mrad) and by its error on the table: points on a cube's top (5 cm) over the usable
area, seen by the true camera and measured through the calibrated one (planar mm, mean and max;
within a few hundredths of a millimetre of what ``benchmarks/calibration.py``'s detector gives).

``--procedure lens`` runs the lens views alone (the procedure before the table sheet, solved
eye-to-hand); ``table`` (the default) the procedure as it is: the sheet, the lens and the
working-plane views, solved on the table plane. docs/calibration.md has the figures.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np

from bt_arrange.calibration import BoardView, CharucoBoard, board_poses, solve_eye_to_hand, solve_intrinsics
from bt_arrange.calibration.behaviours import SHEET, VIEWS
from bt_arrange.calibration.board import TABLE_SHEET, TABLE_SHEET_THICKNESS_M
from bt_arrange.calibration.procedure import working_plane_poses
from bt_arrange.calibration.solve import solve_on_table_plane
from bt_arrange.geometry import Pose
from bt_arrange.robot import CameraIntrinsics
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.pybullet.calibration import SimCalibrationRun
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.runs import SimWorld
from bt_arrange_sim.realcell import WORKSPACE_X_M, WORKSPACE_Y_M, parse_cell

#: The height of a cube's top face: where the detector measures.
CUBE_TOP_M = 0.05


def table_error_mm(
    estimate: CameraIntrinsics, camera: Pose, true: CameraIntrinsics, true_camera: Pose
) -> tuple[float, float]:
    """Mean and max planar error (mm) of cube-top points over the usable area, through the calibrated camera."""
    xs = np.linspace(WORKSPACE_X_M[0] + 0.02, WORKSPACE_X_M[1] - 0.02, 9)
    ys = np.linspace(WORKSPACE_Y_M[0] + 0.02, WORKSPACE_Y_M[1] - 0.02, 9)
    points = np.array([[x, y, CUBE_TOP_M] for x in xs for y in ys])
    seen = true_camera.inverse()
    pixels, _ = cv2.projectPoints(points, cv2.Rodrigues(seen.rotation)[0], seen.position_m, true.matrix,
                                  np.asarray(true.distortion))  # fmt: skip
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    rays = cv2.undistortPoints(pixels, estimate.matrix, np.asarray(estimate.distortion), criteria=criteria)
    directions = np.c_[rays.reshape(-1, 2), np.ones(len(points))] @ camera.rotation.T
    hits = camera.position_m + directions * ((CUBE_TOP_M - camera.position_m[2]) / directions[:, 2])[:, None]
    errors = np.linalg.norm((hits - points)[:, :2], axis=1) * 1000
    return float(errors.mean()), float(errors.max())


def pose_error(estimate: Pose, truth: Pose) -> tuple[float, float]:
    """Position (mm) and rotation (mrad) of ``estimate`` off ``truth``."""
    relative = truth.inverse() @ estimate
    angle = math.acos(max(-1.0, min(1.0, (float(np.trace(relative.rotation)) - 1) / 2)))
    return float(np.linalg.norm(relative.position_m) * 1000), angle * 1000


def record_views(cell_name: str, views: int, procedure: str) -> dict[str, Any]:
    """Run the procedure; return its views, the true TCP pose at each, the sheet's view and the true camera."""
    errors = parse_cell(cell_name)
    board = CharucoBoard()
    config = CellConfig(errors=errors.with_run_seed(0)) if errors.enabled else CellConfig()
    config = dataclasses.replace(config, board=board)
    view = config.camera.view()
    if procedure == "lens":
        lens, plane, sheet = board_poses(view, board, config.board_mount, count=views), [], None
    else:
        lens = board_poses(view, board, config.board_mount, count=views - views // 2)
        plane = working_plane_poses(view, board, config.board_mount, count=views // 2)
        sheet = TABLE_SHEET
    run = SimCalibrationRun(lambda: SimWorld(WorkCell(config)), lens, board=board, plane_poses=plane, sheet=sheet)
    truths: list[Pose] = []

    def keep_truth(root: Any) -> None:
        # A capture just appended a view: the arm is still at rest where it was seen.
        blackboard = run.root.children[-1].blackboard
        count = len(blackboard.get(VIEWS)) if blackboard.exists(VIEWS) else 0
        if count > len(truths):
            cell = run.world.cell  # type: ignore[attr-defined]
            state = cell.client.getLinkState(cell.robot_id, cell.tcp_link_index, computeForwardKinematics=True)
            rotation = np.array(cell.client.getMatrixFromQuaternion(state[5])).reshape(3, 3)
            truths.append(Pose.from_rotation(state[4], rotation))

    run.tick_hooks.append(keep_truth)
    with run:
        run.run()
        true_k, true_camera = run.true_camera()
        blackboard = run.root.children[-1].blackboard
        seen = list(blackboard.get(VIEWS)) if blackboard.exists(VIEWS) else []
        sheet_view = blackboard.get(SHEET) if blackboard.exists(SHEET) else None
    return {"views": seen, "truth": truths, "sheet": sheet_view, "true_k": true_k, "true_camera": true_camera}


def budget(recorded: dict[str, Any]) -> list[dict[str, Any]]:
    """Each re-solve's camera-to-base and table errors."""
    views: list[BoardView] = recorded["views"]
    truths: list[Pose] = recorded["truth"]
    sheet, true_k, true_camera = recorded["sheet"], recorded["true_k"], recorded["true_camera"]
    observations = [v.observation for v in views] + ([sheet] if sheet is not None else [])
    measured_k = solve_intrinsics(observations, true_k.width_px, true_k.height_px).intrinsics

    def swapped(position: bool, orientation: bool) -> list[BoardView]:
        return [
            dataclasses.replace(
                v,
                tcp_pose=Pose.from_rotation(
                    t.position_m if position else v.tcp_pose.position_m,
                    t.rotation if orientation else v.tcp_pose.rotation,
                ),
            )
            for v, t in zip(views, truths, strict=True)
        ]

    def solve(given: list[BoardView], k: CameraIntrinsics) -> Pose:
        hand_eye = solve_eye_to_hand(given, k)
        working = [v for v in given if v.working_plane]
        if sheet is not None and len(working) >= 3:
            hand_eye = solve_on_table_plane(working, k, sheet, hand_eye, TABLE_SHEET_THICKNESS_M)
        return hand_eye.camera_to_base

    cases: list[tuple[str, Callable[[], tuple[CameraIntrinsics, Pose]]]] = [
        ("everything as measured (the procedure)", lambda: (measured_k, solve(views, measured_k))),
        ("the true intrinsics and lens", lambda: (true_k, solve(views, true_k))),
        ("the true TCP poses", lambda: (measured_k, solve(swapped(True, True), measured_k))),
        (
            "the true TCP positions, the controller's orientations",
            lambda: (measured_k, solve(swapped(True, False), measured_k)),
        ),
        (
            "the controller's positions, the true orientations",
            lambda: (measured_k, solve(swapped(False, True), measured_k)),
        ),
        ("the true TCP poses and the true intrinsics", lambda: (true_k, solve(swapped(True, True), true_k))),
    ]
    rows = []
    for name, case in cases:
        k, camera = case()
        position_mm, rotation_mrad = pose_error(camera, true_camera)
        mean_mm, max_mm = table_error_mm(k, camera, true_k, true_camera)
        rows.append({
            "given": name,
            "camera_to_base_error_mm": round(position_mm, 3),
            "camera_to_base_error_mrad": round(rotation_mrad, 3),
            "table_mean_mm": round(mean_mm, 3),
            "table_max_mm": round(max_mm, 3),
        })  # fmt: skip
    tcp_errors = [
        np.linalg.norm(t.position_m - v.tcp_pose.position_m) * 1000 for v, t in zip(views, truths, strict=True)
    ]
    rows.append({"given": "the controller's TCP position error at the views (mm)",
                 "min": round(float(np.min(tcp_errors)), 3), "max": round(float(np.max(tcp_errors)), 3)})  # fmt: skip
    return rows


def main(argv: list[str] | None = None) -> int:
    """Run the procedure once and print the budget."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cell", default="real")
    parser.add_argument("--views", type=int, default=28)
    parser.add_argument("--procedure", choices=("lens", "table"), default="table")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    recorded = record_views(args.cell, args.views, args.procedure)
    if len(recorded["views"]) < 6:
        print(f"too few views: {len(recorded['views'])}", file=sys.stderr)
        return 1
    rows = budget(recorded)
    result = {"cell": args.cell, "procedure": args.procedure, "views": len(recorded["views"]), "rows": rows}
    print(json.dumps(result) if args.json else json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
