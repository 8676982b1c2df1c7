"""What the top camera sees, as data: its intrinsics and its pose, and which parts of the table lie in its image.

A backend hands a ``CameraView`` to the plan check (the simulated cell builds one from its camera
configuration without starting a world; a real cell from its calibration).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_arrange.geometry import Pose
from bt_arrange.objects import ObjectType
from bt_arrange.perception.pose import pixel_on_plane, project_world
from bt_arrange.robot import CameraIntrinsics
from bt_arrange.shapes import footprint_m, grown

#: How far beyond a part's top face (each side, in metres on the table) the camera must still see:
#: room for a placing error and for the detector's crop around the face.
VIEW_MARGIN_M = 0.01


@dataclass(frozen=True)
class CameraView:
    """What the top camera sees: its intrinsics and its pose ``T_W_C`` (OpenCV optical frame).

    ``margin_m`` (each side of a part's top face, metres) is what ``check_plan`` demands beyond
    the face.
    """

    intrinsics: CameraIntrinsics
    camera_pose_world: Pose
    margin_m: float = VIEW_MARGIN_M

    def sees_outline(self, corners_m: np.ndarray, z_m: float) -> bool:
        """True when a level polygon (N x 2 corners, metres) at height ``z_m`` lies inside the image."""
        corners = np.column_stack([corners_m, np.full(len(corners_m), z_m)])
        depth = (corners - self.camera_pose_world.position_m) @ self.camera_pose_world.rotation
        if np.any(depth[:, 2] <= 0):
            return False
        pixels = project_world(self.intrinsics, self.camera_pose_world, corners)
        width, height = self.intrinsics.width_px, self.intrinsics.height_px
        return bool(np.all(pixels >= 0) and np.all(pixels[:, 0] <= width - 1) and np.all(pixels[:, 1] <= height - 1))

    def sees_face(self, x_m: float, y_m: float, yaw_rad: float, edge_m: float) -> bool:
        """True when the top face of a cube of ``edge_m`` at (x, y, yaw), grown by ``margin_m``, is in the image."""
        return self.sees_part(x_m, y_m, yaw_rad, ObjectType("cube", (edge_m, edge_m, edge_m)))

    def sees_part(self, x_m: float, y_m: float, yaw_rad: float, object_type: ObjectType, z_m: float = 0.0) -> bool:
        """True when the top face of a part at (x, y, yaw), grown by ``margin_m``, lies inside the image.

        ``z_m``: the part's bottom face above the table (a raised part's top face is nearer the camera).
        """
        shape = object_type.shape
        corners = footprint_m(grown(shape, self.margin_m), x_m, y_m, yaw_rad)
        return self.sees_outline(corners, z_m + shape.height_m)

    def sees_disc(self, x_m: float, y_m: float, radius_m: float, z_m: float, samples: int = 32) -> bool:
        """True when a level disc (``samples`` points of its rim) at height ``z_m`` lies inside the image.

        A part whose top face fits this disc, grown by ``margin_m``, is seen at any yaw.
        """
        angles = np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False)
        rim = np.column_stack([x_m + radius_m * np.cos(angles), y_m + radius_m * np.sin(angles), np.full(samples, z_m)])
        depth = (rim - self.camera_pose_world.position_m) @ self.camera_pose_world.rotation
        if np.any(depth[:, 2] <= 0):
            return False
        pixels = project_world(self.intrinsics, self.camera_pose_world, rim)
        width, height = self.intrinsics.width_px, self.intrinsics.height_px
        return bool(np.all(pixels >= 0) and np.all(pixels[:, 0] <= width - 1) and np.all(pixels[:, 1] <= height - 1))

    def table_extent_m(self, top_z_m: float) -> tuple[float, float, float, float]:
        """What the image covers (x_min, x_max, y_min, y_max) on the plane of top faces at ``top_z_m``.

        An outer box of the image's corners on that plane, for messages; ``sees_part`` decides.
        """
        corners_px = np.array(
            [
                [0.0, 0.0],
                [self.intrinsics.width_px - 1.0, 0.0],
                [self.intrinsics.width_px - 1.0, self.intrinsics.height_px - 1.0],
                [0.0, self.intrinsics.height_px - 1.0],
            ]
        )
        points = [pixel_on_plane(self.intrinsics, self.camera_pose_world, p, top_z_m) for p in corners_px]
        xy = np.array([p[:2] for p in points if p is not None])
        if len(xy) == 0:
            return (math.nan, math.nan, math.nan, math.nan)
        return (float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max()))
