"""EstimateGraspFromDepth: the paper's Table 1 row 4 with a SUBSTITUTE grasp pose estimator.

In the paper's fourth experiment the object pose estimation before picking (Algorithm 1,
line 6) was replaced with the learned 6-DoF grasp pose estimator of Berscheid et al., whose
weights are not available. :class:`EstimateGraspFromDepth` takes Detect's place before Pick
with :class:`~bt_arrange.perception.depth_grasp.DepthGraspEstimator`, a geometric estimator on
the depth image alone (colour-blind, with seeded sensor noise); see that module for what it does
and the size of its errors. Inspection after placing and the pushes still use the colour
detector, as in the paper.

``bt_arrange.trees.transfer(target, locate=by_depth(seed))`` builds the transfer with this
behaviour instead of Detect (``arrange_one`` and ``arrangement`` take the same ``locate``)::

    Retry "pick and place red"
    └── Sequence "transfer red"
        ├── EstimateGraspFromDepth "estimate red grasp from depth"   depth camera -> /red/pose
        ├── Pick "pick red"
        └── GraspGuard "while holding red"
            └── Place "place red"
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, Stage, StagedBehaviour
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.looking import is_parked, park_stage
from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose
from bt_arrange.numbers import fixed
from bt_arrange.perception.depth_grasp import SOURCE, DepthGraspEstimator


def _checked_hint(near_xy_m: object) -> tuple[float, float] | None:
    if near_xy_m is None:
        return None
    try:
        x, y = (float(v) for v in near_xy_m)  # type: ignore[attr-defined]
    except (TypeError, ValueError) as error:
        raise PlanError(f"near_xy_m={near_xy_m!r} must be an (x, y) pair in metres, or None") from error
    if not (math.isfinite(x) and math.isfinite(y)):
        raise PlanError(f"near_xy_m={near_xy_m!r} must be finite")
    return x, y


class EstimateGraspFromDepth(StagedBehaviour):
    """Estimate the object's grasp pose from the top camera's depth image and write ``/<obj>/pose``.

    A drop-in for :class:`~bt_arrange.behaviours.looking.Detect` before Pick: the arm first moves
    out of the camera's view when it is not parked, then the camera's frame with depth is handed
    to the estimator (a substitute for Berscheid et al.'s learned estimator), which renders only
    the part of it where something stands (``DepthGraspEstimator.estimate_from``). Nothing
    found, an ambiguous or partial blob: FAILURE with the estimator's reason.

    The estimator is colour-blind: ``colour`` is accepted for symmetry with Detect and appears
    in messages only. Among several parts it takes the blob nearest ``near_xy_m`` (world metres)
    when given, else the largest (arbitrary among equal parts: give a hint when several parts
    are in view). ``seed`` seeds the depth noise; the stream restarts at every ``setup()``, so a
    tree set up afresh draws the same noise.
    """

    def __init__(
        self,
        name: str,
        obj: str,
        colour: str | None = None,
        estimator: DepthGraspEstimator | None = None,
        near_xy_m: tuple[float, float] | None = None,
        seed: int = 0,
    ) -> None:
        super().__init__(name)
        self.obj = obj
        self.colour = colour or obj
        self.estimator = estimator or DepthGraspEstimator()
        self.near_xy_m = _checked_hint(near_xy_m)
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.writes(keys.key(obj, keys.POSE))
        self.found: Pose | None = None

    def setup(self, **kwargs: Any) -> None:
        """Receive the context and restart the noise stream from ``seed``."""
        super().setup(**kwargs)
        self.rng = np.random.default_rng(self.seed)

    def stages(self, context: Context) -> list[Stage]:
        """Park if needed, then capture with depth and estimate."""
        estimating = InstantStage(stage.estimate_from_depth(self.obj), self._estimate)
        return [estimating] if is_parked(context) else [park_stage(), estimating]

    def _estimate(self, context: Context) -> str | None:
        estimate = self.estimator.estimate_from(context.robot.camera, self.near_xy_m, self.rng, name=self.obj)
        if not estimate.found or estimate.pose_world is None:
            return f"{self.obj} {estimate.status.value}: {estimate.reason}"
        self.found = estimate.pose_world
        self.write(keys.key(self.obj, keys.POSE), estimate.pose_world)
        return None

    def success_message(self) -> str:
        """Feedback with the estimated grasp pose, labelled as the substitute it is."""
        assert self.found is not None
        planar = self.found.planar()
        return (
            f"{self.obj} grasp at x={fixed(planar.x_m, 4)} m, y={fixed(planar.y_m, 4)} m, "
            f"yaw={fixed(math.degrees(planar.yaw_rad))} deg ({SOURCE})"
        )
