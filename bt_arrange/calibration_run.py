"""A calibration run: the procedure's tree in a session, like any other run, and what it found.

``CalibrationRun`` wraps a ``bt_arrange.session.Session`` of ``calibration_tree`` (so the run is
ticked, logged to ``transitions.jsonl``, recorded and shown live as any run is) and hands back a
``CalibrationOutcome``: the solve's ``CameraCalibration``, or the one line saying why there is none.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange.calibration.behaviours import CaptureBoard, MoveBoard, SolveCalibration
from bt_arrange.calibration.board import CharucoBoard
from bt_arrange.calibration.file import CameraCalibration
from bt_arrange.calibration.procedure import calibration_tree
from bt_arrange.geometry import Pose
from bt_arrange.motion.safety import MotionSafety
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.session import Session, SessionReport, World


@dataclass
class CalibrationOutcome:
    """What a calibration run ended with."""

    calibration: CameraCalibration | None
    #: Why there is no calibration ("" when there is one).
    reason: str
    poses: int
    #: Poses the arm could not reach, and poses where the board was not seen.
    unreachable: int
    not_seen: int
    report: SessionReport


class CalibrationRun:
    """The calibration tree on a world, as a context manager: ``with ... as run: outcome = run.run()``."""

    def __init__(
        self,
        open_world: Callable[[], World],
        poses: list[Pose],
        *,
        view: CameraView | None = None,
        board: CharucoBoard | None = None,
        cell: str = "",
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        plane_poses: list[Pose] | None = None,
        sheet: CharucoBoard | None = None,
        motion_safety: MotionSafety | None = None,
    ) -> None:
        self.board = board or CharucoBoard()
        self.sheet = sheet
        plane_poses = plane_poses or []
        self.root = calibration_tree(poses, self.board, cell=cell, plane_poses=plane_poses, sheet=sheet)
        self.poses = len(poses) + len(plane_poses)
        self.session = Session(
            self.root,
            [],
            open_world,
            view=view,
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title="calibrate",
            motion_safety=motion_safety,
        )
        self.tick_hooks: list[Callable[[py_trees.behaviour.Behaviour], Any]] = self.session.tick_hooks

    @property
    def world(self) -> World:
        """The world the calibration runs in."""
        return self.session.world

    def elapsed_s(self) -> float:
        """World time since the tree started."""
        return self.session.elapsed_s()

    def run(self) -> CalibrationOutcome:
        """Tick the procedure to the end."""
        report = self.session.run()
        nodes = list(self.root.iterate())
        solve = next(node for node in nodes if isinstance(node, SolveCalibration))
        unreachable = sum(isinstance(n, MoveBoard) and n.status == py_trees.common.Status.FAILURE for n in nodes)
        not_seen = sum(isinstance(n, CaptureBoard) and n.status == py_trees.common.Status.FAILURE for n in nodes)
        reason = ""
        if solve.result is None:
            reason = solve.feedback_message or ("the run stopped at the time limit" if report.timed_out else "")
        return CalibrationOutcome(solve.result, reason, self.poses, unreachable, not_seen, report)

    def close(self) -> None:
        """Close the world."""
        self.session.close()

    def __enter__(self) -> CalibrationRun:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
