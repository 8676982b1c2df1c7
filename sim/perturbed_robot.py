"""The real cell's robot as built: the nominal URDF perturbed by its link and joint errors.

The simulated world loads the perturbed URDF while the planner keeps the nominal one
(``bt_arrange_sim.realcell`` holds the error model); ``hand_eye_base_pose`` is the base pose a
hand-eye calibration of that robot would report.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bt_arrange.files import shared_temp_file
from bt_arrange_sim.realcell import WORKSPACE_X_M, WORKSPACE_Y_M, RealCellErrors

# -- the perturbed robot ------------------------------------------------------------------------


def _rpy_to_matrix(rpy: NDArray[np.float64]) -> NDArray[np.float64]:
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _matrix_to_rpy(m: NDArray[np.float64]) -> NDArray[np.float64]:
    pitch = math.asin(max(-1.0, min(1.0, -m[2, 0])))
    if abs(math.cos(pitch)) > 1e-9:
        roll = math.atan2(m[2, 1], m[2, 2])
        yaw = math.atan2(m[1, 0], m[0, 0])
    else:  # gimbal lock: put everything in yaw
        roll, yaw = 0.0, math.atan2(-m[0, 1], m[1, 1])
    return np.array([roll, pitch, yaw])


def _axis_rotation(axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def perturbed_urdf_text(
    nominal_text: str,
    arm_joints: tuple[str, ...],
    finger_joints: tuple[str, ...],
    link_errors_m: NDArray[np.float64],
    joint_zero_errors_rad: NDArray[np.float64],
    finger_offset_m: float,
) -> str:
    """The URDF with each arm joint's origin lengthened and its zero turned, fingers moved.

    Each arm joint's origin translation is lengthened and its zero turned, and the
    fingers moved together along the closing axis (both joint origins by ``finger_offset_m``).
    """
    root = ET.fromstring(nominal_text)
    joints = {j.get("name"): j for j in root.iter("joint")}
    for name, length_error, zero_error in zip(arm_joints, link_errors_m, joint_zero_errors_rad, strict=True):
        joint = joints[name]
        origin = joint.find("origin")
        assert origin is not None
        xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        rpy = np.array([float(v) for v in origin.get("rpy", "0 0 0").split()])
        norm = float(np.linalg.norm(xyz))
        if norm > 0:
            xyz = xyz + xyz / norm * length_error
        axis_element = joint.find("axis")
        axis = np.array([float(v) for v in (axis_element.get("xyz") if axis_element is not None else "1 0 0").split()])
        # A joint whose zero is off: the child frame is turned about the joint axis at q = 0.
        rotation = _rpy_to_matrix(rpy) @ _axis_rotation(axis, float(zero_error))
        origin.set("xyz", " ".join(f"{v:.9g}" for v in xyz))
        origin.set("rpy", " ".join(f"{v:.12g}" for v in _matrix_to_rpy(rotation)))
    for name in finger_joints:
        origin = joints[name].find("origin")
        assert origin is not None
        xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        xyz[0] += finger_offset_m  # both fingers' origins: the pads' centre moves along the closing axis (x)
        origin.set("xyz", " ".join(f"{v:.9g}" for v in xyz))
    return ET.tostring(root, encoding="unicode")


def write_perturbed_urdf(errors: RealCellErrors) -> Path | None:
    """A temporary file with the real cell's URDF, or None when the arm and fingers are nominal.

    The file lives in the system's temporary folder, named by the cell seed and the draws, and is
    written once per process and cell.
    """
    from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES, default_urdf_path

    link_errors, zero_errors = errors.arm_draw()
    finger_offset = errors.finger_offset_m()
    if not (errors.kinematics.enabled or errors.gripper.enabled) or (
        not link_errors.any() and not zero_errors.any() and finger_offset == 0.0
    ):
        return None
    text = perturbed_urdf_text(
        default_urdf_path().read_text(), ARM_JOINT_NAMES, FINGER_JOINT_NAMES, link_errors, zero_errors, finger_offset
    )
    # Meshes are none (primitive shapes), so the file may live anywhere.
    return shared_temp_file(f"bt_arrange_realcell_{errors.cell_seed}_", ".urdf", text)


def hand_eye_base_pose(urdf_path: Path) -> tuple[NDArray[np.float64], float]:
    """The base placement (translation m, yaw rad) that absorbs the perturbed arm's mean TCP error.

    Samples gripper-down poses over the workspace, solves them with the nominal model, runs the
    joint vectors through the perturbed model, and fits the rigid motion (x, y, z, yaw) that takes
    the true TCPs back onto the nominal ones: a real hand-eye calibration finds that transform.
    """
    from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, gripper_down_pose

    nominal, true = ArmKinematics(), ArmKinematics(urdf_path)
    wanted, reached = [], []
    q = np.asarray(DEFAULT_HOME_Q, dtype=float)
    for x in np.linspace(*WORKSPACE_X_M, 4):
        for y in np.linspace(*WORKSPACE_Y_M, 5):
            for z in (0.025, 0.10):
                target = gripper_down_pose(float(x), float(y), z)
                q = nominal.inverse(target, q)
                wanted.append(target.position_m)
                reached.append(true.forward(q).position_m)
    a, b = np.array(reached), np.array(wanted)
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    h = (a[:, :2] - ca[:2]).T @ (b[:, :2] - cb[:2])
    yaw = math.atan2(h[0, 1] - h[1, 0], h[0, 0] + h[1, 1])
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    translation = cb - rot @ ca
    return translation, yaw


def tcp_error_over_workspace_mm(errors: RealCellErrors, points: int = 5) -> NDArray[np.float64]:
    """The true TCP's planar error (mm) at gripper-down poses over the workspace, after the hand-eye fit.

    Runs in pure kinematics (no world): what the arm's calibration error does to a grasp or a push.
    """
    from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, gripper_down_pose

    path = write_perturbed_urdf(errors)
    if path is None:
        return np.zeros((points * points, 2))
    translation, yaw = hand_eye_base_pose(path) if errors.kinematics.hand_eye_absorbs_mean else (np.zeros(3), 0.0)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    nominal, true = ArmKinematics(), ArmKinematics(path)
    q = np.asarray(DEFAULT_HOME_Q, dtype=float)
    out = []
    for x in np.linspace(0.38, 0.62, points):
        for y in np.linspace(-0.25, 0.25, points):
            target = gripper_down_pose(float(x), float(y), 0.025)
            q = nominal.inverse(target, q)
            reached = rot @ true.forward(q).position_m + translation
            out.append((reached[:2] - target.position_m[:2]) * 1000)
    return np.array(out)
