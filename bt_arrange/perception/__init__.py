"""Perception: find the coloured parts in a top-camera frame and estimate their poses.

The paper's pipeline (HSV threshold, 7x7 closing and opening, Suzuki-Abe contours,
Douglas-Peucker polygon, PnP refined by Levenberg-Marquardt, camera-to-world transform), with
the corners brought below a pixel so that a 1 mm threshold can be checked at 0.5 mm per pixel.
It takes a :class:`~bt_arrange.robot.CameraFrame` and knows nothing of the simulator::

    detector = PartDetector()
    detection = detector.detect(camera.capture(), "red")
    if detection.found:
        print(detection.planar)
    else:
        print(detection.status, detection.reason)

See docs/perception.md.
"""

from typing import TYPE_CHECKING

from bt_arrange.deprecation import renamed_attributes
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.perception.corners import CornerRefinement
from bt_arrange.perception.depth_grasp import DepthGraspConfig, DepthGraspEstimator
from bt_arrange.perception.detection import (
    Detection,
    DetectionStatus,
    DetectorConfig,
    PartDetector,
    WorldRegion,
)
from bt_arrange.perception.outline_unknown import (
    MeasuredOutline,
    measure_unknown_outlines,
    measure_unknown_outlines_in_mask,
)
from bt_arrange.perception.pose import PoseModel

__all__ = [
    "DEFAULT_COLOUR_TABLE",
    "ColourRange",
    "ColourTable",
    "CornerRefinement",
    "DepthGraspConfig",
    "DepthGraspEstimator",
    "Detection",
    "DetectionStatus",
    "DetectorConfig",
    "MeasuredOutline",
    "PartDetector",
    "PoseModel",
    "WorldRegion",
    "measure_unknown_outlines",
    "measure_unknown_outlines_in_mask",
]

# Deprecated: the names that said "cube" for any part, kept one release (CHANGELOG.md).
if TYPE_CHECKING:
    CubeDetector = PartDetector
else:
    __getattr__ = renamed_attributes(__name__, {"CubeDetector": "PartDetector"})
