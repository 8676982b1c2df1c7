"""The calibration's behaviours: move the board to a pose, capture it, solve from what was seen.

Blackboard keys (the calibration's own namespace):

| key | type | written by | read by |
|---|---|---|---|
| ``/calibration/views`` | ``list[BoardView]``: corners, the controller's TCP pose | CaptureBoard | SolveCalibration |
| ``/calibration/sheet`` | ``BoardObservation``: the table sheet's corners | CaptureSheet | SolveCalibration |
| ``/calibration/result`` | ``CameraCalibration`` | SolveCalibration | the command line |
"""

from __future__ import annotations

import datetime
from typing import Any

from bt_arrange.behaviours.base import InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.context import Context
from bt_arrange.calibration.board import TABLE_SHEET_THICKNESS_M, BoardObservation, CharucoBoard
from bt_arrange.calibration.file import CameraCalibration
from bt_arrange.calibration.solve import (
    BoardView,
    check_view_count,
    solve_eye_to_hand,
    solve_intrinsics,
    solve_on_table_plane,
)
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion import Motion
from bt_arrange.ports import Port

VIEWS = "/calibration/views"
SHEET = "/calibration/sheet"
RESULT = "/calibration/result"

#: Stage names (the running behaviour's feedback).
MOVE_BOARD = "move the board"
CAPTURE_BOARD = "capture the board"
CAPTURE_SHEET = "capture the table sheet"
SOLVE = "solve intrinsics and camera to base"


class MoveBoard(StagedBehaviour):
    """Move the arm so that the TCP reaches ``tcp_pose`` (the board, bolted to the flange, with it).

    An unreachable pose is a FAILURE whose feedback says why (the procedure skips it).
    """

    node_description = "arm -> board pose"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """None: the pose is configuration."""
        return ()

    def __init__(self, name: str, tcp_pose: Pose) -> None:
        super().__init__(name)
        self.tcp_pose = tcp_pose

    def stages(self, context: Context) -> list[Stage]:
        """One joint motion to the IK solution of the pose."""

        def plan(context: Context, q: FloatArray) -> Motion:
            return context.planner.move_to_pose(q, self.tcp_pose)

        return [MoveStage(MOVE_BOARD, plan)]

    def success_message(self) -> str:
        """Feedback once there."""
        x, y, z = self.tcp_pose.position_m
        return f"TCP at ({x:.3f}, {y:.3f}, {z:.3f}) m"


class CaptureBoard(StagedBehaviour):
    """Take a full frame, find the board's ChArUco corners and append the view to ``/calibration/views``.

    The view pairs the corners with the TCP pose the arm's controller reports for the measured
    joints (its own kinematics, as a real controller's ``getActualTCPPose``), never the simulator's.
    A board not seen (fewer than ``board.MIN_CORNERS`` corners) is a FAILURE (the procedure skips it).
    """

    node_description = "camera -> /calibration/views"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """None: the board is configuration."""
        return ()

    def __init__(self, name: str, board: CharucoBoard, working_plane: bool = False) -> None:
        super().__init__(name)
        self.board = board
        self.working_plane = working_plane
        self.corners = 0
        self.reads(VIEWS)
        self.writes(VIEWS)

    @property
    def facts(self) -> dict[str, Any]:
        """How many corners the last capture found."""
        return {"corners": self.corners}

    def stages(self, context: Context) -> list[Stage]:
        """Capture and detect, in one tick."""
        return [InstantStage(CAPTURE_BOARD, self._capture)]

    def _capture(self, context: Context) -> str | None:
        frame = context.robot.camera.capture()
        observation = self.board.detect(frame.rgb)
        self.corners = 0 if observation is None else observation.count
        if observation is None:
            return "board not seen (fewer than the corners a view needs)"
        q = context.robot.arm.joint_positions()
        views = list(self.blackboard.get(VIEWS)) if self.blackboard.exists(VIEWS) else []
        views.append(BoardView(observation, context.planner.kinematics.forward(q), self.working_plane))
        self.write(VIEWS, views)
        return None

    def success_message(self) -> str:
        """Feedback once captured."""
        return f"{self.corners} of {self.board.corner_count} corners"


class CaptureSheet(StagedBehaviour):
    """Take a full frame and find the table sheet (a board lying on the table); write ``/calibration/sheet``.

    The sheet not seen is a FAILURE (the procedure goes on; the solve then does without the table plane).
    """

    node_description = "camera -> /calibration/sheet"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """None: the sheet is configuration."""
        return ()

    def __init__(self, name: str, sheet: CharucoBoard) -> None:
        super().__init__(name)
        self.sheet = sheet
        self.corners = 0
        self.writes(SHEET)

    @property
    def facts(self) -> dict[str, Any]:
        """How many corners of the sheet the capture found."""
        return {"corners": self.corners}

    def stages(self, context: Context) -> list[Stage]:
        """Capture and detect, in one tick."""
        return [InstantStage(CAPTURE_SHEET, self._capture)]

    def _capture(self, context: Context) -> str | None:
        observation = self.sheet.detect(context.robot.camera.capture().rgb)
        self.corners = 0 if observation is None else observation.count
        if observation is None:
            return "table sheet not seen (fewer than the corners a view needs)"
        self.write(SHEET, observation)
        return None

    def success_message(self) -> str:
        """Feedback once captured."""
        return f"{self.corners} of {self.sheet.corner_count} corners of the table sheet"


class SolveCalibration(StagedBehaviour):
    """Solve the intrinsics, the distortion and camera to base from the views; write ``/calibration/result``.

    Too few views is a FAILURE of one line (``solve.check_view_count``). With the table sheet seen
    and at least 3 working-plane views, camera to base is referenced to the table plane
    (``solve.solve_on_table_plane``, the sheet's face at ``sheet_face_z_m`` in the base frame);
    otherwise it is the plain eye-to-hand solve of every view, and the feedback says so.
    """

    node_description = "/calibration/views -> /calibration/result"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """None."""
        return ()

    def __init__(
        self,
        name: str,
        poses: int,
        cell: str = "",
        board: CharucoBoard | None = None,
        sheet_face_z_m: float = TABLE_SHEET_THICKNESS_M,
    ) -> None:
        super().__init__(name)
        self.poses = poses
        self.cell = cell
        self.board = board or CharucoBoard()
        self.sheet_face_z_m = sheet_face_z_m
        self.result: CameraCalibration | None = None
        #: Whether camera to base was referenced to the table plane (the sheet seen, enough working-plane views).
        self.on_table_plane = False
        self.reads(VIEWS, SHEET)
        self.writes(RESULT)

    def stages(self, context: Context) -> list[Stage]:
        """The solve, in one tick."""
        return [InstantStage(SOLVE, self._solve)]

    def _solve(self, context: Context) -> str | None:
        views: list[BoardView] = list(self.blackboard.get(VIEWS)) if self.blackboard.exists(VIEWS) else []
        try:
            check_view_count(len(views), skipped=self.poses - len(views))
            sheet: BoardObservation | None = self.blackboard.get(SHEET) if self.blackboard.exists(SHEET) else None
            nominal = context.robot.camera.intrinsics
            # The sheet is one more view of a flat board for the lens (the largest, where the parts lie).
            observations = [v.observation for v in views] + ([sheet] if sheet is not None else [])
            intrinsics = solve_intrinsics(observations, nominal.width_px, nominal.height_px)
            hand_eye = solve_eye_to_hand(views, intrinsics.intrinsics)
            working = [v for v in views if v.working_plane]
            self.on_table_plane = sheet is not None and len(working) >= 3
            if sheet is not None and self.on_table_plane:
                hand_eye = solve_on_table_plane(working, intrinsics.intrinsics, sheet, hand_eye, self.sheet_face_z_m)
        except BtArrangeError as error:
            return str(error)
        b = self.board
        self.result = CameraCalibration(
            intrinsics=intrinsics.intrinsics,
            camera_to_base=hand_eye.camera_to_base,
            reprojection_error_px=intrinsics.reprojection_error_px,
            views=len(views),
            cell=self.cell,
            date=datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat(),
            skipped_views=self.poses - len(views),
            hand_eye_residual_mm=hand_eye.residual_mm,
            board=f"ChArUco {b.squares_x}x{b.squares_y}, {b.square_m * 1000:g} mm squares, "
            f"{b.marker_m * 1000:g} mm markers, {b.dictionary}",
        )
        self.write(RESULT, self.result)
        return None

    def success_message(self) -> str:
        """Feedback once solved."""
        if self.result is None:
            return "solved"
        reference = "on the table plane" if self.on_table_plane else "without the table plane (sheet not seen)"
        return (
            f"{self.result.views} views, reprojection error {self.result.reprojection_error_px:.3f} px, "
            f"hand-eye residual {self.result.hand_eye_residual_mm or 0.0:.3f} mm, camera to base {reference}"
        )
