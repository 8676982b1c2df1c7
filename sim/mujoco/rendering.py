"""The top camera's frames rendered by MuJoCo's OpenGL renderer, offscreen (OSMesa headless).

One GL context and one offscreen buffer of the full image's size per cell; a window of the image
(``PixelWindow``) is rendered into the buffer's corner through the part of the full frustum that
passes through the window's pixels (an off-axis frustum, like the pybullet cell's), binned by
rendering fewer pixels. OpenGL samples each pixel at its centre, so the rendered image is the
nominal pinhole exactly (principal point ``((W - 1) / 2, (H - 1) / 2)`` in OpenCV's pixel-centre
convention): no half-pixel shift to calibrate, unlike TinyRenderer's.
"""

from __future__ import annotations

import atexit
import contextlib
import os

import numpy as np

from bt_arrange.robot import CameraIntrinsics, PixelWindow

_GL_CONTEXTS: dict[tuple[int, int], object] = {}


def _gl_context(width: int, height: int):  # noqa: ANN202 - a mujoco GLContext
    """The process's offscreen GL context of a size: OSMesa's when ``MUJOCO_GL=osmesa``, else mujoco's choice.

    One per size and process, shared by every cell (one at a time renders, each making it current):
    a freed OSMesa context did not give all its memory back (measured: 3 to 5 MB a cell).
    ``mujoco.GLContext`` is fixed when mujoco is first imported; asking for OSMesa's by name keeps a
    process that imported mujoco before ``bt_arrange_sim.mujoco`` chose OSMesa working headless.
    """
    key = (width, height)
    if key not in _GL_CONTEXTS:
        import mujoco

        if os.environ.get("MUJOCO_GL") == "osmesa":
            from mujoco.osmesa import GLContext as base
        else:
            base = mujoco.GLContext
        # Freed at exit while its libraries are still loaded, not by ``__del__`` during the
        # interpreter's teardown (which printed a TypeError on stderr).
        shared = type("SharedGLContext", (base,), {"__del__": lambda self: None})
        try:
            context = shared(width, height)
        except Exception as error:  # noqa: BLE001 - a GL library that loads but cannot start (EGL without a GPU)
            from bt_arrange_sim.mujoco.gl import gl_error

            raise gl_error(error) from error
        atexit.register(_free_quietly, context)
        _GL_CONTEXTS[key] = context
    return _GL_CONTEXTS[key]


def _free_quietly(context) -> None:  # noqa: ANN001
    with contextlib.suppress(Exception):
        context.free()


class OffscreenRenderer:
    """Renders one model's fixed camera ``camera_name`` into numpy arrays, any window of the full image."""

    def __init__(self, model, camera_name: str, nominal: CameraIntrinsics, near_m: float, far_m: float) -> None:  # noqa: ANN001
        import mujoco

        self._model = model
        self._nominal = nominal
        self._near, self._far = near_m, far_m
        width, height = nominal.width_px, nominal.height_px
        self._gl = _gl_context(width, height)
        self._gl.make_current()
        self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._camera.fixedcamid = model.camera(camera_name).id

    def render(
        self,
        data,
        window: PixelWindow,
        with_depth: bool = False,
        light_direction: np.ndarray | None = None,  # noqa: ANN001
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """RGB (and depth in metres along the optical axis) of ``window`` as the scene is in ``data`` now."""
        import mujoco

        model = self._model
        if light_direction is not None:
            model.light_dir[0] = light_direction
        self._gl.make_current()
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        mujoco.mjv_updateScene(model, data, self._option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL, self._scene)
        left, right, bottom, top = self.frustum(window)
        for glcam in self._scene.camera:
            glcam.frustum_near = self._near
            glcam.frustum_far = self._far
            glcam.frustum_center = (left + right) / 2.0
            glcam.frustum_width = (right - left) / 2.0
            glcam.frustum_bottom = bottom
            glcam.frustum_top = top
        width, height = window.out_width_px, window.out_height_px
        rect = mujoco.MjrRect(0, 0, width, height)
        mujoco.mjr_render(rect, self._scene, self._context)
        rgb = np.empty((height, width, 3), dtype=np.uint8)
        depth = np.empty((height, width), dtype=np.float32) if with_depth else None
        mujoco.mjr_readPixels(rgb, depth, rect, self._context)
        rgb = np.ascontiguousarray(rgb[::-1])
        if depth is not None:
            depth = self._metric_depth(depth[::-1])
        return rgb, depth

    def frustum(self, window: PixelWindow) -> tuple[float, float, float, float]:
        """Left, right, bottom and top of the nominal frustum through ``window`` on the near plane."""
        n = self._nominal
        near = self._near
        # Pixel edges u = 0 .. W map to x = near * (u - (cx + 0.5)) / fx; rows run down from the top.
        left = near * (window.x_px - (n.cx_px + 0.5)) / n.fx_px
        right = near * (window.x_px + window.width_px - (n.cx_px + 0.5)) / n.fx_px
        top = near * ((n.cy_px + 0.5) - window.y_px) / n.fy_px
        bottom = near * ((n.cy_px + 0.5) - (window.y_px + window.height_px)) / n.fy_px
        return left, right, bottom, top

    def _metric_depth(self, z: np.ndarray) -> np.ndarray:
        """Reverse-Z buffer values to distances along the optical axis (the formula of ``mujoco.Renderer``)."""
        zfar, znear = np.float32(self._far), np.float32(self._near)
        c_coef = -(zfar + znear) / (zfar - znear)
        d_coef = -(np.float32(2) * zfar * znear) / (zfar - znear)
        c_coef = np.float32(-0.5) * c_coef - np.float32(0.5)
        d_coef = np.float32(-0.5) * d_coef
        return (d_coef / (z.astype(np.float64) + c_coef)).astype(np.float32)

    def close(self) -> None:
        """Free the model's GL resources (the process's GL context stays for the next cell)."""
        if self._context is not None:
            self._gl.make_current()
            self._context.free()
            self._context = None  # type: ignore[assignment]
