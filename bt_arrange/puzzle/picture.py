"""A painted slab: the picture on its top face, and the camera's colours held against it.

``picture = "PATH.png"`` in a ``[puzzle.NAME]`` prints an image over the slab's whole top face:
its columns run along the slab's length (x), its rows across it, the first row at the slab's +y
edge (as the picture is seen from the top camera with the slab unturned). ``picture = "fresco"``
is the built-in one (``builtin_picture``), drawn here. The camera tells a painted face from the grey
table and the near-white sides by its saturation, so a picture's colours must be saturated
(``MIN_SATURATION``); ``check_picture`` refuses one that is not, in one line.
"""

from __future__ import annotations

import hashlib
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PlanError

#: The built-in pictures, by name.
BUILT_IN = ("fresco",)
#: A picture file is at most this large (bytes) and this many pixels a side.
MAX_PICTURE_BYTES = 8 * 1024 * 1024
MAX_PICTURE_PX = 4096
#: The camera finds a painted face by saturation (HSV, 0..1): every pixel of a picture must have at least this much.
MIN_SATURATION = 0.45
#: And at least this value (0..1): dark pixels have no reliable hue under the cell's light.
MIN_VALUE = 0.35


def _draw_fresco(width_px: int = 640, height_px: int = 480) -> NDArray[np.uint8]:
    """The built-in picture: sweeping hues with rings and bands, saturated everywhere (deterministic)."""
    import cv2

    y, x = np.mgrid[0:height_px, 0:width_px].astype(np.float64)
    u, v = x / width_px, y / height_px
    hue = (0.55 * u + 0.35 * v + 0.12 * np.sin(7.0 * u) * np.cos(5.0 * v)) % 1.0
    for cx, cy, radius in ((0.25, 0.3, 0.18), (0.7, 0.65, 0.22), (0.8, 0.2, 0.1)):
        ring = np.hypot(u - cx, (v - cy) * height_px / width_px)
        hue = np.where(np.abs(ring - radius) < 0.025, (hue + 0.5) % 1.0, hue)
    saturation = 0.75 + 0.2 * np.cos(9.0 * u + 4.0 * v)
    value = 0.7 + 0.25 * np.sin(11.0 * v - 3.0 * u)
    hsv = np.dstack([hue * 179.0, saturation * 255.0, value * 255.0]).astype(np.uint8)
    rgb = cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB)
    return np.ascontiguousarray(rgb)


def builtin_picture(name: str) -> Path:
    """The file of a built-in picture, drawn once into the temporary folder (named by its content)."""
    import cv2

    if name not in BUILT_IN:
        raise PlanError(f"no built-in picture {name!r}: the built-in ones are {', '.join(BUILT_IN)}")
    rgb = _draw_fresco()
    ok, png = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    assert ok
    data = png.tobytes()
    folder = Path(tempfile.gettempdir()) / "bt_arrange_pictures"
    folder.mkdir(exist_ok=True)
    path = folder / f"{name}-{hashlib.sha1(data).hexdigest()[:12]}.png"
    if not path.exists():
        partial = path.with_suffix(f".{np.random.default_rng().integers(1 << 30)}.part")
        partial.write_bytes(data)
        partial.replace(path)
    return path


def picture_file(picture: str) -> Path:
    """The file of a puzzle's ``picture``: a built-in's drawn file, or the path itself."""
    return builtin_picture(picture) if picture in BUILT_IN else Path(picture)


def read_picture(path: str | Path) -> NDArray[np.uint8]:
    """A picture's pixels (RGB, rows x columns x 3); a ``PlanError`` in one line when it cannot be one."""
    import cv2

    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as error:
        raise PlanError(f"picture {path}: cannot be read ({error.strerror or error})") from None
    if size > MAX_PICTURE_BYTES:
        raise PlanError(f"picture {path}: {size:,} bytes, over the limit of {MAX_PICTURE_BYTES:,}")
    bgr = cv2.imdecode(np.fromfile(str(path), dtype=np.uint8), cv2.IMREAD_COLOR)
    if bgr is None:
        raise PlanError(f"picture {path}: not an image OpenCV reads (PNG or JPEG)")
    if max(bgr.shape[:2]) > MAX_PICTURE_PX or min(bgr.shape[:2]) < 8:
        raise PlanError(f"picture {path}: {bgr.shape[1]} x {bgr.shape[0]} px, outside 8 to {MAX_PICTURE_PX} px a side")
    return np.ascontiguousarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))


def check_picture(path: str | Path) -> None:
    """A ``PlanError`` when the picture has pixels the camera cannot tell from the table or the sides."""
    import cv2

    rgb = read_picture(path)
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV).reshape(-1, 3) / np.array([179.0, 255.0, 255.0])
    dull = np.mean((hsv[:, 1] < MIN_SATURATION) | (hsv[:, 2] < MIN_VALUE))
    if dull > 0.0:
        raise PlanError(
            f"picture {path}: {dull:.1%} of its pixels are greyish or dark (saturation under {MIN_SATURATION:g} or "
            f"value under {MIN_VALUE:g}): the camera tells a painted face from the table and the sides by its colour"
        )


def slab_uv(points_slab_m: NDArray[np.float64], size_m: tuple[float, float, float]) -> NDArray[np.float64]:
    """Texture coordinates (u along the picture's columns, v up its rows from the bottom) of points of the slab."""
    length, width = size_m[0], size_m[1]
    return np.column_stack([points_slab_m[:, 0] / length + 0.5, points_slab_m[:, 1] / width + 0.5])


def picture_rgb_at(
    picture: NDArray[np.uint8], points_slab_m: NDArray[np.float64], size_m: tuple[float, float, float]
) -> NDArray[np.float64]:
    """The picture's colours (RGB 0..1) at points of the slab (nearest pixel; points off the slab clipped to it)."""
    uv = np.clip(slab_uv(points_slab_m, size_m), 0.0, 1.0)
    rows, cols = picture.shape[:2]
    col = np.clip(np.round(uv[:, 0] * (cols - 1)).astype(int), 0, cols - 1)
    row = np.clip(np.round((1.0 - uv[:, 1]) * (rows - 1)).astype(int), 0, rows - 1)
    return picture[row, col].astype(np.float64) / 255.0


def hue_distance(first_rgb: NDArray[np.float64], second_rgb: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per pair of colours, the distance of their hues (0..0.5 of a turn): the light scales value, not hue."""
    import cv2

    def hues(rgb: NDArray[np.float64]) -> NDArray[np.float64]:
        pixels = np.clip(rgb * 255.0, 0, 255).astype(np.uint8).reshape(-1, 1, 3)
        return cv2.cvtColor(pixels, cv2.COLOR_RGB2HSV_FULL)[:, 0, 0].astype(np.float64) / 256.0

    turn = np.abs(hues(first_rgb) - hues(second_rgb))
    return np.minimum(turn, 1.0 - turn)


__all__ = [
    "BUILT_IN",
    "MIN_SATURATION",
    "builtin_picture",
    "check_picture",
    "hue_distance",
    "picture_file",
    "picture_rgb_at",
    "read_picture",
    "slab_uv",
]
