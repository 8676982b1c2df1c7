"""Camera calibration: a ChArUco board, the solve (intrinsics, distortion, camera to base), the file.

- ``board``: ``CharucoBoard`` (OpenCV's ``aruco``), its texture and ``detect()``;
- ``solve``: ``solve_intrinsics`` (``cv2.calibrateCamera``) and ``solve_eye_to_hand`` (AX = YB);
- ``file``: ``CameraCalibration``, ``read_calibration`` / ``write_calibration`` (``camera.toml``);
- ``camera``: ``CalibratedCamera``, the world's camera seen through a calibration;
- ``behaviours`` and ``procedure``: ``MoveBoard``, ``CaptureBoard``, ``SolveCalibration``, the
  board's poses and ``calibration_tree``.

See docs/calibration.md. Nothing here imports a simulator.
"""

from bt_arrange.calibration.behaviours import CaptureBoard, MoveBoard, SolveCalibration
from bt_arrange.calibration.board import BoardObservation, CharucoBoard
from bt_arrange.calibration.camera import CalibratedCamera
from bt_arrange.calibration.file import (
    CameraCalibration,
    calibration_from_mapping,
    matrix_rpy,
    read_calibration,
    rpy_matrix,
    write_calibration,
)
from bt_arrange.calibration.procedure import BoardMount, board_poses, calibration_tree
from bt_arrange.calibration.solve import (
    BoardView,
    HandEyeSolution,
    IntrinsicsSolution,
    linear_ax_yb,
    solve_eye_to_hand,
    solve_intrinsics,
)

__all__ = [
    "BoardMount",
    "BoardObservation",
    "BoardView",
    "CalibratedCamera",
    "CameraCalibration",
    "CaptureBoard",
    "CharucoBoard",
    "HandEyeSolution",
    "IntrinsicsSolution",
    "MoveBoard",
    "SolveCalibration",
    "board_poses",
    "calibration_from_mapping",
    "calibration_tree",
    "linear_ax_yb",
    "matrix_rpy",
    "read_calibration",
    "rpy_matrix",
    "solve_eye_to_hand",
    "solve_intrinsics",
    "write_calibration",
]
