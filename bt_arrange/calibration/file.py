"""The calibration file (``camera.toml``): what a calibration found, in millimetres and degrees.

The keys are a contract (``bt-arrange calibrate --out`` writes them, ``--calibration`` reads them)::

    cell = "real"                        # where it was made
    date = "2026-12-01T10:00:00+00:00"   # when
    width_px = 1920                      # the image it holds for
    height_px = 1080
    fx_px = 1371.0                       # pinhole, pixel-centre convention (OpenCV's)
    fy_px = 1371.0
    cx_px = 959.5
    cy_px = 539.5
    distortion = [k1, k2, p1, p2, k3]    # OpenCV's order
    reprojection_error_px = 0.12         # RMS over every corner of every view
    views = 18                           # views the solve used

    [camera_to_base]                     # T_B_C: the camera's optical frame in the robot base frame
    x_mm = 500.0
    y_mm = 0.0
    z_mm = 700.0
    roll_deg = 180.0                     # R = Rz(yaw) Ry(pitch) Rx(roll), as in a URDF's rpy
    pitch_deg = 0.0
    yaw_deg = -93.0

The optical frame is OpenCV's (x right, y down, z forward). The base frame is the one the arm's
controller reports its TCP in, which is the frame ``bt-arrange`` plans in (the world frame).

``read_calibration`` checks every field as the plan reader does: a ``PlanError`` of one line that
names the field and what it must be.
"""

from __future__ import annotations

import datetime
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_arrange import files
from bt_arrange.errors import PlanError, RecordError
from bt_arrange.filelimits import read_limited
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.robot import CameraIntrinsics

#: The number of distortion coefficients OpenCV accepts (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tx ty]]]]).
DISTORTION_LENGTHS = (4, 5, 8, 12, 14)
_TOP_KEYS = (
    "cell",
    "date",
    "width_px",
    "height_px",
    "fx_px",
    "fy_px",
    "cx_px",
    "cy_px",
    "distortion",
    "reprojection_error_px",
    "views",
    "camera_to_base",
)
#: Keys a file may carry beyond the contract, for the record (written by ``bt-arrange calibrate``).
_OPTIONAL_KEYS = ("skipped_views", "hand_eye_residual_mm", "board")
_POSE_KEYS = ("x_mm", "y_mm", "z_mm", "roll_deg", "pitch_deg", "yaw_deg")


def rpy_matrix(roll_rad: float, pitch_rad: float, yaw_rad: float) -> FloatArray:
    """``Rz(yaw) Ry(pitch) Rx(roll)``: the rotation of a URDF's ``rpy``."""
    cr, sr, cp, sp = math.cos(roll_rad), math.sin(roll_rad), math.cos(pitch_rad), math.sin(pitch_rad)
    cy, sy = math.cos(yaw_rad), math.sin(yaw_rad)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def matrix_rpy(rotation: FloatArray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) in radians of a rotation, ``rpy_matrix``'s inverse (pitch in [-pi/2, pi/2])."""
    m = np.asarray(rotation, dtype=float)
    pitch = math.asin(max(-1.0, min(1.0, -m[2, 0])))
    if abs(math.cos(pitch)) > 1e-9:
        return math.atan2(m[2, 1], m[2, 2]), pitch, math.atan2(m[1, 0], m[0, 0])
    return 0.0, pitch, math.atan2(-m[0, 1], m[1, 1])  # gimbal lock: everything in yaw


@dataclass(frozen=True)
class CameraCalibration:
    """A camera's calibration: intrinsics with distortion, the camera-to-base pose, and how good it is."""

    intrinsics: CameraIntrinsics
    #: ``T_B_C``: the optical frame (x right, y down, z forward) in the robot base (world) frame.
    camera_to_base: Pose
    reprojection_error_px: float
    views: int
    cell: str = ""
    date: str = ""
    #: Poses of the procedure that were not used: unreachable, or the board not seen.
    skipped_views: int = 0
    #: RMS distance (mm) between the board corners as the arm and the camera put them (the AX = YB residual).
    hand_eye_residual_mm: float | None = None
    board: str = ""

    def view(self) -> CameraView:
        """What this camera sees, for the plan check."""
        return CameraView(self.intrinsics, self.camera_to_base)

    def to_toml(self) -> str:
        """The file's text (``write_calibration`` writes it)."""
        k = self.intrinsics
        roll, pitch, yaw = (math.degrees(a) for a in matrix_rpy(self.camera_to_base.rotation))
        x, y, z = (float(v) * 1000 for v in self.camera_to_base.position_m)
        lines = [
            "# Camera calibration written by bt-arrange calibrate (docs/calibration.md).",
            "# Pinhole in pixels (pixel-centre convention), distortion in OpenCV's order (k1, k2, p1, p2, k3),",
            "# camera_to_base = the optical frame (x right, y down, z forward) in the robot base frame,",
            "# rotation Rz(yaw) Ry(pitch) Rx(roll).",
            f"cell = {_toml_string(self.cell)}",
            f"date = {_toml_string(self.date)}",
            f"width_px = {k.width_px}",
            f"height_px = {k.height_px}",
            f"fx_px = {k.fx_px:.6f}",
            f"fy_px = {k.fy_px:.6f}",
            f"cx_px = {k.cx_px:.6f}",
            f"cy_px = {k.cy_px:.6f}",
            "distortion = [" + ", ".join(f"{v:.9g}" for v in k.distortion) + "]",
            f"reprojection_error_px = {self.reprojection_error_px:.4f}",
            f"views = {self.views}",
            f"skipped_views = {self.skipped_views}",
        ]
        if self.hand_eye_residual_mm is not None:
            lines.append(f"hand_eye_residual_mm = {self.hand_eye_residual_mm:.4f}")
        if self.board:
            lines.append(f"board = {_toml_string(self.board)}")
        lines += [
            "",
            "[camera_to_base]",
            f"x_mm = {x:.4f}",
            f"y_mm = {y:.4f}",
            f"z_mm = {z:.4f}",
            f"roll_deg = {roll:.6f}",
            f"pitch_deg = {pitch:.6f}",
            f"yaw_deg = {yaw:.6f}",
        ]
        return "\n".join(lines) + "\n"


def _toml_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def write_calibration(calibration: CameraCalibration, path: Path | str) -> Path:
    """Write ``calibration`` to ``path`` whole or not at all (``bt_arrange.files.write_text``); the path.

    Through the project's atomic writer: a temporary name of this process's own beside it (two
    calibrations written at once do not collide), flushed to the disk, then renamed. A file that
    cannot be written (a full disk, a folder gone or read-only) is a ``RecordError`` naming it,
    with ``result`` the calibration (the command prints it, then exits 3); ``path`` is then the old
    file or absent, never cut short.
    """
    path = Path(path)
    try:
        files.write_text(path, calibration.to_toml())
    except OSError as error:
        fault = files.Faults()
        fault.add(path, error)
        raise RecordError(
            f"cannot write the calibration file {path}: {files.cause(error)}", faults=fault.faults, result=calibration
        ) from error
    return path


def check_image_size(calibration: CameraCalibration, width_px: int, height_px: int) -> None:
    """A one-line ``PlanError`` when ``calibration`` holds for another image size than the camera's."""
    k = calibration.intrinsics
    if (k.width_px, k.height_px) != (width_px, height_px):
        raise PlanError(
            f"the calibration is for {k.width_px}x{k.height_px} px images, the camera takes {width_px}x{height_px} px",
            field="width_px",
            value=(k.width_px, k.height_px),
            limit=(width_px, height_px),
        )


def read_calibration_option(
    path: Path | str, width_px: int | None = None, height_px: int | None = None
) -> CameraCalibration:
    """``--calibration``'s file: ``read_calibration``, for an image of ``width_px`` x ``height_px`` when given.

    Its one-line ``PlanError`` starts with the option and the path (``--calibration camera.toml: ...``).
    """
    try:
        calibration = read_calibration(path)
        if width_px is not None and height_px is not None:
            check_image_size(calibration, width_px, height_px)
    except PlanError as error:
        raise PlanError(f"--calibration {path}: {error}", field=error.field, value=error.value) from error
    return calibration


def _toml_module() -> Any:
    if sys.version_info >= (3, 11):
        import tomllib

        return tomllib
    import tomli  # the tomli backport on 3.10 (a dependency there)

    return tomli


def read_calibration(path: Path | str) -> CameraCalibration:
    """A calibration from its file; a one-line ``PlanError`` naming the field for any mistake.

    Read as every shared file is (``bt_arrange.filelimits.read_limited``): within ``MAX_FILE_BYTES``
    and UTF-8, or one line saying which.
    """
    path = Path(path)
    try:
        text = read_limited(path, "the calibration file", PlanError)
    except OSError as error:  # a missing file (read_limited words the other faults itself)
        raise PlanError(f"cannot read the calibration file {path}: {error.strerror or error}") from error
    try:
        data = _toml_module().loads(text)
    except Exception as error:  # tomllib.TOMLDecodeError; one line, whatever the parser says
        raise PlanError(f"calibration file {path} is not valid TOML: {error}") from error
    return calibration_from_mapping(data, where=f"calibration file {path}")


def calibration_from_mapping(data: Mapping[str, Any], where: str = "calibration") -> CameraCalibration:
    """A calibration from a mapping like the file's; a ``PlanError`` naming the field otherwise."""

    def fail(field: str, message: str) -> PlanError:
        return PlanError(f"{where}: {field} {message}", field=field, value=data.get(field))

    for key in data:
        if key not in _TOP_KEYS and key not in _OPTIONAL_KEYS:
            raise PlanError(
                f"{where}: unknown key {key!r}; the keys are {', '.join(_TOP_KEYS)}", field=key, value=data[key]
            )
    for key in _TOP_KEYS:
        if key not in data:
            raise fail(key, "is missing")

    def number(field: str, value: Any, *, positive: bool = False, minimum: float | None = None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise fail(field, f"= {value!r} must be a finite number")
        if positive and value <= 0:
            raise fail(field, f"= {value!r} must be positive")
        if minimum is not None and value < minimum:
            raise fail(field, f"= {value!r} must be at least {minimum:g}")
        return float(value)

    def whole(field: str, value: Any, minimum: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise fail(field, f"= {value!r} must be a whole number, {minimum} or more")
        return int(value)

    def string(field: str, value: Any) -> str:
        if isinstance(value, (datetime.datetime, datetime.date)):
            return value.isoformat()
        if not isinstance(value, str):
            raise fail(field, f"= {value!r} must be a string")
        return value

    width = whole("width_px", data["width_px"], 1)
    height = whole("height_px", data["height_px"], 1)
    fx = number("fx_px", data["fx_px"], positive=True)
    fy = number("fy_px", data["fy_px"], positive=True)
    cx = number("cx_px", data["cx_px"])
    cy = number("cy_px", data["cy_px"])
    if not -0.5 <= cx <= width - 0.5:
        raise fail("cx_px", f"= {cx:g} must lie inside the image (-0.5 to {width - 0.5:g} px)")
    if not -0.5 <= cy <= height - 0.5:
        raise fail("cy_px", f"= {cy:g} must lie inside the image (-0.5 to {height - 0.5:g} px)")
    distortion = data["distortion"]
    if not isinstance(distortion, list) or len(distortion) not in DISTORTION_LENGTHS:
        raise fail(
            "distortion",
            f"= {distortion!r} must be a list of {', '.join(map(str, DISTORTION_LENGTHS))} numbers (OpenCV's order)",
        )
    coefficients = tuple(number(f"distortion[{i}]", v) for i, v in enumerate(distortion))
    reprojection = number("reprojection_error_px", data["reprojection_error_px"], minimum=0.0)
    views = whole("views", data["views"], 1)
    skipped = whole("skipped_views", data.get("skipped_views", 0), 0)
    residual = data.get("hand_eye_residual_mm")
    residual_mm = None if residual is None else number("hand_eye_residual_mm", residual, minimum=0.0)
    pose_table = data["camera_to_base"]
    if not isinstance(pose_table, Mapping):
        raise fail("camera_to_base", f"must be a table ([camera_to_base] with {', '.join(_POSE_KEYS)})")
    for key in pose_table:
        if key not in _POSE_KEYS:
            raise PlanError(
                f"{where}: unknown key camera_to_base.{key}; [camera_to_base] takes {', '.join(_POSE_KEYS)}",
                field=f"camera_to_base.{key}",
            )
    values = {}
    for key in _POSE_KEYS:
        if key not in pose_table:
            raise PlanError(f"{where}: camera_to_base.{key} is missing", field=f"camera_to_base.{key}")
        values[key] = number(f"camera_to_base.{key}", pose_table[key])
    for key, limit in (("roll_deg", 180.0), ("pitch_deg", 90.0), ("yaw_deg", 180.0)):
        if abs(values[key]) > limit:
            raise PlanError(
                f"{where}: camera_to_base.{key} = {values[key]:g} must lie within -{limit:g} to {limit:g} degrees",
                field=f"camera_to_base.{key}",
            )
    rotation = rpy_matrix(*(math.radians(values[k]) for k in ("roll_deg", "pitch_deg", "yaw_deg")))
    position = np.array([values["x_mm"], values["y_mm"], values["z_mm"]]) / 1000
    return CameraCalibration(
        intrinsics=CameraIntrinsics(width, height, fx, fy, cx, cy, coefficients),
        camera_to_base=Pose.from_rotation(position, rotation),
        reprojection_error_px=reprojection,
        views=views,
        cell=string("cell", data["cell"]),
        date=string("date", data["date"]),
        skipped_views=skipped,
        hand_eye_residual_mm=residual_mm,
        board=string("board", data.get("board", "")),
    )
