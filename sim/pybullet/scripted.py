"""Pick, place and push a cube told by ground truth: a yardstick for the cell, not the task.

The benchmark of the work cell and its integration tests use it to measure what the arm, the
gripper and the physics can do before perception enters. It runs the very behaviours an
arrangement tree runs (``Pick``, ``Place``, ``Push``), each as a one-node tree on the world's
clock, with the cube's true pose written to the blackboard where ``Detect`` would write the
camera's. The ticking is ``bt_arrange.behaviour_run.BehaviourRun``'s: the cell supplies a world
(``SimWorld``), never a runner of its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import py_trees
from py_trees.common import Status

from bt_arrange.behaviour_run import BehaviourRun
from bt_arrange.behaviours import Context, MoveStage, Pick, Place, Push, StagedBehaviour, keys
from bt_arrange.errors import BtArrangeError
from bt_arrange.geometry import PlanarPose, Pose
from bt_arrange.motion import CartesianLimits, JointLimits
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.settings import ManipulationSettings
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.runs import SimWorld

#: The blackboard namespace of the cube the script handles.
OBJ = "cube"


@dataclass
class PickPlaceResult:
    """What one scripted pick measured (ground truth steered it; the robot saw nothing)."""

    grasped: bool
    grip_width_m: float
    sim_seconds: float
    feedback: str = ""


class _MoveTo(StagedBehaviour):
    """One joint-space move to a TCP pose."""

    def __init__(self, pose: Pose) -> None:
        super().__init__("move")
        self._pose = pose

    def stages(self, context: Context) -> list:  # noqa: D102
        return [MoveStage("move", lambda c, q: c.planner.move_to_pose(q, self._pose))]


class ScriptedPickPlace:
    """Runs the arrangement behaviours on one cell, one at a time, from ground-truth poses."""

    def __init__(
        self,
        cell: WorkCell,
        settings: ManipulationSettings | None = None,
        joint_limits: JointLimits | None = None,
        cartesian_limits: CartesianLimits | None = None,
        time_limit_s: float = 60.0,
        object_type: ObjectType = CUBE,
    ) -> None:
        self.cell = cell
        self._behaviours = BehaviourRun(
            SimWorld(cell),
            settings=settings,
            joint_limits=joint_limits,
            cartesian_limits=cartesian_limits,
            time_limit_s=time_limit_s,
        )
        #: The behaviours' context (the cell's robot, the kinematics and limits), shared by every step.
        self.context: Context = self._behaviours.context
        self.time_limit_s = time_limit_s
        #: The type of the part handled (default the paper's cube).
        self.object_type = object_type
        self._blackboard = py_trees.blackboard.Client(name="ground truth")
        for field in (keys.POSE, keys.TARGET, keys.OFFSET_XY_MM, keys.PUSH_AXIS):
            self._blackboard.register_key(keys.key(OBJ, field), access=py_trees.common.Access.WRITE)

    def pick(self, x_m: float, y_m: float, yaw_rad: float) -> PickPlaceResult:
        """Grasp a cube resting at (x, y, yaw) and lift it (``Pick``)."""
        self._write(keys.POSE, Pose.from_planar(x_m, y_m, yaw_rad, z_m=self.object_type.shape.height_m / 2))
        pick = Pick("pick", OBJ, self.object_type)
        status, seconds = self._run(pick)
        width = pick.grip_width_m if pick.grip_width_m is not None else self.cell.gripper.width()
        return PickPlaceResult(status == Status.SUCCESS, width, seconds, pick.feedback_message)

    def place(self, x_m: float, y_m: float, yaw_rad: float) -> float:
        """Carry the held cube to (x, y, yaw), lower it, release it, retreat (``Place``); returns sim seconds."""
        self._write(keys.TARGET, PlanarPose(x_m, y_m, yaw_rad))
        return self._expect_success(Place("place", OBJ, self.object_type))

    def push(self, x_m: float, y_m: float, axis: str, distance_m: float) -> float:
        """Push a cube resting at (x, y) by ``distance_m`` along world ``axis`` (``Push``); returns sim seconds."""
        if axis not in ("x", "y"):
            raise ValueError(f"push axis must be 'x' or 'y', got {axis!r}")
        dx_m, dy_m = (distance_m, 0.0) if axis == "x" else (0.0, distance_m)
        self._write(keys.POSE, Pose.from_planar(x_m, y_m, 0.0, z_m=CUBE.shape.height_m / 2))
        self._write(keys.TARGET, PlanarPose(x_m + dx_m, y_m + dy_m, 0.0))
        self._write(keys.OFFSET_XY_MM, (dx_m * 1000, dy_m * 1000))
        self._write(keys.PUSH_AXIS, axis)
        return self._expect_success(Push("push", OBJ))

    def push_along(self, x_m: float, y_m: float, yaw_rad: float, heading_rad: float, distance_m: float) -> str:
        """Push a part of ``object_type`` resting at (x, y, yaw) by ``distance_m`` along ``heading_rad``.

        The heading is in the part's frame (the target keeps its yaw); a prism is pushed squarely
        onto the edge whose push best closes it (``Push``). Returns the push's feedback.
        """
        c, s = math.cos(yaw_rad + heading_rad), math.sin(yaw_rad + heading_rad)
        self._write(keys.POSE, Pose.from_planar(x_m, y_m, yaw_rad, z_m=self.object_type.shape.height_m / 2))
        self._write(keys.TARGET, PlanarPose(x_m + distance_m * c, y_m + distance_m * s, yaw_rad))
        offset_mm = (distance_m * 1000 * math.cos(heading_rad), distance_m * 1000 * math.sin(heading_rad))
        self._write(keys.OFFSET_XY_MM, offset_mm)
        self._write(keys.PUSH_AXIS, "x")
        push = Push("push", OBJ, object_type=self.object_type)
        self._expect_success(push)
        return push.feedback_message

    def move_to(self, pose: Pose) -> float:
        """A joint-space move of the TCP to ``pose``; returns sim seconds."""
        return self._expect_success(_MoveTo(pose))

    def _write(self, field: str, value: object) -> None:
        self._blackboard.set(keys.key(OBJ, field), value, overwrite=True)

    def _run(self, behaviour: py_trees.behaviour.Behaviour) -> tuple[Status, float]:
        result = self._behaviours.run(behaviour)
        return result.status, result.sim_seconds

    def _expect_success(self, behaviour: py_trees.behaviour.Behaviour) -> float:
        status, seconds = self._run(behaviour)
        if status != Status.SUCCESS:
            raise BtArrangeError(f"{behaviour.name} ended {status.value}: {behaviour.feedback_message}")
        return seconds
