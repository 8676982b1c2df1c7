"""The cell's top camera as a network camera: HTTP on ``--camera-port``, frames rendered when asked.

Endpoints (the contract with the ``ur`` backend):

- ``GET /info``: the camera's factory intrinsics as JSON (``width_px``, ``height_px``, ``fx_px``,
  ``fy_px``, ``cx_px``, ``cy_px``, ``distortion`` (k1, k2, p1, p2, k3), ``depth_unit_m``, ``model``);
- ``GET /color.png?x=X&y=Y&w=W&h=H&binning=B``: a lossless PNG of the RGB frame rendered now (the
  full image without parameters), header ``X-Timestamp-S`` the controller's time of the frame;
- ``GET /depth.png?...``: the same frame's depth, a 16-bit PNG in units of ``depth_unit_m`` (0: none).

The frame is the cell camera's own ``capture`` (its renderer, its noise), made on the physics
thread; the PNG is encoded on the request's thread.
"""

from __future__ import annotations

import json
import sys
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import TYPE_CHECKING, Any
from urllib.parse import parse_qs, urlsplit

import numpy as np

from bt_arrange.robot import PixelWindow

if TYPE_CHECKING:
    from bt_arrange_sim.ursim.controller import Controller
    from bt_arrange_sim.ursim.servers import ClientRegistry

DEPTH_UNIT_M = 0.0001
CAMERA_MODEL = "bt-arrange simulated top camera (L515-like RGB-D, pybullet TinyRenderer)"


def camera_info(controller: Controller) -> dict[str, Any]:
    """``/info``: the intrinsics the camera really has (the ideal cell's calibrated ones; a real cell's true ones)."""
    intrinsics = controller.cell.camera.true_intrinsics
    distortion = [float(v) for v in intrinsics.distortion]
    return {
        "width_px": intrinsics.width_px,
        "height_px": intrinsics.height_px,
        "fx_px": intrinsics.fx_px,
        "fy_px": intrinsics.fy_px,
        "cx_px": intrinsics.cx_px,
        "cy_px": intrinsics.cy_px,
        "distortion": (distortion + [0.0] * 5)[:5],
        "depth_unit_m": DEPTH_UNIT_M,
        "model": CAMERA_MODEL,
    }


class CameraServer(ThreadingHTTPServer):
    """The HTTP server; its client sockets are in the registry under ``camera`` (the faults port drops them)."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, controller: Controller, host: str, port: int, clients: ClientRegistry) -> None:
        self.controller = controller
        self.clients = clients
        super().__init__((host, port), CameraRequestHandler)
        self._thread = threading.Thread(target=self.serve_forever, name="camera-http", daemon=True)

    def start(self) -> None:
        """Serve from now on (its own thread)."""
        self._thread.start()

    def close(self) -> None:
        """Stop serving."""
        self.shutdown()
        self.server_close()

    def process_request_thread(self, request: Any, client_address: Any) -> None:  # noqa: D102
        self.clients.add("camera", request)
        try:
            super().process_request_thread(request, client_address)
        finally:
            self.clients.remove("camera", request)


class CameraRequestHandler(BaseHTTPRequestHandler):
    """One HTTP request: ``/info``, ``/color.png`` or ``/depth.png``."""

    server: CameraServer
    protocol_version = "HTTP/1.1"

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
        """Quiet: the controller's stderr is for what goes wrong."""

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        """Answer the request (a 400 with the reason for a bad window, a 404 for another path)."""
        url = urlsplit(self.path)
        try:
            if url.path == "/info":
                self._send(200, "application/json", json.dumps(camera_info(self.server.controller)).encode())
            elif url.path in ("/color.png", "/depth.png"):
                self._send_frame(url.path == "/depth.png", parse_qs(url.query))
            else:
                self._send(404, "text/plain", b"not found: /info, /color.png, /depth.png\n")
        except (ConnectionError, OSError):
            return
        except Exception as error:  # noqa: BLE001 - one bad request answers 500, the server goes on
            print(f"ursim: camera: {type(error).__name__}: {error}", file=sys.stderr)
            self._send(500, "text/plain", f"{type(error).__name__}: {error}\n".encode())

    def _send_frame(self, depth: bool, query: dict[str, list[str]]) -> None:
        import cv2

        controller = self.server.controller
        try:
            window = _window(query, controller.cell.camera.intrinsics)
        except (ValueError, Exception) as error:  # noqa: BLE001 - any bad parameter is the client's error
            self._send(400, "text/plain", f"bad window: {error}\n".encode())
            return
        frame = controller.call(lambda: controller.cell.camera.capture(with_depth=depth, window=window))
        if depth:
            metres = np.nan_to_num(np.asarray(frame.depth_m, dtype=np.float64), nan=0.0, posinf=0.0)
            far_m = controller.cell.config.camera.far_m
            metres[metres >= far_m * 0.999] = 0.0  # the far plane: nothing there
            image = np.clip(np.round(metres / DEPTH_UNIT_M), 0, 65535).astype(np.uint16)
        else:
            image = cv2.cvtColor(np.ascontiguousarray(frame.rgb), cv2.COLOR_RGB2BGR)
        ok, encoded = cv2.imencode(".png", image)
        if not ok:
            raise RuntimeError("PNG encoding failed")
        self._send(200, "image/png", encoded.tobytes(), {"X-Timestamp-S": repr(float(frame.time_s))})

    def _send(self, status: int, content_type: str, body: bytes, headers: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        for name, value in (headers or {}).items():
            self.send_header(name, value)
        self.end_headers()
        self.wfile.write(body)


def _window(query: dict[str, list[str]], intrinsics: Any) -> PixelWindow | None:
    """The pixel window of the query (None: the full image), checked to lie inside the image."""
    if not any(k in query for k in ("x", "y", "w", "h", "binning")):
        return None

    def number(name: str, default: int) -> int:
        return int(query[name][0]) if name in query else default

    x, y = number("x", 0), number("y", 0)
    window = PixelWindow(
        x,
        y,
        number("w", intrinsics.width_px - x),
        number("h", intrinsics.height_px - y),
        number("binning", 1),
    )
    window.check_inside(intrinsics)
    return window
