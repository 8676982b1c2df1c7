"""The calibration board in the simulated cell: a textured plate bolted to the flange.

The board is a tool, not a part: a real cell bolts it to the flange with a bracket for the
calibration, so here it is a rigid link of the robot itself, ``calibration_board``, added to the
URDF the cell loads (a fixed joint to the ``tcp`` link at ``BoardMount``'s pose; visual only, so it
collides with nothing, and 0.3 kg of inertia). No constraint holds it, and parts are never
attached to anything: they move only through contact.

The plate is a mesh (a thin box written as an OBJ with texture coordinates) whose top face shows
the ChArUco pattern (``CharucoBoard.plate_image``), loaded with ``loadTexture`` and set with
``changeVisualShape(textureUniqueId=...)``; TinyRenderer draws it, and the board is found in the
rendered image by OpenCV's ``CharucoDetector`` like any camera image.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bt_arrange.calibration import BoardMount, CharucoBoard, matrix_rpy
from bt_arrange.calibration.board import TABLE_SHEET_THICKNESS_M
from bt_arrange.calibration_run import CalibrationRun
from bt_arrange.files import shared_temp_file
from bt_arrange.geometry import Pose, matrix_to_quaternion
from bt_arrange.robot import CameraIntrinsics

#: The link the board is on, and its joint.
BOARD_LINK = "calibration_board"
BOARD_JOINT = "tcp-calibration_board_fixed_joint"
#: The plate's thickness and mass (an aluminium composite plate; estimate).
PLATE_THICKNESS_M = 0.003
PLATE_MASS_KG = 0.3
#: Texture resolution: about the camera's at 30 cm (0.9 px per mm there), twice over.
TEXTURE_PX_PER_M = 4000.0


def _plate_obj(board: CharucoBoard) -> str:
    """A thin box in the board frame (pattern corner at the origin, face at z = 0, seen from -z) as OBJ.

    The face at z = 0 carries the whole texture; the other faces sample its white margin.
    """
    width, height = board.plate_size_m
    m = board.margin_m
    x0, y0, x1, y1, t = -m, -m, width - m, height - m, PLATE_THICKNESS_M
    vertices = [(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0), (x0, y0, t), (x1, y0, t), (x1, y1, t), (x0, y1, t)]
    # Texture v runs up the image: the pattern's first row (y = 0) is at the image's top (v = 1).
    uv = [(0, 1), (1, 1), (1, 0), (0, 0), (0.001, 0.999)]
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += [f"vt {u} {v}" for u, v in uv]
    lines += ["vn 0 0 -1", "vn 0 0 1", "vn 0 -1 0", "vn 1 0 0", "vn 0 1 0", "vn -1 0 0"]
    # The face (normal -z, counter-clockwise seen from -z), then the back and the sides (white).
    lines += ["f 1/1/1 3/3/1 2/2/1", "f 1/1/1 4/4/1 3/3/1"]
    for a, b, c, d, n in ((5, 6, 7, 8, 2), (1, 2, 6, 5, 3), (2, 3, 7, 6, 4), (3, 4, 8, 7, 5), (4, 1, 5, 8, 6)):
        lines += [f"f {a}/5/{n} {b}/5/{n} {c}/5/{n}", f"f {a}/5/{n} {c}/5/{n} {d}/5/{n}"]
    return "\n".join(lines) + "\n"


def board_files(board: CharucoBoard) -> tuple[Path, Path]:
    """The plate's mesh and texture, written once per process and board to the temporary folder."""
    import cv2

    digest = hashlib.sha1(repr(board).encode()).hexdigest()[:12]
    folder = Path(tempfile.gettempdir())
    mesh = folder / f"bt_arrange_board_{digest}.obj"
    texture = folder / f"bt_arrange_board_{digest}.png"
    for path, write in (
        (mesh, lambda p: p.write_text(_plate_obj(board))),
        (texture, lambda p: cv2.imwrite(str(p), board.plate_image(TEXTURE_PX_PER_M))),
    ):
        if not path.exists():
            tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
            write(tmp)
            tmp.replace(path)
    return mesh, texture


def urdf_with_board(urdf_text: str, board: CharucoBoard, mount: BoardMount) -> str:
    """The robot's URDF with the board as a link fixed to ``tcp`` at the mount's pose."""
    mesh, _ = board_files(board)
    root = ET.fromstring(urdf_text)
    T_T_P = mount.board_to_tool(board)
    roll, pitch, yaw = matrix_rpy(T_T_P.rotation)
    link = ET.SubElement(root, "link", name=BOARD_LINK)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=" ".join(f"{v:.6f}" for v in board.centre_m), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=f"{PLATE_MASS_KG}")
    ET.SubElement(inertial, "inertia", ixx="1e-3", ixy="0", ixz="0", iyy="1e-3", iyz="0", izz="2e-3")
    visual = ET.SubElement(link, "visual")
    ET.SubElement(visual, "origin", xyz="0 0 0", rpy="0 0 0")
    geometry = ET.SubElement(visual, "geometry")
    ET.SubElement(geometry, "mesh", filename=str(mesh), scale="1 1 1")
    joint = ET.SubElement(root, "joint", name=BOARD_JOINT, type="fixed")
    ET.SubElement(joint, "parent", link="tcp")
    ET.SubElement(joint, "child", link=BOARD_LINK)
    ET.SubElement(
        joint,
        "origin",
        xyz=" ".join(f"{v:.9f}" for v in T_T_P.position_m),
        rpy=f"{roll:.12f} {pitch:.12f} {yaw:.12f}",
    )
    return ET.tostring(root, encoding="unicode")


def write_urdf_with_board(urdf_path: Path, board: CharucoBoard, mount: BoardMount) -> Path:
    """A temporary URDF file: ``urdf_path``'s robot with the board on its flange."""
    return shared_temp_file(
        "bt_arrange_board_robot_", ".urdf", urdf_with_board(Path(urdf_path).read_text(), board, mount)
    )


def texture_board(client: object, robot_id: int, link_index: int, board: CharucoBoard) -> None:
    """Paint the board link with its pattern (``loadTexture``, ``changeVisualShape``)."""
    _, texture = board_files(board)
    texture_id = client.loadTexture(str(texture))  # type: ignore[attr-defined]
    client.changeVisualShape(  # type: ignore[attr-defined]
        robot_id, link_index, textureUniqueId=texture_id, rgbaColor=[1.0, 1.0, 1.0, 1.0]
    )


def board_pose_truth(cell: object) -> np.ndarray:
    """The board's true pose in the world (4x4; evaluation only)."""
    client, robot = cell.client, cell.robot_id  # type: ignore[attr-defined]
    index = cell._link_index[BOARD_LINK]  # type: ignore[attr-defined]
    state = client.getLinkState(robot, index, computeForwardKinematics=True)
    matrix = np.eye(4)
    matrix[:3, :3] = np.array(client.getMatrixFromQuaternion(state[5])).reshape(3, 3)
    matrix[:3, 3] = state[4]
    return matrix


#: Where the table sheet lies: its centre (x, y, m) and the turn of its long side from the world's x
#: axis (rad): across the working area, laid by hand a little askew. The procedure does not know it.
TABLE_SHEET_PLACE = (0.48, 0.01, 1.62)


def lay_table_sheet(cell: object, sheet: CharucoBoard, place: tuple[float, float, float] = TABLE_SHEET_PLACE) -> int:
    """Lay the table sheet on the table, face up (visual only: nothing touches it); returns its body id.

    The sheet is a tool of the procedure like the flange board: a plate with the pattern on its face,
    its back on the table top (``TABLE_SHEET_THICKNESS_M`` thick, so its face is that high).
    """
    client = cell.client  # type: ignore[attr-defined]
    mesh, texture = board_files(sheet)
    x, y, turn = place
    c, s = np.cos(turn), np.sin(turn)
    # The board frame's z axis points into the plate: face up, it points down.
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.diag([1.0, -1.0, -1.0])
    origin = np.array([x, y, TABLE_SHEET_THICKNESS_M]) - rotation @ sheet.centre_m
    visual = client.createVisualShape(client.GEOM_MESH, fileName=str(mesh), meshScale=[1, 1, 1])
    body = int(
        client.createMultiBody(
            0.0, -1, visual, basePosition=origin.tolist(), baseOrientation=matrix_to_quaternion(rotation).tolist()
        )
    )
    client.changeVisualShape(body, -1, textureUniqueId=client.loadTexture(str(texture)), rgbaColor=[1, 1, 1, 1])
    return body


class SimCalibrationRun(CalibrationRun):
    """A ``CalibrationRun`` in the pybullet cell, with the simulator's truth to judge it by (evaluation only).

    With a ``sheet``, the world it opens has the table sheet laid on the table (``lay_table_sheet``).
    """

    def __init__(self, open_world: Callable[[], Any], poses: list[Pose], **options: Any) -> None:
        sheet = options.get("sheet")

        def open_with_sheet() -> Any:
            world = open_world()
            if sheet is not None:
                lay_table_sheet(world.cell, sheet)
            return world

        super().__init__(open_with_sheet, poses, **options)

    def true_camera(self) -> tuple[CameraIntrinsics, Pose]:
        """The true camera's intrinsics (with its lens) and pose ``T_W_C``: what the calibration should find."""
        camera = self.world.cell.camera  # type: ignore[attr-defined]
        return camera.true_intrinsics, camera.true_pose_world
