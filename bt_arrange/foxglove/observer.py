"""A session's run as Foxglove streams: one ``RunObserver`` logs to a ``foxglove.Context``.

The sinks of that context (``run.mcap``, the live WebSocket server, or both) get the same messages;
the observer only reads the world (the measured joints, the camera's own frames, the ground
truth for evaluation) and never acts on it. It hooks into a ``bt_arrange.session.Session``:

- ``runner_hooks``: before the first tick it wraps the context's camera (``TappedCamera``), so
  every frame the perception captures is logged as it is taken, and logs what never changes
  (``/robot_description``, ``/parts``);
- ``transition_hooks``: each status change (``/log`` for its feedback; ``/tree`` after the tick);
- ``tick_hooks``: ``/tree`` when a node changed, ``/tf`` and ``/offsets`` every ``TF_PERIOD_S``;
- ``finish(report)``: a last ``/tf`` (the final poses) and ``/report``.

Times are world time (the world's clock from 0 at its start) in nanoseconds, as the log time of
each message and in its own ``timestamp``.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import foxglove
import py_trees
from foxglove.channels import (
    CameraCalibrationChannel,
    CompressedImageChannel,
    FrameTransformsChannel,
    LogChannel,
    SceneUpdateChannel,
)
from foxglove.messages import (
    CameraCalibration,
    CompressedImage,
    FrameTransform,
    FrameTransforms,
    Log,
    LogLevel,
    Quaternion,
    SceneUpdate,
    Timestamp,
    Vector3,
)

from bt_arrange.foxglove import scene
from bt_arrange.foxglove.links import RobotLinks
from bt_arrange.groot2.publisher import preorder
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES, default_urdf_path
from bt_arrange.robot import CameraFrame, PixelWindow
from bt_arrange.xmltree import tag_of

#: The least world time between two ``/tf`` messages: a decimation of the control period (8 ms: every third), smooth
#: in the 3-D panel at a third of the size.
TF_PERIOD_S = 0.02
#: World time between two repeats of ``/robot_description`` and ``/parts`` when live: a live client
#: that connects after the start sees them too (the protocol keeps no message for late subscribers).
STATICS_PERIOD_S = 1.0
#: PNG compression level of ``/camera/image``: 1 is the fastest (the images stay lossless).
PNG_LEVEL = 1


def _ns(time_s: float) -> int:
    return max(0, round(time_s * 1e9))


def _stamp(time_s: float) -> Timestamp:
    ns = _ns(time_s)
    return Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def _observing(hook: Callable[..., None]) -> Callable[..., None]:
    """A hook that only observes: an error in it stops the recording (``failed``), never the run."""

    @functools.wraps(hook)
    def guarded(self: RunObserver, *args: Any) -> None:
        if self.failed is not None:
            return
        try:
            hook(self, *args)
        except Exception as error:  # noqa: BLE001 - whatever broke the recording, the run goes on
            self.failed = f"{type(error).__name__}: {error}"

    return guarded


class TappedCamera:
    """A camera that hands each frame it captures to the observer, unchanged, then to the caller."""

    def __init__(self, camera: Any, observer: RunObserver) -> None:
        self._camera = camera
        self._observer = observer

    @property
    def intrinsics(self) -> Any:
        """The wrapped camera's intrinsics."""
        return self._camera.intrinsics

    @property
    def pose_world(self) -> Any:
        """The wrapped camera's pose."""
        return self._camera.pose_world

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        """The wrapped camera's frame, logged on ``/camera/image`` and ``/camera/calibration``."""
        frame: CameraFrame = self._camera.capture(with_depth=with_depth, window=window)
        self._observer.on_frame(frame)
        return frame

    def __getattr__(self, name: str) -> Any:
        return getattr(self._camera, name)


class Channels:
    """The run's topics on one context, made before the world is built when live: a client subscribes before tick 1."""

    def __init__(self, context: foxglove.Context) -> None:
        self.image = CompressedImageChannel("/camera/image", context=context)
        self.calibration = CameraCalibrationChannel("/camera/calibration", context=context)
        self.tf = FrameTransformsChannel("/tf", context=context)
        self.robot_description = foxglove.Channel(
            "/robot_description", schema=scene.URDF_SCHEMA, message_encoding="json", context=context
        )
        self.parts = SceneUpdateChannel("/parts", context=context)
        self.tree = foxglove.Channel("/tree", schema=scene.TREE_SCHEMA, message_encoding="json", context=context)
        self.log = LogChannel("/log", context=context)
        self.report = foxglove.Channel("/report", schema=scene.REPORT_SCHEMA, message_encoding="json", context=context)
        self.offsets = foxglove.Channel(
            "/offsets", schema=scene.OFFSETS_SCHEMA, message_encoding="json", context=context
        )


class RunObserver:
    """Logs one session's run to ``context`` (see the module's text); attach it with ``attach(session)``."""

    def __init__(self, session: Any, channels: Channels, *, urdf_path: Path | None = None, server: Any = None) -> None:
        self.session = session
        #: Why the recording stopped (an error in a hook), or None: the run goes on, the file is not written.
        self.failed: str | None = None
        #: The live server (``--foxglove``), or None: it is told the world time, and late clients get the statics.
        self.server = server
        self._last_statics_s = -math.inf
        self.urdf_path = urdf_path or default_urdf_path()
        self.links = RobotLinks(self.urdf_path)
        self.image, self.calibration, self.tf = channels.image, channels.calibration, channels.tf
        self.robot_description, self.parts, self.tree = channels.robot_description, channels.parts, channels.tree
        self.log, self.report, self.offsets = channels.log, channels.report, channels.offsets
        self._row_of: dict[str, dict[str, Any]] = {}
        self._read_tree()
        self._tree_changed = False
        self._last_tf_s = -math.inf
        #: The camera perception uses (set before the first tick), and how many targets the scene drew.
        self._camera: Any = None
        self._scene_targets = 0
        self._last_time_ns = 0
        #: Messages logged per topic (for the benchmark and the tests).
        self.counts: dict[str, int] = {}

    # -- hooks -----------------------------------------------------------------------------

    def attach(self) -> RunObserver:
        """Add the observer's hooks to its session."""
        self.session.runner_hooks.append(self.on_runner)
        self.session.transition_hooks.append(self.on_transition)
        self.session.tick_hooks.append(self.on_tick)
        return self

    def now_ns(self) -> int:
        """World time now, never before a message already logged (MCAP readers expect order)."""
        self._last_time_ns = max(self._last_time_ns, _ns(self.session.world.clock.now()))
        return self._last_time_ns

    def _count(self, topic: str) -> None:
        self.counts[topic] = self.counts.get(topic, 0) + 1

    @_observing
    def on_runner(self, runner: Any) -> None:
        """Before the first tick: tap the camera, log what never changes and the first poses."""
        context = runner.context
        context.robot = dataclasses.replace(context.robot, camera=TappedCamera(context.robot.camera, self))
        # The camera perception uses (calibrated when the run is): its pose is the one /tf carries.
        self._camera = context.robot.camera
        self._urdf_text = self.urdf_path.read_text(encoding="utf-8")
        self._scene_update = self._scene()
        time_ns = self.now_ns()
        self._publish_statics(time_ns)
        self._publish_tree(time_ns)
        self._publish_tf(time_ns)

    def _publish_statics(self, time_ns: int) -> None:
        self._last_statics_s = time_ns / 1e9
        self.robot_description.log({"data": self._urdf_text}, log_time=time_ns)
        self._count("/robot_description")
        self.parts.log(self._scene_update, log_time=time_ns)
        self._count("/parts")

    @_observing
    def on_transition(self, transition: Any) -> None:
        """A status change: the node's row for ``/tree``, its feedback on ``/log``."""
        row = self._row_of.get(transition.node_id)
        if row is None:  # a node built while the tree runs (a solved puzzle's pieces): the tree has grown
            self._read_tree()
            row = self._row_of.get(transition.node_id)
        if row is not None:
            row["status"] = transition.new
            self._tree_changed = True
        if transition.feedback and transition.new in ("SUCCESS", "FAILURE"):
            level = LogLevel.Warning if transition.new == "FAILURE" else LogLevel.Info
            time_ns = self.now_ns()
            self.log.log(
                Log(
                    timestamp=_stamp(time_ns / 1e9), level=level, message=transition.feedback, name=transition.behaviour
                ),
                log_time=time_ns,
            )
            self._count("/log")

    @_observing
    def on_tick(self, root: py_trees.behaviour.Behaviour) -> None:
        """After a tick: ``/tree`` if a node changed, ``/tf`` once per ``TF_PERIOD_S`` of world time."""
        time_ns = self.now_ns()
        plan = getattr(self.session, "plan", None)
        if plan is not None and len(plan.targets) != self._scene_targets:
            # Parts that join the plan as it runs (a puzzle's pieces, once solved): the scene again.
            self._scene_update = self._scene()
            self._publish_statics(time_ns)
        if self._tree_changed:
            self._publish_tree(time_ns)
        if time_ns / 1e9 - self._last_tf_s >= TF_PERIOD_S - 1e-9:
            self._publish_tf(time_ns)
            if self.server is not None:
                self.server.broadcast_time(time_ns)
                if time_ns / 1e9 - self._last_statics_s >= STATICS_PERIOD_S:
                    self._publish_statics(time_ns)

    @_observing
    def on_frame(self, frame: CameraFrame) -> None:
        """A frame the perception captured: its image as PNG, and the intrinsics it was taken with."""
        ok, png = cv2.imencode(
            ".png", cv2.cvtColor(frame.rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_PNG_COMPRESSION, PNG_LEVEL]
        )
        if not ok:
            return
        time_ns = self.now_ns()
        stamp = _stamp(time_ns / 1e9)
        self.image.log(
            CompressedImage(timestamp=stamp, frame_id=scene.CAMERA_FRAME, data=png.tobytes(), format="png"),
            log_time=time_ns,
        )
        self._count("/camera/image")
        k = frame.intrinsics
        fx, fy, cx, cy = k.fx_px, k.fy_px, k.cx_px, k.cy_px
        self.calibration.log(
            CameraCalibration(
                timestamp=stamp,
                frame_id=scene.CAMERA_FRAME,
                width=k.width_px,
                height=k.height_px,
                distortion_model="plumb_bob",
                D=[float(v) for v in k.distortion],
                K=[fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
                R=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                P=[fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
            ),
            log_time=time_ns,
        )
        self._count("/camera/calibration")

    @_observing
    def finish(self, report: Any) -> None:
        """At the end: the last ``/tree`` and ``/tf`` (the final poses), then ``/report``."""
        time_ns = self.now_ns()
        # A run stopped at its time limit resets its nodes without reporting each change: read them.
        for node, row in zip(self.nodes, self._node_rows, strict=True):
            if row["status"] != node.status.value:
                row["status"] = node.status.value
                self._tree_changed = True
        if self._tree_changed:
            self._publish_tree(time_ns)
        self._publish_tf(time_ns)
        self.report.log(report.to_dict(), log_time=time_ns)
        self._count("/report")

    # -- messages --------------------------------------------------------------------------

    def _read_tree(self) -> None:
        """The tree's nodes and their ``/tree`` rows, top-down; a node seen before keeps its row (and status)."""
        self.nodes = preorder(self.session.root)
        rows = []
        for uid, node in enumerate(self.nodes, 1):
            known = self._row_of.get(str(node.id))
            row = known or {"type": tag_of(node), "name": node.name, "status": node.status.value}
            rows.append({"uid": uid, **{k: v for k, v in row.items() if k != "uid"}})
        self._node_rows = rows
        self._row_of = {str(node.id): row for node, row in zip(self.nodes, rows, strict=True)}

    def _publish_tree(self, time_ns: int) -> None:
        self._tree_changed = False
        name = self.session.root.name
        self.tree.log({"time_s": time_ns / 1e9, "tree": name, "nodes": self._node_rows}, log_time=time_ns)
        self._count("/tree")

    def _publish_tf(self, time_ns: int) -> None:
        self._last_tf_s = time_ns / 1e9
        stamp = _stamp(self._last_tf_s)
        world = self.session.world
        robot = world.robot
        positions = dict(zip(ARM_JOINT_NAMES, (float(q) for q in robot.arm.joint_positions()), strict=False))
        finger_m = float(robot.gripper.width()) / 2  # each pad's distance from the centre
        positions.update(dict.fromkeys(FINGER_JOINT_NAMES, finger_m))

        def transform(parent: str, child: str, translation: Any, rotation: Any) -> FrameTransform:
            return FrameTransform(
                timestamp=stamp,
                parent_frame_id=parent,
                child_frame_id=child,
                translation=Vector3(x=float(translation[0]), y=float(translation[1]), z=float(translation[2])),
                rotation=Quaternion(
                    x=float(rotation[0]), y=float(rotation[1]), z=float(rotation[2]), w=float(rotation[3])
                ),
            )

        # The framework's kinematics put the base at the world origin (ArmKinematics' default).
        transforms = [transform(scene.WORLD_FRAME, self.links.base_link, (0, 0, 0), (0, 0, 0, 1))]
        transforms += [transform(*joint) for joint in self.links.transforms(positions)]
        camera = (self._camera if self._camera is not None else robot.camera).pose_world
        transforms.append(transform(scene.WORLD_FRAME, scene.CAMERA_FRAME, camera.position_m, camera.quaternion_xyzw))
        offsets = []
        for name, position, quaternion in self._part_poses():
            transforms.append(transform(scene.WORLD_FRAME, name, position, quaternion))
            target = self._targets.get(name)
            if target is not None:
                offsets.append(
                    {"name": name, "offset_mm": math.hypot(position[0] - target.x_m, position[1] - target.y_m) * 1000}
                )
        self.tf.log(FrameTransforms(transforms=transforms), log_time=time_ns)
        self._count("/tf")
        if offsets:
            self.offsets.log({"time_s": self._last_tf_s, "parts": offsets}, log_time=time_ns)
            self._count("/offsets")

    @property
    def _targets(self) -> dict[str, Any]:
        plan = getattr(self.session, "plan", None)
        return {t.obj: t for t in plan.targets} if plan is not None else {}

    def _part_poses(self) -> list[tuple[str, Any, Any]]:
        """Each part's true pose (evaluation only): the world's full pose where it has one, else planar on the table.

        A puzzle's piece is named as the plan names it once surveyed (``slab 3`` is the world's
        ``slab fragment 5``), so its scene entity follows it; every other part has the plan's name.
        """
        truth = self.session.truth
        if truth is None:
            return []
        full = getattr(truth, "pose_truth", None)
        puzzle_truth = getattr(self.session, "puzzle_truth", None)
        shown = {world: name for name, world in puzzle_truth.parts.items()} if puzzle_truth is not None else {}
        poses = []
        for world_name in truth.part_names():
            name = shown.get(world_name, world_name)
            if full is not None:
                pose = full(world_name)
                poses.append((name, pose.position_m, pose.quaternion_xyzw))
                continue
            x, y, yaw = truth.planar_pose(world_name)
            target = self._targets.get(name)
            half_m = float(target.object_type.shape.height_m) / 2 if target is not None else 0.0
            poses.append((name, (x, y, half_m), scene.yaw_quaternion(yaw)))
        return poses

    def _scene(self) -> SceneUpdate:
        entities = []
        targets = self._targets
        for target in targets.values():
            shape = target.object_type.shape
            rgb = self.session.colours[target.colour].paint_rgb
            entities.append(scene.part_entity(target.obj, shape, rgb))
            entities.append(scene.target_entity(target.obj, shape, rgb, target.x_m, target.y_m, target.yaw_rad))
        self._scene_targets = len(targets)
        return SceneUpdate(entities=entities)


def report_json(report: Any) -> str:
    """The report as ``/report`` carries it (for the tests)."""
    return json.dumps(report.to_dict())
