"""The table's top filled in, not shaded pixel by pixel: the same pixels as TinyRenderer's, at a fraction of its time.

``TableTopFill.render`` is the simulated camera's fast path (``SimCamera._render``); it returns
None wherever the plain render must be made instead. ``tests/integration/test_camera_cell.py`` holds
it to the plain render's colour and z-buffer.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

#: Renders (width, height, projection, light) to TinyRenderer's RGBA and z-buffer: ``SimCamera._rgba``.
Rgba = Callable[[int, int, list[float], list[float]], tuple[np.ndarray, np.ndarray]]


def straight_down(view_matrix: list[float]) -> bool:
    """True when the camera's optical axis is the world's vertical (the table's top at one depth)."""
    view = np.asarray(view_matrix, dtype=float).reshape(4, 4, order="F")
    return abs(view[2, 0]) < 1e-12 and abs(view[2, 1]) < 1e-12


class TableTopFill:
    """The table top's colour and z-buffer value by view, light and table colour, and the frames filled with them."""

    def __init__(self, cell: Any, rgba: Rgba) -> None:
        self._cell = cell
        self._rgba = rgba
        self._tops: dict[tuple, tuple[np.ndarray, np.float32]] = {}
        self._view_matrix: list[float] = []

    def render(
        self, view_matrix: list[float], width: int, height: int, projection: list[float], light: list[float]
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The same image, the table's top filled in instead of shaded pixel by pixel; None where that cannot be.

        TinyRenderer shades every pixel of the table's top (most of a frame) at about 150 ns each:
        six of the seven milliseconds of a 185 x 185 px window. Seen straight down, the top is one
        flat face of one colour, at one depth (its normal, the light and the view are the same at
        every pixel: measured one colour over every window). So the world is rendered without the
        table (hidden for the render: its alpha 0, which TinyRenderer skips), and every pixel that
        rendered nothing, or something farther than the table's top (a part's bottom sunk a
        fraction of a millimetre into it), takes the top's colour and depth, as TinyRenderer would
        have drawn them: its depth test keeps the nearer fragment. The top's colour and depth come
        from a one-pixel render of the table through a pixel that showed nothing, kept per view and
        light. Not done (None: the plain render) in the pybullet window, for a camera not looking
        straight down (a real cell's tilted camera: the top's depth varies), for a view reaching past
        the table's top, or where a fragment lies exactly at the top's depth (a tie the draw order
        decides). ``tests/integration/test_camera_cell.py`` holds it to the plain render's pixels.
        """
        cell = self._cell
        self._view_matrix = view_matrix
        if cell.gui or not straight_down(view_matrix):
            return None
        planes = _frustum_planes(projection, cell.config.camera.near_m)
        if not self._within_table_top(planes):
            return None
        client, table = cell.client, cell.table_id
        table_rgba = list(client.getVisualShapeData(table)[0][7])
        client.changeVisualShape(table, -1, rgbaColor=[*table_rgba[:3], 0.0])
        try:
            rgba, z = self._rgba(width, height, projection, light)
        finally:
            client.changeVisualShape(table, -1, rgbaColor=table_rgba)
        top = self._table_top(planes, width, height, z, light, table_rgba)
        if top is None:
            return None
        colour, top_z = top
        # TinyRenderer's depth test runs on its own depths, which its z-buffer output rounds: a
        # fragment within a few of the output's steps of the top's (a part's edge where it meets
        # the table) may have been drawn or not. Such a frame is rendered as it is.
        steps = _TIE_STEPS * np.spacing(top_z)
        shown = z > top_z + steps
        if np.count_nonzero(shown) + np.count_nonzero(z < top_z - steps) != z.size:
            return None
        # The four bytes of a pixel as one 32-bit word: one pass over the pixels, not one per channel.
        np.copyto(rgba.view(np.uint32), colour.view(np.uint32), where=shown[:, :, np.newaxis])
        np.copyto(z, top_z, where=shown)
        return rgba[:, :, :3].copy(), z

    def _within_table_top(self, planes: tuple[float, float, float, float]) -> bool:
        """True when all of the frustum's view of the table's plane lies on its top (1 mm inside its edges)."""
        cell = self._cell
        view = np.asarray(self._view_matrix, dtype=float).reshape(4, 4, order="F")
        eye_to_world = np.linalg.inv(view)
        height_m = eye_to_world[2, 3]
        if height_m <= cell.config.camera.near_m:
            return False
        left, right, bottom, top = planes
        near = cell.config.camera.near_m
        corners = np.array([[x, y, -near, 0.0] for x in (left, right) for y in (bottom, top)]) * (height_m / near)
        points = eye_to_world[:3, 3] + (eye_to_world[:3, :3] @ corners[:, :3].T).T
        (length, width), (cx, cy) = cell.config.table_size_m, cell.config.table_centre_xy_m
        inside_x = np.abs(points[:, 0] - cx) < length / 2 - 0.001
        inside_y = np.abs(points[:, 1] - cy) < width / 2 - 0.001
        return bool(np.all(inside_x & inside_y))

    def _table_top(
        self,
        planes: tuple[float, float, float, float],
        width: int,
        height: int,
        z: np.ndarray,
        light: list[float],
        table_rgba: list[float],
    ) -> tuple[np.ndarray, np.float32] | None:
        """The table top's RGBA and z-buffer value for this view and light: one pixel rendered where nothing was."""
        key = (tuple(self._view_matrix), tuple(light), tuple(table_rgba))
        if key in self._tops:
            return self._tops[key]
        empty = z >= _NOTHING_Z
        # A pixel whose neighbours showed nothing either: the one-pixel render samples near its corner.
        inner = empty[:-2, :-2] & empty[:-2, 1:-1] & empty[:-2, 2:] & empty[1:-1, :-2] & empty[1:-1, 1:-1]
        inner = inner & empty[1:-1, 2:] & empty[2:, :-2] & empty[2:, 1:-1] & empty[2:, 2:]
        rows, columns = np.nonzero(inner)
        if len(rows) == 0:
            return None
        row, column = int(rows[0]) + 1, int(columns[0]) + 1
        left, right, bottom, top = planes
        du, dv = (right - left) / width, (top - bottom) / height
        near, far = self._cell.config.camera.near_m, self._cell.config.camera.far_m
        pixel = frustum(left + column * du, left + (column + 1) * du, top - (row + 1) * dv, top - row * dv, near, far)
        rgba, pixel_z = self._rgba(1, 1, pixel, light)
        view = np.asarray(self._view_matrix, dtype=float).reshape(4, 4, order="F")
        distance_m = np.linalg.inv(view)[2, 3]
        expected_z = far * (distance_m - near) / ((far - near) * distance_m)
        if abs(float(pixel_z[0, 0]) - expected_z) > 1e-5:
            return None  # something other than the table's top there
        found = (rgba[0, 0].copy(), np.float32(pixel_z[0, 0]))
        if len(self._tops) >= 16:  # a jittering light gives each frame its own
            self._tops.pop(next(iter(self._tops)))
        self._tops[key] = found
        return found


#: The z-buffer of a pixel TinyRenderer drew nothing in (its clear value, the largest float32 below 1).
_NOTHING_Z = np.float32(0.9999999)
#: Steps of the z-buffer's float32 around the table top's value within which a fragment may be in front or behind.
_TIE_STEPS = 4


def _frustum_planes(projection: list[float], near: float) -> tuple[float, float, float, float]:
    """(left, right, bottom, top) on the near plane of a ``glFrustum`` matrix (column-major, as pybullet takes it)."""
    p00, p11, p02, p12 = projection[0], projection[5], projection[8], projection[9]
    width, height = 2.0 * near / p00, 2.0 * near / p11
    centre_x, centre_y = p02 * width / 2.0, p12 * height / 2.0
    return centre_x - width / 2.0, centre_x + width / 2.0, centre_y - height / 2.0, centre_y + height / 2.0


def frustum(left: float, right: float, bottom: float, top: float, near: float, far: float) -> list[float]:
    """``glFrustum``'s matrix, column-major as pybullet takes it."""
    matrix = np.array(
        [
            [2 * near / (right - left), 0.0, (right + left) / (right - left), 0.0],
            [0.0, 2 * near / (top - bottom), (top + bottom) / (top - bottom), 0.0],
            [0.0, 0.0, -(far + near) / (far - near), -2 * far * near / (far - near)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )
    return [float(v) for v in matrix.flatten(order="F")]
