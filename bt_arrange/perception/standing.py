"""Does a raised part stand on its support? Its top face's plane from the depth image.

The colour detection measures a raised part on the plane its top face should lie on (``z_m`` plus
its height); depth says whether it does. ``measure_top_face`` takes a frame with depth and the
part's measured pose, back-projects the depth pixels inside its top face (shrunk by
``INSET_M``, away from the edges where depth mixes the face and what lies beyond it), fits a plane
by least squares and returns its height at the part's centre and its tilt from level. A part that
stands where the plan says has its top face at ``z_m + height`` and level; one tipped over an edge
of its support is tilted; one that fell is lower.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bt_arrange.errors import PerceptionError
from bt_arrange.geometry import Pose
from bt_arrange.perception.pose import project_world
from bt_arrange.robot import CameraFrame
from bt_arrange.shapes import Shape, footprint_m, grown

#: The face is sampled this far (m) inside its edges: depth at an edge mixes in what lies beyond.
INSET_M = 0.005
#: Fewer depth samples than this on the face, and the plane is not trusted.
MIN_SAMPLES = 50


@dataclass(frozen=True)
class TopFace:
    """The top face's plane as depth measures it: height at the part's centre (m), tilt from level (deg)."""

    height_m: float
    tilt_deg: float
    samples: int
    #: RMS distance of the samples from the plane (m): a face broken by an edge, or noise.
    residual_m: float


def measure_top_face(frame: CameraFrame, pose: Pose, shape: Shape, top_z_m: float) -> TopFace:
    """The plane of the part's top face from ``frame.depth_m``, sampled where it should be (``pose`` at ``top_z_m``)."""
    if frame.depth_m is None:
        raise PerceptionError("the frame has no depth: capture(with_depth=True)")
    inner = grown(shape, -INSET_M)
    planar = pose.planar()
    corners = footprint_m(inner, planar.x_m, planar.y_m, planar.yaw_rad)
    points = np.column_stack([corners, np.full(len(corners), top_z_m)])
    pixels = project_world(frame.intrinsics, frame.camera_pose_world, points)
    depth = np.asarray(frame.depth_m, dtype=np.float64)
    mask = np.zeros(depth.shape, dtype=np.uint8)
    cv2.fillPoly(mask, [np.round(pixels).astype(np.int32)], 1)
    rows, cols = np.nonzero(mask & np.isfinite(depth).astype(np.uint8))
    if len(rows) < MIN_SAMPLES:
        raise PerceptionError(
            f"only {len(rows)} depth pixels on the top face where it should be (at least {MIN_SAMPLES} needed)"
        )
    z = depth[rows, cols]
    intrinsics = frame.intrinsics
    xn = (cols - intrinsics.cx_px) / intrinsics.fx_px
    yn = (rows - intrinsics.cy_px) / intrinsics.fy_px
    camera = np.column_stack([xn * z, yn * z, z])
    T = frame.camera_pose_world
    world = camera @ T.rotation.T + T.position_m
    # z = a x + b y + c about the part's centre: c is the height there.
    design = np.column_stack([world[:, 0] - planar.x_m, world[:, 1] - planar.y_m, np.ones(len(world))])
    (a, b, c), *_ = np.linalg.lstsq(design, world[:, 2], rcond=None)
    residual = world[:, 2] - design @ np.array([a, b, c])
    return TopFace(
        height_m=float(c),
        tilt_deg=math.degrees(math.atan(math.hypot(a, b))),
        samples=len(world),
        residual_m=float(np.sqrt(np.mean(residual**2))),
    )
