"""Camera drivers for a real cell: OpenCV reading a network camera's snapshot URL, or a V4L2 device / a stream.

``--camera SPEC`` chooses one (``open_camera``):

- ``http://HOST:PORT/`` (a URL ending in ``/``): a **network camera** serving snapshots, read with
  urllib and ``cv2.imdecode``. ``GET info`` gives its factory intrinsics as JSON (``width_px``,
  ``height_px``, ``fx_px``, ``fy_px``, ``cx_px``, ``cy_px``, ``distortion``, ``depth_unit_m``,
  ``model``); ``GET color.png?x=&y=&w=&h=&binning=`` a lossless RGB frame taken now, of a window of
  the sensor read out at a binning (all optional: the whole image), with its time in the header
  ``X-Timestamp-S``; ``GET depth.png?...`` the same as 16-bit depth in ``depth_unit_m``. A window
  asked by ``Camera.capture(window=...)`` is read out by the camera, so a measurement moves only the
  pixels it needs. This driver is proven end to end against the emulated controller's camera.
- anything else: ``cv2.VideoCapture`` (a V4L2 device ``/dev/video0`` or its index ``0``, an RTSP or
  MJPEG stream URL). The full frame is grabbed and the window cut and binned here; no depth. Its
  intrinsics come from a calibration file (or the nominal pinhole). Documented, not exercised end to end.

The camera's pose in the world (the robot's base frame) is not the driver's: it comes from
``--calibration camera.toml`` or the cell's nominal mount (``bt_arrange.paper_cell``).
"""

from __future__ import annotations

import json
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Callable
from typing import Any

import numpy as np

from bt_arrange.errors import BackendError
from bt_arrange.geometry import Pose
from bt_arrange.motion.safety import SafetyStop
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow

#: How long one HTTP request to the camera may take (s): a 1920x1080 PNG over a lab network.
HTTP_TIMEOUT_S = 10.0
#: Frames a stream is read ahead by before the one used (its buffer holds frames from before the motion).
STREAM_FLUSH_FRAMES = 4


class CameraLinkError(BackendError):
    """The camera could not be reached, or sent what is not an image of the expected size."""


def is_snapshot_url(spec: str) -> bool:
    """True for a network camera's snapshot base URL (``http(s)://HOST[:PORT]/...`` ending in ``/``)."""
    return spec.startswith(("http://", "https://")) and spec.endswith("/")


class NetworkCamera:
    """A network camera read by snapshot URL: a ``bt_arrange.robot.Camera`` (windows read out by the camera)."""

    def __init__(
        self,
        base_url: str,
        pose_world: Pose,
        *,
        clock: Callable[[], float] | None = None,
        timeout_s: float = HTTP_TIMEOUT_S,
    ) -> None:
        self.base_url = base_url
        self._pose_world = pose_world
        self._clock = clock
        self._timeout_s = timeout_s
        info = json.loads(self._get("info").decode("utf-8"))
        try:
            self._intrinsics = CameraIntrinsics(
                int(info["width_px"]),
                int(info["height_px"]),
                float(info["fx_px"]),
                float(info["fy_px"]),
                float(info["cx_px"]),
                float(info["cy_px"]),
                tuple(float(v) for v in info.get("distortion", (0.0,) * 5)),
            )
            self._depth_unit_m = float(info.get("depth_unit_m", 0.001))
        except (KeyError, TypeError, ValueError) as error:
            raise CameraLinkError(f"the camera at {base_url} sent intrinsics without {error}") from error
        #: The camera's own name for itself (``model`` of its info).
        self.model = str(info.get("model", "network camera"))
        #: The camera's timestamp of the last frame (``X-Timestamp-S``), or None.
        self.last_timestamp_s: float | None = None

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """The camera's factory intrinsics of its full image (a calibration replaces them, ``CalibratedCamera``)."""
        return self._intrinsics

    @property
    def pose_world(self) -> Pose:
        """``T_W_C``: the cell's nominal mount (a calibration replaces it)."""
        return self._pose_world

    def use_clock(self, clock: Callable[[], float]) -> None:
        """Stamp frames with ``clock`` (the world's time), once the world exists."""
        self._clock = clock

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """One frame taken now; only ``window`` (read out by the camera at its binning) when given.

        A camera lost mid-run ends the run (``SafetyStop``: the arm is braked by the framework): a
        tree that cannot look must not go on moving parts it cannot see.
        """
        try:
            return self._capture(with_depth, window)
        except CameraLinkError as error:
            raise SafetyStop(str(error), arm_stopped=False) from error

    def _capture(self, with_depth: bool, window: PixelWindow | None) -> CameraFrame:
        import cv2

        query = ""
        intrinsics = self._intrinsics
        if window is not None and not window.is_full(self._intrinsics):
            intrinsics = self._intrinsics.windowed(window)
            region = {"x": window.x_px, "y": window.y_px, "w": window.width_px, "h": window.height_px}
            query = "?" + urllib.parse.urlencode({**region, "binning": window.binning})
        bgr = self._image("color.png" + query, cv2.IMREAD_COLOR, intrinsics)
        rgb = np.ascontiguousarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
        depth = None
        if with_depth:
            raw = self._image("depth.png" + query, cv2.IMREAD_UNCHANGED, intrinsics)
            depth = (raw.astype(np.float32) * np.float32(self._depth_unit_m)).astype(np.float32)
        time_s = self._clock() if self._clock is not None else (self.last_timestamp_s or 0.0)
        return CameraFrame(rgb, depth, intrinsics, self._pose_world, time_s)

    def _image(self, path: str, flags: int, intrinsics: CameraIntrinsics) -> Any:
        import cv2

        data = self._get(path)
        image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), flags)
        if image is None:
            raise CameraLinkError(f"the camera at {self.base_url} sent {path.split('?')[0]} that is not an image")
        if image.shape[:2] != (intrinsics.height_px, intrinsics.width_px):
            raise CameraLinkError(
                f"the camera at {self.base_url} sent a {image.shape[1]}x{image.shape[0]} px image for a "
                f"{intrinsics.width_px}x{intrinsics.height_px} px request"
            )
        return image

    def _get(self, path: str) -> bytes:
        url = self.base_url + path
        try:
            with urllib.request.urlopen(url, timeout=self._timeout_s) as response:  # noqa: S310 - the user's camera
                stamp = response.headers.get("X-Timestamp-S")
                if stamp is not None:
                    try:
                        self.last_timestamp_s = float(stamp)
                    except ValueError:
                        self.last_timestamp_s = None
                return bytes(response.read())
        except urllib.error.HTTPError as error:
            raise CameraLinkError(f"the camera at {self.base_url} answered {error.code} to {path}") from error
        except (urllib.error.URLError, OSError) as error:
            reason = getattr(error, "reason", error)
            raise CameraLinkError(f"cannot reach the camera at {self.base_url}: {reason}") from error


class VideoCaptureCamera:
    """A camera OpenCV opens (``cv2.VideoCapture``): a V4L2 device or a stream URL. RGB only; windows cut here.

    Not exercised end to end (no such device on the machines this was built on): a lab checks it with
    ``bt-arrange info --backend ur --robot HOST --camera SPEC``, which grabs one frame.
    """

    def __init__(
        self,
        spec: str,
        pose_world: Pose,
        intrinsics: CameraIntrinsics | None,
        *,
        clock: Callable[[], float] | None = None,
    ) -> None:
        import cv2

        source: int | str = int(spec) if spec.isdigit() else spec
        self._capture = cv2.VideoCapture(source)
        if not self._capture.isOpened():
            raise CameraLinkError(f"OpenCV cannot open the camera {spec!r} (a V4L2 device, its index or a stream URL)")
        self.spec = spec
        self.model = f"OpenCV VideoCapture {spec}"
        self._pose_world = pose_world
        self._clock = clock
        frame = self._grab()
        height, width = frame.shape[:2]
        # Without a calibration, the nominal pinhole of the paper's camera's field of view at this size.
        self._intrinsics = intrinsics or CameraIntrinsics.from_fov(width, height, 70.0)
        if (self._intrinsics.width_px, self._intrinsics.height_px) != (width, height):
            raise CameraLinkError(
                f"the camera {spec!r} gives {width}x{height} px frames, its intrinsics are for "
                f"{self._intrinsics.width_px}x{self._intrinsics.height_px} px"
            )

    @property
    def intrinsics(self) -> CameraIntrinsics:
        """The intrinsics of the full frame."""
        return self._intrinsics

    @property
    def pose_world(self) -> Pose:
        """``T_W_C``."""
        return self._pose_world

    def _grab(self) -> Any:
        frame = None
        for _ in range(STREAM_FLUSH_FRAMES + 1):
            ok, frame = self._capture.read()
            if not ok:
                raise CameraLinkError(f"the camera {self.spec!r} gave no frame")
        return frame

    def use_clock(self, clock: Callable[[], float]) -> None:
        """Stamp frames with ``clock`` (the world's time), once the world exists."""
        self._clock = clock

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """The newest frame (RGB; no depth), cut to ``window`` and binned by area when given."""
        import cv2

        bgr = self._grab()
        intrinsics = self._intrinsics
        if window is not None and not window.is_full(self._intrinsics):
            intrinsics = self._intrinsics.windowed(window)
            bgr = bgr[window.y_px : window.y_px + window.height_px, window.x_px : window.x_px + window.width_px]
            if window.binning > 1:
                size = (window.out_width_px, window.out_height_px)
                bgr = cv2.resize(bgr, size, interpolation=cv2.INTER_AREA)
        rgb = np.ascontiguousarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
        return CameraFrame(rgb, None, intrinsics, self._pose_world, self._clock() if self._clock else 0.0)

    def close(self) -> None:
        """Release the device."""
        self._capture.release()


def open_camera(
    spec: str,
    pose_world: Pose,
    intrinsics: CameraIntrinsics | None = None,
    *,
    clock: Callable[[], float] | None = None,
) -> NetworkCamera | VideoCaptureCamera:
    """The driver for ``--camera SPEC``: a snapshot URL's network camera, else OpenCV's VideoCapture."""
    if is_snapshot_url(spec):
        return NetworkCamera(spec, pose_world, clock=clock)
    return VideoCaptureCamera(spec, pose_world, intrinsics, clock=clock)
