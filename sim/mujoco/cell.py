"""The work cell in MuJoCo: the pybullet cell's table, robot, parts, camera and clock in a second engine.

``MujocoCell`` takes the engine-neutral ``CellConfig`` (``bt_arrange_sim.config``: time step and control
period, gravity, the table, the camera's intrinsics and pose, the friction coefficients, the gripper's speeds and
forces) and MuJoCo's own ``MujocoPhysics`` (the contact model and the servos, ``model``). Its
methods for ground truth and error injection have the names and meanings of ``WorkCell``'s, so
the injectors of ``bt_arrange_sim.injection`` act on either (``injection.framework.InjectableCell``).

A compiled MuJoCo model has a fixed set of bodies: adding or removing a part builds the model
again (``_rebuild``) with the robot's and every other part's state carried over; a run places its
parts once, before the tree starts.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES, TCP_FRAME
from bt_arrange.objects import CUBE, DEFAULT_PART_FRICTION, ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.robot import Robot
from bt_arrange_sim.cell_base import CellBase
from bt_arrange_sim.config import HOME_Q, CellConfig
from bt_arrange_sim.mujoco import model as cell_model
from bt_arrange_sim.mujoco.devices import MujocoArm, MujocoCamera, MujocoClock, MujocoGripper, _xyzw
from bt_arrange_sim.mujoco.model import FINGER_BODIES, MujocoPhysics, PartSpec
from bt_arrange_sim.noise import CameraNoise
from bt_arrange_sim.parts import paint_of


class MujocoCell(CellBase):
    """One MuJoCo work cell: model, data, devices and parts. Headless; ``close`` frees the renderer."""

    ARM_JOINTS = ARM_JOINT_NAMES
    FINGER_JOINTS = FINGER_JOINT_NAMES

    def __init__(self, config: CellConfig | None = None, physics: MujocoPhysics | None = None) -> None:
        self.config = config or CellConfig()
        if self.config.errors.enabled or self.config.board is not None:
            raise PlanError("the MuJoCo cell is the ideal cell: a real cell's errors and the board are pybullet's")
        self.mujoco_physics = physics or MujocoPhysics()
        self._substeps = self.config.physics.substeps
        self._steps = 0
        self._parts: dict[str, PartSpec] = {}
        #: Each part's body id, by name (``WorkCell.parts``' meaning).
        self.parts: dict[str, int] = {}
        self.object_types: dict[str, ObjectType] = {}
        self.colours: ColourTable = DEFAULT_COLOUR_TABLE
        self.grasp_offset_m = 0.0
        self.camera_noise = CameraNoise(self.config.camera_noise)
        self.clock = MujocoClock(self)
        self._pad_friction = self.config.physics.pad_contact.lateral_friction
        self.model: Any = None
        self.data: Any = None
        self.camera: MujocoCamera | None = None  # type: ignore[assignment]
        self._build(carry=None)
        self.arm.reset(HOME_Q)
        self.gripper.reset(self.gripper.max_width_m)

    # -- building ---------------------------------------------------------------------------

    def _build(self, carry: dict[str, Any] | None) -> None:
        """Compile the model with the current parts; ``carry`` is the old state to keep (robot and parts)."""
        import mujoco

        spec = cell_model.build_spec(self.config, self.mujoco_physics, list(self._parts.values()))
        model = spec.compile()
        cell_model.finish_model(model, self.config, self.mujoco_physics, HOME_Q)
        data = mujoco.MjData(model)
        if self.camera is not None:
            self.camera.close()
        self.model, self.data = model, data
        self.parts = {name: model.body(name).id for name in self._parts}
        self.tcp_body = model.body(TCP_FRAME).id
        self.finger_joint_indices = tuple(model.joint(n).id for n in self.FINGER_JOINTS)
        self._finger_body = {
            model.joint(n).id: model.body(b).id for n, b in zip(self.FINGER_JOINTS, FINGER_BODIES, strict=True)
        }
        mode = carry.get("gripper_mode") if carry else None
        self.arm = MujocoArm(self)
        self.gripper = MujocoGripper(self)
        self.camera = MujocoCamera(self)
        if carry is not None:
            for joint in (*self.ARM_JOINTS, *self.FINGER_JOINTS):
                data.qpos[model.joint(joint).qposadr[0]] = carry["qpos"][joint]
                data.qvel[model.joint(joint).dofadr[0]] = carry["qvel"][joint]
            for name, (qpos, qvel) in carry["parts"].items():
                if name in self.parts:
                    joint = model.joint(f"{name}_free")
                    data.qpos[joint.qposadr[0] : joint.qposadr[0] + 7] = qpos
                    data.qvel[joint.dofadr[0] : joint.dofadr[0] + 6] = qvel
            data.ctrl[: len(carry["ctrl"])] = carry["ctrl"]
            model.actuator_gainprm[:] = carry["gainprm"]
            model.actuator_biasprm[:] = carry["biasprm"]
            if mode is not None:
                self.gripper._mode = mode
            self.arm.command(*carry["arm_setpoint"])
            self._apply_pad_friction()
        self._fresh = False

    def _state(self) -> dict[str, Any]:
        model, data = self.model, self.data
        joints = (*self.ARM_JOINTS, *self.FINGER_JOINTS)
        parts = {}
        for name in self.parts:
            joint = model.joint(f"{name}_free")
            parts[name] = (
                data.qpos[joint.qposadr[0] : joint.qposadr[0] + 7].copy(),
                data.qvel[joint.dofadr[0] : joint.dofadr[0] + 6].copy(),
            )
        return {
            "qpos": {j: float(data.qpos[model.joint(j).qposadr[0]]) for j in joints},
            "qvel": {j: float(data.qvel[model.joint(j).dofadr[0]]) for j in joints},
            "parts": parts,
            "ctrl": data.ctrl.copy(),
            "gainprm": model.actuator_gainprm.copy(),
            "biasprm": model.actuator_biasprm.copy(),
            "gripper_mode": self.gripper._mode,
            "arm_setpoint": self.arm.setpoint,
        }

    def _rebuild(self) -> None:
        self._build(self._state())

    # -- world -----------------------------------------------------------------------------

    @property
    def robot(self) -> Robot:
        """The cell's devices behind the interfaces behaviours use."""
        assert self.camera is not None
        return Robot(arm=self.arm, gripper=self.gripper, camera=self.camera, clock=self.clock)

    def step(self, control_periods: int = 1) -> None:
        """Advance the world by whole control periods (each ``substeps`` physics steps)."""
        import mujoco

        model, data = self.model, self.data
        for _ in range(control_periods):
            self.gripper.update()
            for substep in range(self._substeps):
                self.arm.interpolate(substep)
                mujoco.mj_step(model, data)
        self._steps += control_periods * self._substeps
        self._fresh = False

    def forward(self) -> None:
        """Bring positions, contacts and sensors up to the state (``mj_step`` leaves them one step behind)."""
        if not self._fresh:
            import mujoco

            mujoco.mj_forward(self.model, self.data)
            self._fresh = True

    def invalidate(self) -> None:
        """The state was set by hand: recompute what depends on it before it is read."""
        self._fresh = False

    def joint_name(self, index: int) -> str:
        """Name of a joint of the model by its id."""
        return str(self.model.joint(index).name)

    def close(self) -> None:
        """Free the renderer (the model and data are plain memory)."""
        if self.camera is not None:
            self.camera.close()
            self.camera = None

    # -- parts -----------------------------------------------------------------------------

    def add_object(
        self, object_type: ObjectType, colour: str | ColourRange, x_m: float, y_m: float, yaw_rad: float = 0.0,
        name: str | None = None,
    ) -> str:  # fmt: skip
        """Put a part of ``object_type`` on the table, resting at (x, y, yaw), top face ``colour``; returns its name."""
        name = self._new_part(object_type, colour, x_m, y_m, yaw_rad, name)
        self._rebuild()
        return name

    def add_parts(self, starts: Iterable[Any]) -> None:
        """Put several parts on the table (a scene from ``scenes.scatter``): one rebuild for all."""
        for start in starts:
            if getattr(start, "picture", None):
                from bt_arrange.errors import PlanError

                raise PlanError(
                    "a painted puzzle (picture) needs the pybullet engine: the MuJoCo cell paints no pictures"
                )
            kind = getattr(start, "object_type", None) or CUBE
            self._new_part(kind, start.colour, start.x_m, start.y_m, start.yaw_rad, start.name)
        self._rebuild()

    def _new_part(
        self, object_type: ObjectType, colour: str | ColourRange, x_m: float, y_m: float, yaw_rad: float,
        name: str | None,
    ) -> str:  # fmt: skip
        colour_name = colour.name if isinstance(colour, ColourRange) else colour
        name = name or colour_name
        if name in self._parts:
            raise ValueError(f"a cube named {name!r} is already in the cell")
        rgb = paint_of(colour, self.colours)
        friction = object_type.lateral_friction if object_type.lateral_friction is not None else DEFAULT_PART_FRICTION
        pose = Pose.from_planar(x_m, y_m, yaw_rad, z_m=object_type.shape.height_m / 2)
        self._parts[name] = PartSpec(name, object_type, rgb, pose, friction)
        self.object_types[name] = object_type
        return name

    def remove_part(self, name: str) -> None:
        """Take a part off the table."""
        self._parts.pop(name)
        self.object_types.pop(name, None)
        self._rebuild()

    # -- ground truth: evaluation and error injection only ---------------------------------

    def _free(self, name: str) -> tuple[int, int]:
        joint = self.model.joint(f"{name}_free")
        return int(joint.qposadr[0]), int(joint.dofadr[0])

    def part_pose_truth(self, name: str) -> Pose:
        """The engine's true pose of a part's centre. Never steer the robot with it."""
        qadr, _ = self._free(name)
        qpos = self.data.qpos
        return Pose(qpos[qadr : qadr + 3].copy(), _xyzw(qpos[qadr + 3 : qadr + 7]))

    def place_part_truth(self, name: str, pose: Pose) -> None:
        """Error injection: put a part at ``pose``; it moves on by physics (``WorkCell.place_part_truth``)."""
        qadr, dadr = self._free(name)
        x, y, z, w = (float(v) for v in pose.quaternion_xyzw)
        self.data.qpos[qadr : qadr + 3] = pose.position_m
        self.data.qpos[qadr + 3 : qadr + 7] = [w, x, y, z]
        self.data.qvel[dadr : dadr + 6] = 0.0
        self.invalidate()

    def displace_part(self, name: str, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Error injection: move a resting part by (dx, dy) and turn it by dyaw, as a bump would."""
        pose = self.part_pose_truth(name)
        moved = Pose.from_planar(pose.x_m + dx_m, pose.y_m + dy_m, pose.yaw_rad + dyaw_rad, z_m=pose.z_m)
        self.place_part_truth(name, moved)

    def finger_opening_m(self, finger: int) -> float:
        """True position of one finger joint (``finger_joint_indices``): its pad's distance from the centre."""
        return float(self.data.qpos[self.model.jnt_qposadr[finger]])

    def finger_pad_position_m(self, finger: int) -> np.ndarray:
        """True world position of one finger's link (its pad), for error injection."""
        self.forward()
        return self.data.xpos[self._finger_body[finger]].copy()

    def set_pad_friction(self, cube: str, lateral_friction: float) -> None:
        """Error injection: give both pads ``lateral_friction`` (Bullet's coefficient); every contact takes it at once.

        MuJoCo finds its contacts afresh at every step: the pairs' coefficient is all there is to change.
        """
        self._pad_friction = lateral_friction
        self._apply_pad_friction(only=cube)

    def _apply_pad_friction(self, only: str | None = None) -> None:
        model = self.model
        fingers = set(self._finger_body.values())
        for pair in range(model.npair):
            if int(model.geom_bodyid[model.pair_geom1[pair]]) not in fingers:
                continue  # two parts' pair (``model._part_pairs``): no pad in it
            geom = model.pair_geom2[pair]
            name = self.model.body(model.geom_bodyid[geom]).name
            if name in self._parts and (only is None or name == only):
                friction = cell_model.pad_friction(self._parts[name].friction, self._pad_friction, self.mujoco_physics)
                model.pair_friction[pair, :2] = friction

    def part_in_gripper_truth(self, name: str) -> bool:
        """True when both finger links touch the part."""
        self.forward()
        body = self.parts[name]
        touching = set()
        model, data = self.model, self.data
        fingers = set(self._finger_body.values())
        for geom1, geom2 in data.contact.geom[: data.ncon]:
            bodies = {int(model.geom_bodyid[geom1]), int(model.geom_bodyid[geom2])}
            if body in bodies:
                touching |= bodies & fingers
        return touching == fingers

    def begin_grasp(self) -> None:
        """A real cell's grasp offset: none in the ideal cell (the only MuJoCo cell)."""

    def end_grasp(self, opening_m: float) -> None:
        """See ``begin_grasp``."""


def with_physics(physics: MujocoPhysics, **changes: float) -> MujocoPhysics:
    """``physics`` with some figures changed (the sensitivity study's variants)."""
    return dataclasses.replace(physics, **changes)
