"""Perception: find the coloured cubes in a top-camera frame and estimate their poses.

The paper's pipeline (HSV threshold, 7x7 closing and opening, Suzuki-Abe contours,
Douglas-Peucker polygon, PnP refined by Levenberg-Marquardt, camera-to-world transform), with
the corners brought below a pixel so that a 1 mm threshold can be checked at 0.5 mm per pixel.
It takes a :class:`~bt_arrange.robot.CameraFrame` and knows nothing of the simulator::

    detector = CubeDetector()
    detection = detector.detect(camera.capture(), "red")
    if detection.found:
        print(detection.planar)
    else:
        print(detection.status, detection.reason)

See docs/perception.md.
"""

from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.perception.corners import CornerRefinement
from bt_arrange.perception.depth_grasp import DepthGraspConfig, DepthGraspEstimator
from bt_arrange.perception.detection import (
    CubeDetector,
    Detection,
    DetectionStatus,
    DetectorConfig,
    WorldRegion,
)
from bt_arrange.perception.pose import PoseModel

__all__ = [
    "DEFAULT_COLOUR_TABLE",
    "ColourRange",
    "ColourTable",
    "CornerRefinement",
    "CubeDetector",
    "DepthGraspConfig",
    "DepthGraspEstimator",
    "Detection",
    "DetectionStatus",
    "DetectorConfig",
    "PoseModel",
    "WorldRegion",
]
