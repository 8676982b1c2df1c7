"""Synthetic top-camera frames of cubes and flat prisms on a table, with exactly known ground truth.

Used by the tests and by :mod:`bt_arrange.perception.evaluate` to measure the pipeline without
a simulator. Cubes are drawn as their visible faces (near-white sides first, coloured tops
last, like a z-buffer would for a camera above the table), each pixel is sampled on a
``supersample x supersample`` grid and averaged with ``cv2.INTER_AREA``: the result is an
area-sampled, anti-aliased image whose polygon edges are known to floating-point precision.
``supersample=1`` samples pixel centres only, the aliased look of pybullet's TinyRenderer.
A :class:`SyntheticPrism` (any simple outline, convex or not) is drawn the same way: its
near-white sides that face the camera, then its coloured top face, each sample tested against
the exact polygon.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bt_arrange.deprecation import renamed_attributes, renamed_keywords
from bt_arrange.geometry import FloatArray, Pose, rotation_z
from bt_arrange.objects import CUBE
from bt_arrange.perception.colours import PAINT_RGB, SIDE_RGB
from bt_arrange.robot import CameraFrame, CameraIntrinsics
from bt_arrange.shapes import Prism

#: The simulated cell's top-face colours (RGB 0..1, fully lit) and part sides.
SIM_PART_COLOURS_RGB = PAINT_RGB
SIM_SIDE_RGB = SIDE_RGB
#: The synthetic cube's edge: the paper's cube (``bt_arrange.objects.CUBE``).
CUBE_EDGE_M = CUBE.size_m[0]
SIM_TABLE_RGB = (0.45, 0.45, 0.47)
SIM_CAMERA_HEIGHT_M = 0.70
SIM_HORIZONTAL_FOV_DEG = 70.0


def sim_intrinsics(width_px: int = 1920, height_px: int = 1080) -> CameraIntrinsics:
    """The simulated L515-like camera: 70 deg horizontal field of view, square pixels, centred."""
    return CameraIntrinsics.from_fov(width_px, height_px, SIM_HORIZONTAL_FOV_DEG)


def top_down_camera_pose(
    x_m: float = 0.5, y_m: float = 0.0, height_m: float = SIM_CAMERA_HEIGHT_M, tilt_deg: float = 0.0
) -> Pose:
    """``T_W_C`` of a camera above ``(x, y)`` looking down, oriented like the simulated cell's.

    Image right is world -y and image down is world -x. ``tilt_deg`` turns the camera about its
    own x axis, so that it no longer looks straight down.
    """
    looking_down = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    return Pose.from_rotation([x_m, y_m, height_m], looking_down @ tilt)


@dataclass(frozen=True)
class SyntheticCube:
    """A cube resting on the table: its colour's name, centre ``(x, y)`` and yaw.

    The top face is ``rgb`` if given, else the simulator's colour of that name, scaled by
    ``brightness`` (the simulator's lighting gives 0.45..1.0).
    """

    colour: str
    x_m: float
    y_m: float
    yaw_rad: float = 0.0
    brightness: float = 1.0
    rgb: tuple[float, float, float] | None = None
    edge_m: float = CUBE_EDGE_M
    table_z_m: float = 0.0
    #: The simulated cubes' colour is a thin plate inset at the top: its sides, this tall,
    #: show the colour on the cube's visible sides, just below the top face's edge.
    top_plate_m: float = 0.0

    @property
    def top_rgb(self) -> FloatArray:
        """The top face's rendered colour (0..1)."""
        return _top_rgb(self.rgb, self.colour, self.brightness)

    @property
    def centre_world(self) -> Pose:
        """Pose of the cube's centre in the world."""
        return Pose.from_planar(self.x_m, self.y_m, self.yaw_rad, self.table_z_m + self.edge_m / 2)

    def corners_world(self, z_m: float) -> FloatArray:
        """The four corners of the horizontal cross-section at height ``z_m`` (4x3), counter-clockwise."""
        h = self.edge_m / 2
        local = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
        return local @ rotation_z(self.yaw_rad).T + np.array([self.x_m, self.y_m, z_m])

    def top_corners_world(self) -> FloatArray:
        """The top face's corners (4x3)."""
        return self.corners_world(self.table_z_m + self.edge_m)


def _top_rgb(rgb: tuple[float, float, float] | None, colour: str, brightness: float) -> FloatArray:
    """A top face's rendered colour (0..1): ``rgb``, else the simulator's paint of ``colour``, lit by ``brightness``."""
    return np.asarray(rgb if rgb is not None else SIM_PART_COLOURS_RGB[colour], dtype=float) * brightness


@dataclass(frozen=True)
class SyntheticPrism:
    """A flat part resting on the table: a :class:`Prism` at ``(x, y)`` (its area centroid) turned by ``yaw_rad``.

    The top face is ``rgb`` if given, else the simulator's colour of that name, scaled by
    ``brightness``; the sides are near-white and shaded like a box's.
    """

    colour: str
    x_m: float
    y_m: float
    yaw_rad: float
    prism: Prism
    brightness: float = 1.0
    rgb: tuple[float, float, float] | None = None
    table_z_m: float = 0.0

    @property
    def top_rgb(self) -> FloatArray:
        """The top face's rendered colour (0..1)."""
        return _top_rgb(self.rgb, self.colour, self.brightness)

    @property
    def centre_world(self) -> Pose:
        """Pose of the part's frame in the world: the area centroid, half the height above the table."""
        return Pose.from_planar(self.x_m, self.y_m, self.yaw_rad, self.table_z_m + self.prism.height_m / 2)

    def outline_world(self, z_m: float) -> FloatArray:
        """The outline at height ``z_m`` (N x 3), counter-clockwise seen from above."""
        local = np.column_stack([self.prism.outline_m, np.zeros(len(self.prism.outline_m))])
        return local @ rotation_z(self.yaw_rad).T + np.array([self.x_m, self.y_m, z_m])

    def top_outline_world(self) -> FloatArray:
        """The top face's outline (N x 3)."""
        return self.outline_world(self.table_z_m + self.prism.height_m)


def project_points(intrinsics: CameraIntrinsics, camera_pose_world: Pose, points_world: ArrayLike) -> FloatArray:
    """Pinhole projection (no distortion) of world points to pixel coordinates (Nx2)."""
    points = np.atleast_2d(np.asarray(points_world, dtype=float))
    in_camera = (points - camera_pose_world.position_m) @ camera_pose_world.rotation
    uv = in_camera[:, :2] / in_camera[:, 2:3]
    return np.column_stack(
        [intrinsics.fx_px * uv[:, 0] + intrinsics.cx_px, intrinsics.fy_px * uv[:, 1] + intrinsics.cy_px]
    )


@dataclass(frozen=True)
class _Face:
    polygon_px: FloatArray  # Nx2; convex unless ``convex`` is False
    rgb: FloatArray  # 0..1
    convex: bool = True


@functools.singledispatch
def _visible(
    part: object,
    intrinsics: CameraIntrinsics,
    camera_pose_world: Pose,
    side_rgb: tuple[float, float, float],
    light_direction: FloatArray,
) -> tuple[list[_Face], _Face]:
    """A rendered part's sides that face the camera, shaded, and its top face (one function per kind of part)."""
    raise TypeError(f"cannot render {part!r}")


@_visible.register
def _visible_faces(
    cube: SyntheticCube,
    intrinsics: CameraIntrinsics,
    camera_pose_world: Pose,
    side_rgb: tuple[float, float, float],
    light_direction: FloatArray,
) -> tuple[list[_Face], _Face]:
    """The cube's side faces that face the camera, shaded, and its top face."""
    top = cube.top_corners_world()
    bottom = cube.corners_world(cube.table_z_m)
    plate = cube.corners_world(cube.table_z_m + cube.edge_m - cube.top_plate_m)
    centre = cube.centre_world.position_m
    sides = []
    for i in range(4):
        j = (i + 1) % 4
        quad = np.array([bottom[i], bottom[j], top[j], top[i]])
        normal = quad.mean(axis=0) - centre
        normal[2] = 0.0
        normal /= np.linalg.norm(normal)
        # Back-face culling: a face seen from behind is hidden by the cube itself.
        if normal @ (camera_pose_world.position_m - quad.mean(axis=0)) <= 0:
            continue
        shade = 0.45 + 0.55 * max(0.0, float(normal @ light_direction))
        sides.append(_Face(project_points(intrinsics, camera_pose_world, quad), np.asarray(side_rgb) * shade))
        if cube.top_plate_m > 0:
            band = np.array([plate[i], plate[j], top[j], top[i]])
            colour = cube.top_rgb / max(cube.brightness, 1e-9) * shade
            sides.append(_Face(project_points(intrinsics, camera_pose_world, band), colour))
    top_face = _Face(project_points(intrinsics, camera_pose_world, top), cube.top_rgb)
    return sides, top_face


@_visible.register
def _visible_prism_faces(
    part: SyntheticPrism,
    intrinsics: CameraIntrinsics,
    camera_pose_world: Pose,
    side_rgb: tuple[float, float, float],
    light_direction: FloatArray,
) -> tuple[list[_Face], _Face]:
    """The prism's sides that face the camera (farthest first), shaded, and its top face (any simple polygon)."""
    top = part.top_outline_world()
    bottom = part.outline_world(part.table_z_m)
    count = len(top)
    eye = camera_pose_world.position_m
    sides = []
    for i in range(count):
        j = (i + 1) % count
        quad = np.array([bottom[i], bottom[j], top[j], top[i]])
        edge = top[j] - top[i]
        normal = np.array([edge[1], -edge[0], 0.0])  # counter-clockwise outline: outward is right of travel
        normal /= np.linalg.norm(normal)
        if normal @ (eye - quad.mean(axis=0)) <= 0:
            continue
        shade = 0.45 + 0.55 * max(0.0, float(normal @ light_direction))
        distance = float(np.linalg.norm(quad.mean(axis=0) - eye))
        sides.append(
            (distance, _Face(project_points(intrinsics, camera_pose_world, quad), np.asarray(side_rgb) * shade))
        )
    # A non-convex prism's sides may hide each other: paint the farther ones first.
    ordered = [face for _, face in sorted(sides, key=lambda item: -item[0])]
    top_face = _Face(project_points(intrinsics, camera_pose_world, top), part.top_rgb, convex=False)
    return ordered, top_face


def _paint(tile: NDArray[np.float32], origin_px: tuple[int, int], supersample: int, face: _Face) -> None:
    """Paint a convex polygon into a supersampled tile, testing each sample's centre exactly."""
    s = supersample
    x0, y0 = origin_px
    height, width = tile.shape[:2]
    polygon = face.polygon_px
    # Sample (i, j) of the tile sits at low-resolution pixel coordinate x0 + (i + 0.5) / s - 0.5:
    # pixel centres are integers, as in OpenCV.
    u_min, v_min = polygon.min(axis=0)
    u_max, v_max = polygon.max(axis=0)
    i0 = max(0, math.floor((u_min - x0 + 0.5) * s - 0.5))
    i1 = min(width, math.ceil((u_max - x0 + 0.5) * s - 0.5) + 1)
    j0 = max(0, math.floor((v_min - y0 + 0.5) * s - 0.5))
    j1 = min(height, math.ceil((v_max - y0 + 0.5) * s - 0.5) + 1)
    if i0 >= i1 or j0 >= j1:
        return
    u = x0 + (np.arange(i0, i1) + 0.5) / s - 0.5
    v = y0 + (np.arange(j0, j1) + 0.5) / s - 0.5
    if not face.convex:
        tile[j0:j1, i0:i1][_inside_polygon(polygon, u, v)] = face.rgb.astype(np.float32)
        return
    area2 = float(np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1]))
    orientation = 1.0 if area2 > 0 else -1.0
    inside = np.ones((j1 - j0, i1 - i0), dtype=bool)
    for k in range(len(polygon)):
        (ua, va), (ub, vb) = polygon[k], polygon[(k + 1) % len(polygon)]
        # Edge function: positive on the polygon's inner side for either orientation.
        edge = orientation * ((ub - ua) * (v[:, None] - va) - (vb - va) * (u[None, :] - ua))
        inside &= edge >= 0
    tile[j0:j1, i0:i1][inside] = face.rgb.astype(np.float32)


def _inside_polygon(polygon: FloatArray, u: FloatArray, v: FloatArray) -> NDArray[np.bool_]:
    """Which samples (v rows x u columns) lie inside a simple polygon, by the even-odd rule (exact per sample)."""
    inside = np.zeros((len(v), len(u)), dtype=bool)
    for k in range(len(polygon)):
        (ua, va), (ub, vb) = polygon[k], polygon[(k + 1) % len(polygon)]
        if va == vb:
            continue  # a horizontal edge crosses no sample's row in a half-open test
        # Rows whose centre lies in [min(va, vb), max(va, vb)): the edge crosses them once.
        rows = (v >= min(va, vb)) & (v < max(va, vb))
        if not np.any(rows):
            continue
        u_cross = ua + (v[rows] - va) * (ub - ua) / (vb - va)
        inside[rows] ^= u[None, :] < u_cross[:, None]
    return inside


@renamed_keywords(cubes="parts")
def render_frame(
    parts: Sequence[SyntheticCube | SyntheticPrism],
    intrinsics: CameraIntrinsics | None = None,
    camera_pose_world: Pose | None = None,
    *,
    supersample: int = 8,
    table_rgb: tuple[float, float, float] = SIM_TABLE_RGB,
    side_rgb: tuple[float, float, float] = SIM_SIDE_RGB,
    light_direction: tuple[float, float, float] = (0.3, 0.2, 1.0),
    noise_sigma: float = 0.0,
    blur_sigma_px: float = 0.0,
    seed: int = 0,
) -> CameraFrame:
    """Render ``parts`` (cubes and prisms) on a grey table as the top camera sees them.

    ``noise_sigma`` is Gaussian sensor noise in 0..255 grey levels, ``blur_sigma_px`` a Gaussian
    blur applied before the noise; the default camera is the simulated cell's.
    """
    intrinsics = intrinsics or sim_intrinsics()
    camera_pose_world = camera_pose_world or top_down_camera_pose()
    width, height = intrinsics.width_px, intrinsics.height_px
    image = np.empty((height, width, 3), dtype=np.float32)
    image[:] = np.asarray(table_rgb, dtype=np.float32)
    light = np.asarray(light_direction, dtype=float) / np.linalg.norm(light_direction)

    faces = [_visible(part, intrinsics, camera_pose_world, side_rgb, light) for part in parts]
    # Tiles: the parts' pixel boxes, merged where they overlap so that shared edges mix the two
    # colours that meet there (and not the table's).
    boxes: list[list[int]] = []
    for sides, top in faces:
        points = np.vstack([top.polygon_px, *[f.polygon_px for f in sides]])
        x0, y0 = np.floor(points.min(axis=0)).astype(int) - 2
        x1, y1 = np.ceil(points.max(axis=0)).astype(int) + 3
        boxes.append([max(0, x0), max(0, y0), min(width, x1), min(height, y1)])
    merged = True
    while merged:
        merged = False
        for a in range(len(boxes)):
            for b in range(a + 1, len(boxes)):
                p, q = boxes[a], boxes[b]
                if p[0] < q[2] and q[0] < p[2] and p[1] < q[3] and q[1] < p[3]:
                    boxes[a] = [min(p[0], q[0]), min(p[1], q[1]), max(p[2], q[2]), max(p[3], q[3])]
                    del boxes[b]
                    merged = True
                    break
            if merged:
                break
    all_sides = [f for sides, _ in faces for f in sides]
    all_tops = [top for _, top in faces]
    for x0, y0, x1, y1 in boxes:
        if x0 >= x1 or y0 >= y1:
            continue
        tile = np.empty(((y1 - y0) * supersample, (x1 - x0) * supersample, 3), dtype=np.float32)
        tile[:] = np.asarray(table_rgb, dtype=np.float32)
        # Painter's order: every top face lies on the plane nearest the camera, so tops go last.
        for face in [*all_sides, *all_tops]:
            _paint(tile, (x0, y0), supersample, face)
        if supersample > 1:
            image[y0:y1, x0:x1] = cv2.resize(tile, (x1 - x0, y1 - y0), interpolation=cv2.INTER_AREA)
        else:
            image[y0:y1, x0:x1] = tile

    image *= 255.0
    if blur_sigma_px > 0:
        image = np.asarray(cv2.GaussianBlur(image, (0, 0), blur_sigma_px), dtype=np.float32)
    if noise_sigma > 0:
        image += np.random.default_rng(seed).normal(0.0, noise_sigma, image.shape).astype(np.float32)
    rgb = np.clip(np.round(image), 0, 255).astype(np.uint8)
    return CameraFrame(rgb, None, intrinsics, camera_pose_world, 0.0)


def visible_table_box(
    intrinsics: CameraIntrinsics, camera_pose_world: Pose, z_m: float, margin_m: float = 0.0
) -> tuple[float, float, float, float]:
    """``(x_min, x_max, y_min, y_max)`` of a box at height ``z_m`` that the camera sees entirely.

    The box lies inside the back-projected image corners, shrunk by ``margin_m`` on every side
    (for a cube's top face to stay whole, half its diagonal, about 0.036 m).
    """
    corners = [
        (0.0, 0.0),
        (intrinsics.width_px - 1.0, 0.0),
        (0.0, intrinsics.height_px - 1.0),
        (intrinsics.width_px - 1.0, intrinsics.height_px - 1.0),
    ]
    points = []
    for u, v in corners:
        ray = camera_pose_world.rotation @ np.array(
            [(u - intrinsics.cx_px) / intrinsics.fx_px, (v - intrinsics.cy_px) / intrinsics.fy_px, 1.0]
        )
        origin = camera_pose_world.position_m
        points.append(origin + (z_m - origin[2]) / ray[2] * ray)
    xs, ys = np.sort([p[0] for p in points]), np.sort([p[1] for p in points])
    # The inner two of the four corner coordinates bound a box inside a trapezoid too.
    return float(xs[1] + margin_m), float(xs[2] - margin_m), float(ys[1] + margin_m), float(ys[2] - margin_m)


def random_cubes(
    rng: np.random.Generator,
    count: int,
    intrinsics: CameraIntrinsics | None = None,
    camera_pose_world: Pose | None = None,
    colours: Sequence[str] = ("red", "green", "blue", "yellow"),
    brightness_range: tuple[float, float] = (0.45, 1.0),
) -> list[SyntheticCube]:
    """``count`` single cubes spread uniformly over the visible table, any yaw, colour and lighting."""
    intrinsics = intrinsics or sim_intrinsics()
    camera_pose_world = camera_pose_world or top_down_camera_pose()
    x_min, x_max, y_min, y_max = visible_table_box(intrinsics, camera_pose_world, CUBE_EDGE_M, 0.04)
    return [
        SyntheticCube(
            str(rng.choice(list(colours))),
            float(rng.uniform(x_min, x_max)),
            float(rng.uniform(y_min, y_max)),
            float(rng.uniform(-math.pi, math.pi)),
            float(rng.uniform(*brightness_range)),
        )
        for _ in range(count)
    ]


# Deprecated: the names that said "cube" for any part, kept one release (CHANGELOG.md).
if TYPE_CHECKING:
    SIM_CUBE_COLOURS_RGB = SIM_PART_COLOURS_RGB
else:
    __getattr__ = renamed_attributes(__name__, {"SIM_CUBE_COLOURS_RGB": "SIM_PART_COLOURS_RGB"})
