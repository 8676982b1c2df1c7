"""LookAtHeld: measure a held part's place in the pads with the top camera, for Place to correct the placing."""

from __future__ import annotations

import math

import numpy as np

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.common_ports import COLOUR, OBJ, OBJECT_TYPE_PORT, entries
from bt_arrange.behaviours.context import Context
from bt_arrange.behaviours.moves import free_grasp_pose, heights_m, to_pose, wrist_yaw_rad
from bt_arrange.geometry import PlanarPose, Pose, fold_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.held import HeldMeasurement, measure_held
from bt_arrange.perception.outline_fit import OutlineModel
from bt_arrange.perception.pose import project_world
from bt_arrange.ports import BOOL, Port
from bt_arrange.robot import PixelWindow

#: Where the held part is looked at: this far (m) beside the camera's axis, on the side of the pick
#: (+y or -y of the camera), the TCP this high (m). Measured in the fresco's cell: there the
#: gripper's body and the wrist stand beside the part in the image, not over all of it; under the
#: camera, and above the pick, they hide it whole. (Between the camera's axis and the base, 0.2 m
#: towards it and 0.12 m aside, the first look saw more pieces, 19 of 20 over seeds 0 to 3, but the
#: pieces took 8.10 s each against 7.70 s here: a longer way round and more pushes.)
LOOK_OFFSET_M = 0.3
LOOK_TCP_Z_M = 0.12
#: Half the side (m) of the square around the part's expected place the camera renders for the look.
LOOK_HALF_SIZE_M = 0.075


def compose(a: PlanarPose, b: PlanarPose) -> PlanarPose:
    """``a`` then ``b`` (``b`` in ``a``'s frame)."""
    c, s = math.cos(a.yaw_rad), math.sin(a.yaw_rad)
    return PlanarPose(a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m, a.yaw_rad + b.yaw_rad)


def relative(a: PlanarPose, b: PlanarPose) -> PlanarPose:
    """``b`` in ``a``'s frame."""
    c, s = math.cos(a.yaw_rad), math.sin(a.yaw_rad)
    dx, dy = b.x_m - a.x_m, b.y_m - a.y_m
    return PlanarPose(c * dx + s * dy, -s * dx + c * dy, b.yaw_rad - a.yaw_rad)


def inverse(a: PlanarPose) -> PlanarPose:
    """The inverse transform of ``a``."""
    return relative(a, PlanarPose(0.0, 0.0, 0.0))


def look_pose(
    camera_xy: tuple[float, float], pick: PlanarPose, wrist_rad: float, quarter_turn: bool = False
) -> tuple[float, float, float]:
    """The TCP's (x, y, yaw) for the look: beside the camera on the pick's side, the wrist turned least.

    The pads close along x (of the two ways round, the one nearer the wrist's yaw): the UR5's wrist
    then stands clear of the part in the image. Over the fresco at seeds 0 to 3 a first look so saw
    17 of 17 pieces on either side; with the pads along y on the -y side, 2 of 10.
    ``quarter_turn``: the pads a quarter turn from that, a second look where the first saw too little.
    """
    side = 1.0 if pick.y_m >= camera_xy[1] else -1.0
    base = math.pi / 2 if quarter_turn else 0.0
    yaw = min((base, base + math.pi), key=lambda y: abs(fold_yaw(y - wrist_rad, 2 * math.pi)))
    yaw = wrist_rad + fold_yaw(yaw - wrist_rad, 2 * math.pi)
    return camera_xy[0], camera_xy[1] + side * LOOK_OFFSET_M, yaw


class LookAtHeld(StagedBehaviour):
    """Move the held part where the top camera sees it beside the gripper, and measure its place in the pads.

    After Pick: the part's expected place in the pads follows from the pose it was picked at
    (``/<obj>/pose``) and the grasp; the camera's frame (with depth) gives its outline where the
    gripper leaves it in view (``bt_arrange.perception.held``). A trusted measurement writes
    ``/<obj>/held_correction``, the turn and shift of the TCP that puts the part where Place's plan
    expects it, and ``/<obj>/held_look`` = ``"held look"``; an untrusted one (too little outline in
    view, a poor fit, too far from the grasp's expectation) fails with the reason, for the tree to
    set the part down and look at it on the table instead.
    """

    node_description = "measure the held part's place in the pads"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The object and its type (BehaviorTree.CPP's ``providedPorts``)."""
        return (
            OBJ,
            OBJECT_TYPE_PORT,
            COLOUR,
            Port("quarter_turn", BOOL, False, "the pads a quarter turn from the first look's", optional=True),
            *entries((keys.POSE, keys.GRASP_HALF_TURN), (keys.HELD_CORRECTION, keys.HELD_LOOK)),
        )

    def __init__(
        self,
        name: str,
        obj: str,
        colour: str | None = None,
        object_type: ObjectType | None = None,
        quarter_turn: bool = False,
    ) -> None:
        super().__init__(name)
        #: True: the pads a quarter turn from the first look's (``look_pose``).
        self.quarter_turn = bool(quarter_turn)
        self.obj = obj
        self.colour = colour or obj
        self.object_type = object_type or CUBE
        self.reads(keys.key(obj, keys.POSE), written_by=f"Detect of {obj}")
        self.reads(keys.key(obj, keys.GRASP_HALF_TURN))
        self.writes(keys.key(obj, keys.HELD_CORRECTION), keys.key(obj, keys.HELD_LOOK))
        self.measurement: HeldMeasurement | None = None
        self._expected_in_tcp = PlanarPose(0.0, 0.0, 0.0)

    def stages(self, context: Context) -> list[Stage]:
        """Move into the camera's view, then capture and measure."""
        pose: Pose = self.read(keys.key(self.obj, keys.POSE), f"Detect of {self.obj}")
        # Until a trusted measurement: the tree's fallback sets the part down.
        self.write(keys.key(self.obj, keys.HELD_CORRECTION), None)
        self.write(keys.key(self.obj, keys.HELD_LOOK), keys.SET_DOWN)
        self.measurement = None
        s = context.settings
        half_key = keys.key(self.obj, keys.GRASP_HALF_TURN)
        half_turn = bool(self.blackboard.get(half_key)) if self.blackboard.exists(half_key) else False
        picked = pose.planar()
        wrist = wrist_yaw_rad(context)
        gx, gy, gyaw = free_grasp_pose(s, self.object_type, picked.x_m, picked.y_m, picked.yaw_rad, wrist, half_turn)
        # Where the pick put the part in the pads, had the camera and the grasp been exact.
        self._expected_in_tcp = relative(PlanarPose(gx, gy, gyaw), picked)
        camera = context.robot.camera.pose_world.position_m
        x, y, yaw = look_pose((float(camera[0]), float(camera[1])), picked, wrist, self.quarter_turn)
        return [
            MoveStage(stage.MOVE_TO_HELD_LOOK, to_pose(x, y, LOOK_TCP_Z_M, yaw, carrying=True)),
            InstantStage(stage.MEASURE_HELD, self._measure),
        ]

    def _measure(self, context: Context) -> str | None:
        s = context.settings
        kind = self.object_type
        grasp_m, _, _ = heights_m(s, kind)
        tcp_pose = context.robot.arm.tcp_pose()
        tcp = tcp_pose.planar()
        plane_z_m = float(tcp_pose.position_m[2]) + kind.shape.height_m - grasp_m
        expected = compose(tcp, self._expected_in_tcp)
        camera = context.robot.camera
        intrinsics, T_W_C = camera.intrinsics, camera.pose_world
        h = LOOK_HALF_SIZE_M
        square = np.array(
            [[expected.x_m + dx, expected.y_m + dy, plane_z_m] for dx in (-h, h) for dy in (-h, h)], dtype=float
        )
        pixels = project_world(intrinsics, T_W_C, square)
        window = PixelWindow.covering(
            intrinsics, pixels[:, 0].min(), pixels[:, 1].min(), pixels[:, 0].max(), pixels[:, 1].max()
        )
        if window is None:
            return f"{self.obj} held outside the camera's view"
        frame = camera.capture(with_depth=True, window=window)
        colour = context.detector.colours.get(self.colour)
        if colour is None or frame.depth_m is None:
            missing = f"no colour {self.colour!r} in the plan's colour table" if colour is None else "no depth"
            return f"{self.obj} not measured in the fingers: {missing}"
        try:
            measured = measure_held(frame, colour, OutlineModel.of(kind), plane_z_m, expected)
        except (ValueError, np.linalg.LinAlgError) as error:  # a degenerate frame or fit: set it down instead
            return f"{self.obj} not measured in the fingers: {error}"
        self.measurement = measured
        if not measured.trusted or measured.pose is None:
            return f"{self.obj} not measured in the fingers: {measured.reason}"
        in_tcp = relative(tcp, measured.pose)
        turn = fold_yaw(in_tcp.yaw_rad - self._expected_in_tcp.yaw_rad, kind.shape.symmetry_rad)
        in_tcp = PlanarPose(in_tcp.x_m, in_tcp.y_m, self._expected_in_tcp.yaw_rad + turn)
        # Place's TCP pose T puts the part at T * expected; T * correction * measured is the same place.
        correction = compose(self._expected_in_tcp, inverse(in_tcp))
        self.write(keys.key(self.obj, keys.HELD_CORRECTION), correction)
        self.write(keys.key(self.obj, keys.HELD_LOOK), keys.LOOKED_IN_FINGERS)
        return None

    def success_message(self) -> str:
        """Feedback with the part's place in the pads against the grasp's."""
        m = self.measurement
        assert m is not None and m.pose is not None
        return (
            f"{self.obj} measured in the fingers ({m.edge_points} outline points, {m.rms_mm:.2f} mm RMS, "
            f"{m.sigma_mm:.2f} mm / {m.sigma_deg:.2f} deg)"
        )
