"""CheckStanding: a raised part stands on its support, level, at its height.

After the Inspect of a raised part (``z_m`` above the table, measured on its own top face's plane)
the camera's depth says whether it really lies there: its top face's plane
(``bt_arrange.perception.standing``) must be level within ``max_tilt_deg`` and at ``z_m`` plus
its height within ``height_tolerance_m``. A part tipped over an edge of its support, or fallen
to the table or onto a lower layer, fails here, naming how far off and how tilted it is, so a
tree neither pushes a part that is not where the colour detection put it nor builds on it.
"""

from __future__ import annotations

import math

from bt_arrange.behaviours import keys
from bt_arrange.behaviours.base import InstantStage, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import OBJ, OBJECT_TYPE_PORT, Z_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.looking import is_parked, park_stage
from bt_arrange.errors import PerceptionError
from bt_arrange.geometry import Pose
from bt_arrange.numbers import fixed
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.standing import TopFace, measure_top_face
from bt_arrange.ports import DOUBLE, Port

#: The top face may lie this far (m) above or below where the plan puts it: the depth's own error
#: averaged over the face (sub-millimetre in the simulated cell), a support's own placing tilt, and
#: less than any fall (a part off its support drops by a whole layer).
STANDING_HEIGHT_TOLERANCE_M = 0.003
#: A part tilted more than this (deg) rests on an edge or a corner, not on its bottom face: a 5 cm
#: cube resting on a 1 mm step tilts about 1.1 deg.
STANDING_MAX_TILT_DEG = 2.0
#: Room (m) around the part for the depth window: the face and a little beyond it.
WINDOW_MARGIN_M = 0.01


class CheckStanding(StagedBehaviour):
    """Confirm from depth that the part (``/<obj>/pose``) stands level on its support at ``z_m``."""

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "depth -> /<obj>/top_height_error_mm, /<obj>/tilt_deg: does the raised part stand"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object, its type, its support's height and the tolerances (BehaviorTree.CPP's ``providedPorts``)."""
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            Z_PORT,
            Port("height_tolerance_m", DOUBLE, STANDING_HEIGHT_TOLERANCE_M, "the top face's height tolerance [m]"),
            Port("max_tilt_deg", DOUBLE, STANDING_MAX_TILT_DEG, "the most the top face may tilt [deg]"),
            *entries((keys.POSE,), (keys.TOP_HEIGHT_ERROR_MM, keys.TILT_DEG)),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        object_type: ObjectType | None = None,
        z_m: float = 0.0,
        height_tolerance_m: float = STANDING_HEIGHT_TOLERANCE_M,
        max_tilt_deg: float = STANDING_MAX_TILT_DEG,
    ) -> None:
        super().__init__(name)
        self.obj = obj
        self.object_type = object_type or CUBE
        self.z_m = float(z_m)
        self.height_tolerance_m = float(height_tolerance_m)
        self.max_tilt_deg = float(max_tilt_deg)
        self.reads(keys.key(obj, keys.POSE), written_by=f"Inspect of {obj}")
        self.writes(keys.key(obj, keys.TOP_HEIGHT_ERROR_MM), keys.key(obj, keys.TILT_DEG))
        self.face: TopFace | None = None

    @property
    def expected_top_m(self) -> float:
        """Where the top face should be (m above the table)."""
        return self.z_m + self.object_type.shape.height_m

    def stages(self, context: Context) -> list[Stage]:
        """Park if needed (the arm would hide the part), then measure."""
        measuring = InstantStage("measure the top face from depth", self._measure)
        return [measuring] if is_parked(context) else [park_stage(), measuring]

    def _measure(self, context: Context) -> str | None:
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Inspect of {self.obj}")
        camera = context.robot.camera
        detector = context.detector.for_object(self.object_type)
        x_m, y_m, _ = detector.config.size_m
        half_m = 0.5 * math.hypot(x_m, y_m) + WINDOW_MARGIN_M
        window = detector.window_around(camera.intrinsics, camera.pose_world, pose.x_m, pose.y_m, half_m)
        frame = camera.capture(with_depth=True, window=window)
        try:
            self.face = face = measure_top_face(frame, pose, self.object_type.shape, self.expected_top_m)
        except PerceptionError as error:
            return f"{self.obj}: {error}"
        error_mm = (face.height_m - self.expected_top_m) * 1000
        self.write(keys.key(self.obj, keys.TOP_HEIGHT_ERROR_MM), error_mm)
        self.write(keys.key(self.obj, keys.TILT_DEG), face.tilt_deg)
        if abs(error_mm) > self.height_tolerance_m * 1000:
            how = "fallen" if error_mm < 0 else "resting on something"
            return (
                f"{self.obj} does not stand on its support: its top face lies at {face.height_m * 1000:.1f} mm, "
                f"{abs(error_mm):.1f} mm {'below' if error_mm < 0 else 'above'} the {self.expected_top_m * 1000:.1f} "
                f"mm it should ({how}; tilted {face.tilt_deg:.1f} deg)"
            )
        if face.tilt_deg > self.max_tilt_deg:
            return (
                f"{self.obj} is tipped: its top face tilts {face.tilt_deg:.1f} deg, more than {self.max_tilt_deg:g} "
                f"deg (at {face.height_m * 1000:.1f} mm, {fixed(error_mm, 1, sign=True)} mm from its height)"
            )
        return None

    def success_message(self) -> str:
        """Feedback with the measured height and tilt."""
        assert self.face is not None
        error_mm = (self.face.height_m - self.expected_top_m) * 1000
        return (
            f"{self.obj} stands on its support: top face {fixed(error_mm, 2, sign=True)} mm "
            f"from {self.expected_top_m * 1000:.0f} mm, tilted {self.face.tilt_deg:.2f} deg "
            f"({self.face.samples} depth pixels)"
        )
