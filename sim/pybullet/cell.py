"""The pybullet work cell: a table, a UR5 with a 2F-85-like gripper, coloured cubes, a top camera.

Each ``WorkCell`` owns its own ``BulletClient``, so several worlds can live in one process.
The world frame has its origin on the table top under the robot base, z up.

Ground truth (``part_pose_truth``) is for evaluation and error injection only: behaviours
see the world through the camera, like the robot in the paper.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import sys
from collections.abc import Iterable, Iterator, Sequence

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES, TCP_FRAME, default_urdf_path
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange_sim.cell_base import CellBase
from bt_arrange_sim.config import HOME_Q, CellConfig
from bt_arrange_sim.noise import CameraNoise, CameraNoiseConfig
from bt_arrange_sim.parts import TABLE_RGB, mass_of
from bt_arrange_sim.perturbed_robot import hand_eye_base_pose, write_perturbed_urdf
from bt_arrange_sim.pybullet.devices import SimArm, SimCamera, SimClock, SimGripper
from bt_arrange_sim.pybullet.objects import apply_contact, create_object
from bt_arrange_sim.scenes import PartStart


@contextlib.contextmanager
def _silenced(fd: int) -> Iterator[None]:
    """Silence a C-level stream (1 stdout, 2 stderr) for the duration, where Python's redirection cannot reach.

    pybullet prints ``argv[0]=`` on stdout when it connects, which would spoil ``--json``, and
    its build time on stderr when first imported, which broke the experiment's progress bar
    (drawn on stderr) once per worker.
    """
    (sys.stdout if fd == 1 else sys.stderr).flush()
    saved = os.dup(fd)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)
        os.close(devnull)


def import_pybullet():  # noqa: ANN201 - the pybullet module
    """``import pybullet`` without its build-time banner on stderr."""
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    with _silenced(2):
        import pybullet
    return pybullet


def require_display() -> None:
    """Raise a ``PlanError`` when the pybullet window (``gui=True``) cannot open: no X or Wayland display.

    Without one, pybullet prints an X error and ends the process itself, with no chance to say why.
    """
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise PlanError(
            "the pybullet window (--gui) needs a display, and DISPLAY is not set: run headless "
            "(without --gui), or under a virtual display: xvfb-run bt-arrange run ... --gui"
        )


_HAND_EYE: dict[str, tuple[np.ndarray, float]] = {}


def _cached_hand_eye(urdf_path: os.PathLike[str] | str) -> tuple[np.ndarray, float]:
    """``perturbed_robot.hand_eye_base_pose`` once per process and URDF (it solves 40 IK problems)."""
    key = str(urdf_path)
    if key not in _HAND_EYE:
        from pathlib import Path

        _HAND_EYE[key] = hand_eye_base_pose(Path(key))
    return _HAND_EYE[key]


class WorkCell(CellBase):
    """One simulated work cell with its own physics world.

    ``gui=True`` opens the pybullet window (needs a display); the default is DIRECT, headless.
    """

    ARM_JOINTS = ARM_JOINT_NAMES
    FINGER_JOINTS = FINGER_JOINT_NAMES

    def __init__(self, config: CellConfig | None = None, gui: bool = False) -> None:
        if gui:
            require_display()
        pybullet = import_pybullet()
        from pybullet_utils.bullet_client import BulletClient

        self.config = config or CellConfig()
        #: True with the pybullet window open.
        self.gui = gui
        physics = self.config.physics
        self._substeps = physics.substeps
        with _silenced(1):
            self.client = BulletClient(connection_mode=pybullet.GUI if gui else pybullet.DIRECT)
        self.client.setGravity(0.0, 0.0, -physics.gravity_m_s2)
        #: The contact solve's iterations now: ``physics.solver_iterations``, more while the pads grip a light part.
        self.solver_iterations = physics.solver_iterations
        self._light_parts = False
        self.client.setPhysicsEngineParameter(
            fixedTimeStep=physics.time_step_s, numSolverIterations=physics.solver_iterations
        )
        self._steps = 0
        self.parts: dict[str, int] = {}
        #: Each part's type, by name (the cube's unless ``add_object`` said otherwise).
        self.object_types: dict[str, ObjectType] = {}
        #: The colour table the cell paints from: the one the camera's detector reads.
        self.colours: ColourTable = DEFAULT_COLOUR_TABLE
        self.table_id = self._create_table()
        errors = self.config.errors
        # A real cell's arm: the perturbed URDF (the planner keeps the nominal one), mounted where
        # the hand-eye calibration puts it (absorbing the arm's mean error over the workspace).
        self.urdf_path = write_perturbed_urdf(errors) if errors.enabled else None
        base_position, base_yaw = (0.0, 0.0, 0.0), 0.0
        if self.urdf_path is not None and errors.kinematics.enabled and errors.kinematics.hand_eye_absorbs_mean:
            translation, base_yaw = _cached_hand_eye(self.urdf_path)
            base_position = (float(translation[0]), float(translation[1]), float(translation[2]))
        robot_urdf = self.urdf_path or default_urdf_path()
        if self.config.board is not None:
            from bt_arrange_sim.pybullet.calibration import write_urdf_with_board

            # The calibration board is a link of the robot (bolted to the flange), never a constraint.
            robot_urdf = write_urdf_with_board(robot_urdf, self.config.board, self.config.board_mount)
        self.robot_id = self.client.loadURDF(
            str(robot_urdf),
            basePosition=list(base_position),
            baseOrientation=list(self.client.getQuaternionFromEuler((0.0, 0.0, base_yaw))),
            useFixedBase=True,
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
        )
        self._edge_rng = errors.rng("objects", per_run=True)
        self._grasp_offset_rng = errors.grasp_offset_rng()
        #: The last grasp's offset of the pads' centre from the TCP along the closing axis (m).
        self.grasp_offset_m = 0.0
        self._recentre_at_width_m: float | None = None
        #: How far (m) re-centring would swing the pad on the grasp offset's side (``end_grasp``).
        self._swing_m = 0.0
        #: True while a release keeps the grasp's offset until the pads clear the part (``end_grasp``).
        self.offset_kept = False
        self._joint_index = {
            self.client.getJointInfo(self.robot_id, i)[1].decode(): i
            for i in range(self.client.getNumJoints(self.robot_id))
        }
        self._link_index = {
            self.client.getJointInfo(self.robot_id, i)[12].decode(): i
            for i in range(self.client.getNumJoints(self.robot_id))
        }
        self.arm_joint_indices = tuple(self._joint_index[name] for name in self.ARM_JOINTS)
        self.arm_joint_efforts_n_m = tuple(
            self.client.getJointInfo(self.robot_id, i)[10] for i in self.arm_joint_indices
        )
        self.finger_joint_indices = tuple(self._joint_index[name] for name in self.FINGER_JOINTS)
        self.tcp_link_index = self._link_index[TCP_FRAME]
        if self.config.board is not None:
            from bt_arrange_sim.pybullet.calibration import BOARD_LINK, texture_board

            texture_board(self.client, self.robot_id, self._link_index[BOARD_LINK], self.config.board)
        self._configure_gripper()
        noise = self.config.camera_noise
        if errors.imaging.enabled:
            imaging = errors.imaging
            noise = CameraNoiseConfig(
                sensor_sigma=imaging.sensor_sigma,
                blur_sigma_px=imaging.blur_sigma_px,
                brightness_jitter=imaging.exposure_jitter,
                seed=int(errors.rng("imaging", per_run=True).integers(2**31)),
            )
        self.camera_noise = CameraNoise(noise)
        self.clock = SimClock(self)
        self.arm = SimArm(self)
        self.gripper = SimGripper(self)
        self.camera = SimCamera(self)
        self.arm.reset(HOME_Q)
        self.gripper.reset(self.gripper.max_width_m)

    # -- world -----------------------------------------------------------------------------

    def step(self, control_periods: int = 1) -> None:
        """Advance the world by whole control periods (each several physics steps)."""
        friction = self.config.errors.friction.enabled
        # Looked up once: ``BulletClient`` builds a fresh partial (and an ``inspect`` call) at every attribute access.
        step_simulation = self.client.stepSimulation
        for _ in range(control_periods):
            if friction:
                self._apply_friction_field()
            for _ in range(self._substeps):
                step_simulation()
            if self._recentre_at_width_m is not None and (
                self.gripper.width() >= self._recentre_at_width_m or (self.offset_kept and self._pads_clear_of_parts())
            ):
                self._set_grasp_offset(0.0)
                self._recentre_at_width_m = None
                if self.offset_kept:
                    # The fingers were sent where the kept offset put them: now to the centred opening.
                    self.offset_kept = False
                    self.gripper.retarget()
        self._steps += control_periods * self._substeps

    def _apply_friction_field(self) -> None:
        """A real cell's table: each cube's friction is the field's where it lies (new contacts take it)."""
        nominal = self.config.physics.cube_contact.lateral_friction
        for body in self.parts.values():
            (x, y, _), _ = self.client.getBasePositionAndOrientation(body)
            self.client.changeDynamics(body, -1, lateralFriction=nominal * self.config.errors.friction_scale(x, y))

    def parts_at_rest(self, speed_m_s: float = 0.001, speed_rad_s: float = 0.01) -> bool:
        """True when every part moves slower than ``speed_m_s`` and turns slower than ``speed_rad_s``."""
        for body in self.parts.values():
            linear, angular = self.client.getBaseVelocity(body)
            if np.linalg.norm(linear) > speed_m_s or np.linalg.norm(angular) > speed_rad_s:
                return False
        return True

    def joint_name(self, index: int) -> str:
        """Name of a joint of the robot by its pybullet index."""
        return self.client.getJointInfo(self.robot_id, index)[1].decode()

    def close(self) -> None:
        """Disconnect this world's physics client."""
        if self.client is not None:
            self.client.disconnect()
            self.client = None  # type: ignore[assignment]

    # -- cubes -----------------------------------------------------------------------------

    def add_object(
        self,
        object_type: ObjectType,
        colour: str | ColourRange,
        x_m: float,
        y_m: float,
        yaw_rad: float = 0.0,
        name: str | None = None,
        picture: str | None = None,
        picture_uv: Sequence[tuple[float, float]] = (),
    ) -> str:
        """Put a cuboid of ``object_type`` on the table, resting at (x, y, yaw), top face ``colour``; returns its name.

        ``picture`` (a file) is printed on a prism's top instead, each outline vertex at ``picture_uv``.

        ``colour`` is a name of ``self.colours`` (the table the camera reads) or a ``ColourRange``
        (painted with its ``paint_rgb``); the name defaults to the colour's.
        """
        colour_name = colour.name if isinstance(colour, ColourRange) else colour
        name = name or colour_name
        if name in self.parts:
            raise ValueError(f"a cube named {name!r} is already in the cell")
        objects = self.config.errors.objects
        # A real cell's parts: each edge off by its tolerance (the perception assumes the nominal size).
        edge_error_m = float(self._edge_rng.normal(0.0, objects.edge_sigma_mm / 1000)) if objects.enabled else 0.0
        built = object_type.resized(edge_error_m) if edge_error_m else object_type
        pose = Pose.from_planar(x_m, y_m, yaw_rad, z_m=built.shape.height_m / 2)
        self.parts[name] = create_object(
            self.client,
            built,
            colour,
            pose.position_m,
            pose.quaternion_xyzw,
            self.config.physics.cube_contact if built.shape.rectangular else self.config.physics.prism_contact,
            self.colours,
            picture=picture,
            picture_uv=picture_uv,
        )
        self.object_types[name] = object_type
        self._note_light_part(built)
        if self.config.physics.parts_sleep:
            self.client.changeDynamics(
                self.parts[name],
                -1,
                activationState=import_pybullet().ACTIVATION_STATE_ENABLE_SLEEPING,
                sleepThreshold=self.config.physics.sleep_threshold,
            )
        return name

    def _note_light_part(self, object_type: ObjectType) -> None:
        """Note a part lighter than ``PhysicsConfig.light_part_mass_kg``: the pads' grip on it needs more iterations."""
        if mass_of(object_type) < self.config.physics.light_part_mass_kg:
            self._light_parts = True

    def _solve_grip(self, gripping: bool) -> None:
        """The contact solve's iterations from a grasp's close (``gripping``) until the pads are narrowed for a push.

        Gripping, with a light part in the cell: ``light_part_solver_iterations``, so that the
        squeeze converges; else ``solver_iterations``, at which the pushes (open pads) were measured.
        """
        physics = self.config.physics
        wanted = physics.light_part_solver_iterations if gripping and self._light_parts else physics.solver_iterations
        if wanted != self.solver_iterations:
            self.solver_iterations = wanted
            self.client.setPhysicsEngineParameter(numSolverIterations=wanted)

    def _wake(self, name: str) -> None:
        """A part whose pose or contacts were changed from outside moves again under physics."""
        self.client.changeDynamics(self.parts[name], -1, activationState=import_pybullet().ACTIVATION_STATE_WAKE_UP)

    def remove_part(self, name: str) -> None:
        """Take a cube off the table."""
        self.client.removeBody(self.parts.pop(name))
        self.object_types.pop(name, None)

    # -- ground truth: evaluation and error injection only ---------------------------------

    def part_pose_truth(self, name: str) -> Pose:
        """The simulator's true pose of a cube's centre. Never steer the robot with it."""
        position, orientation = self.client.getBasePositionAndOrientation(self.parts[name])
        return Pose(np.array(position), np.array(orientation))

    def displace_part(self, name: str, dx_m: float = 0.0, dy_m: float = 0.0, dyaw_rad: float = 0.0) -> None:
        """Error injection: move a resting cube by (dx, dy) and turn it by dyaw, as a bump would.

        The robot learns of it only through its camera. Never used to steer or to fake a result.
        """
        pose = self.part_pose_truth(name)
        moved = Pose.from_planar(pose.x_m + dx_m, pose.y_m + dy_m, pose.yaw_rad + dyaw_rad, z_m=pose.z_m)
        self.client.resetBasePositionAndOrientation(self.parts[name], moved.position_m, moved.quaternion_xyzw)
        self._wake(name)

    def place_part_truth(self, name: str, pose: Pose) -> None:
        """Error injection: put a cube at ``pose`` (a tilt, a drag by a sticking finger); it moves on by physics.

        The robot learns of it only through its camera. Never used to steer or to fake a result.
        """
        self.client.resetBasePositionAndOrientation(self.parts[name], pose.position_m, pose.quaternion_xyzw)
        self._wake(name)

    def finger_opening_m(self, finger: int) -> float:
        """True position of one finger joint (``finger_joint_indices``): its pad's distance from the centre."""
        return float(self.client.getJointState(self.robot_id, finger)[0])

    def finger_pad_position_m(self, finger: int) -> np.ndarray:
        """True world position of one finger's link (its pad), for error injection."""
        return np.array(self.client.getLinkState(self.robot_id, finger, computeForwardKinematics=True)[4])

    def set_pad_friction(self, cube: str, lateral_friction: float) -> None:
        """Error injection: give both pads ``lateral_friction`` and make a held cube's contacts take it at once.

        Bullet keeps the friction a contact point was made with for as long as the point persists
        (a held cube's do, for seconds), so the pads' contact points with the cube are dropped, by
        filtering the pair out and back in, and made afresh at the next physics step.
        """
        contact = dataclasses.replace(self.config.physics.pad_contact, lateral_friction=lateral_friction)
        body = self.parts[cube]
        for finger in self.finger_joint_indices:
            apply_contact(contact, self.client, self.robot_id, finger)
            self.client.setCollisionFilterPair(self.robot_id, body, finger, -1, 0)
            self.client.setCollisionFilterPair(self.robot_id, body, finger, -1, 1)
        self._wake(cube)

    def add_parts(self, starts: Iterable[PartStart]) -> None:
        """Put several cubes on the table (a scene from ``scenes.scatter``)."""
        for start in starts:
            kind = getattr(start, "object_type", None) or CUBE
            # A painted puzzle's piece carries its picture and where its outline lies in it.
            painted = (
                {"picture": start.picture, "picture_uv": start.picture_uv} if getattr(start, "picture", None) else {}
            )
            self.add_object(kind, start.colour, start.x_m, start.y_m, start.yaw_rad, name=start.name, **painted)

    def part_in_gripper_truth(self, name: str) -> bool:
        """True when both finger pads touch the cube."""
        body = self.parts[name]
        return all(
            len(self.client.getContactPoints(self.robot_id, body, linkIndexA=finger)) > 0
            for finger in self.finger_joint_indices
        )

    # -- building ---------------------------------------------------------------------------

    def _create_table(self) -> int:
        import pybullet

        length, width = self.config.table_size_m
        thickness = 0.04
        half = [length / 2, width / 2, thickness / 2]
        collision = self.client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
        visual = self.client.createVisualShape(pybullet.GEOM_BOX, halfExtents=half, rgbaColor=[*TABLE_RGB, 1.0])
        cx, cy = self.config.table_centre_xy_m
        table = self.client.createMultiBody(0.0, collision, visual, basePosition=[cx, cy, -thickness / 2])
        apply_contact(self.config.physics.table_contact, self.client, table)
        return int(table)

    def begin_grasp(self) -> None:
        """A real cell's grasp: the pads' centre settles a fresh draw off the TCP (``GripperError``).

        The gear constraint keeps the two fingers that far apart from symmetric until the next grasp
        (``relativePositionTarget`` is the left joint's value minus the right's: twice the offset).
        No offset in the ideal cell. In either, a light part is gripped under more of the contact
        solve (``PhysicsConfig.light_part_solver_iterations``) until the pads are set for a push.
        """
        self._solve_grip(True)
        if self._grasp_offset_rng is None:
            return
        sigma_m = self.config.errors.gripper.grasp_offset_sigma_mm / 1000
        self._recentre_at_width_m = None
        self.offset_kept = False
        self._set_grasp_offset(float(self._grasp_offset_rng.normal(0.0, sigma_m)))

    def end_grasp(self, opening_m: float) -> None:
        """The gripper opens to ``opening_m``: the fingers re-centre once they are clear of the cube.

        Not at once: re-centring while the pads still touch would push the released cube. The
        offset is dropped when the opening is within 2 mm (and the offset, which a joint limit may
        hold back) of ``opening_m`` (``step``), so pushes are made with centred fingers; but never
        before the pad on the offset's side, swung across by twice the offset, stays clear of where
        the part sits (the opening it starts from, plus twice the offset). A release among neighbours
        opens a few millimetres only: re-centred at once there, that pad struck the released part
        (an 8.4 mm offset flung a fresco piece at 0.33 m/s and turned it 18 deg; a 6.7 mm one
        shoved a piece 8 mm). Such an opening of the pads on a prism keeps what it can of the offset,
        less only what would take the far finger past its stroke, so both pads move away from the
        part, and re-centres once no pad is within the swing of a part (lifted off it). A box's is
        as it was (Table 1's real column was fitted with it).
        """
        if opening_m < self.gripper.width() - 0.001:
            # Open pads narrowed for a push: the pushes were measured at the cell's own solve (at 150
            # a fragment's stopped converging). A release, which widens them, keeps the grip's: the
            # part is let go, and the arm leaves and looks, under the solve that held it.
            self._solve_grip(False)
        if self.grasp_offset_m != 0.0:
            self._recentre_when_clear(opening_m)

    def _recentre_when_clear(self, opening_m: float) -> None:
        """When the fingers, opening to ``opening_m`` from a grasp off the TCP, re-centre (``end_grasp``)."""
        self._swing_m = swing_m = 2 * abs(self.grasp_offset_m)
        clear_m = self.gripper.width() + swing_m + self.RECENTRE_CLEARANCE_M
        recentre_at_m = opening_m - 0.002 - swing_m
        if recentre_at_m >= clear_m or not self._pads_on_prism():
            # A box's release is as it was: the real preset's per-grasp offset was fitted to Table 1's
            # real column with its cubes re-centred so (docs/experiments.md).
            self._recentre_at_width_m = recentre_at_m
            return
        # Opened narrower than that, the centred fingers would close on the part again: only once clear.
        self._recentre_at_width_m = clear_m if opening_m >= clear_m else math.inf
        kept_m = min(abs(self.grasp_offset_m), max(0.0, (self.gripper.max_width_m - opening_m) / 2))
        if kept_m < abs(self.grasp_offset_m):
            self._set_grasp_offset(math.copysign(kept_m, self.grasp_offset_m))
        self.offset_kept = True

    def finger_targets_m(self, opening_m: float) -> tuple[float, float]:
        """Where each finger (left, right: its pad's distance from the centre) is sent for ``opening_m``.

        Centred, but about the kept offset while a release keeps it (``end_grasp``): sent symmetric,
        the fingers' position motors fought the gear constraint and crept open past the opening.
        """
        offset_m = self.grasp_offset_m if self.offset_kept else 0.0
        return opening_m / 2 + offset_m, opening_m / 2 - offset_m

    #: How far (m) the near pad stays from a released part once the fingers re-centre.
    RECENTRE_CLEARANCE_M = 0.001

    def _pads_on_prism(self) -> bool:
        """Whether a pad touches a part that is no box (a prism: a fresco piece, an irregular part)."""
        contacts = self.client.getContactPoints
        return any(
            contacts(self.robot_id, self.parts[name], linkIndexA=finger)
            for name, kind in self.object_types.items()
            if not kind.shape.rectangular
            for finger in self.finger_joint_indices
        )

    def _pads_clear_of_parts(self) -> bool:
        """Whether no pad is within the re-centring's swing (twice the grasp's offset, and a millimetre) of any part."""
        reach_m = self._swing_m + self.RECENTRE_CLEARANCE_M
        closest = self.client.getClosestPoints
        return not any(
            closest(self.robot_id, body, reach_m, linkIndexA=finger)
            for body in self.parts.values()
            for finger in self.finger_joint_indices
        )

    def _set_grasp_offset(self, offset_m: float) -> None:
        self.grasp_offset_m = offset_m
        self.client.changeConstraint(
            self.gear_constraint_id,
            gearRatio=-1,
            maxForce=self.config.physics.gear_max_force_n,
            erp=self.config.errors.gripper.coupling_erp,
            relativePositionTarget=2 * offset_m,
        )

    def _configure_gripper(self) -> None:
        import pybullet

        physics = self.config.physics
        left, right = self.finger_joint_indices
        # The real 2F-85 linkage keeps both fingers symmetric; pybullet ignores URDF <mimic>,
        # so a gear constraint (ratio -1 on mirrored axes) ties the two joint values together.
        self.gear_constraint_id = self.client.createConstraint(
            self.robot_id,
            left,
            self.robot_id,
            right,
            jointType=pybullet.JOINT_GEAR,
            jointAxis=[1, 0, 0],
            parentFramePosition=[0, 0, 0],
            childFramePosition=[0, 0, 0],
        )
        gripper = self.config.errors.gripper
        # A real cell's linkage has play: a softer coupling (the fitted figure of realcell.GripperError).
        erp = gripper.coupling_erp if gripper.enabled else physics.gear_erp
        self.client.changeConstraint(self.gear_constraint_id, gearRatio=-1, maxForce=physics.gear_max_force_n, erp=erp)
        for finger in self.finger_joint_indices:
            apply_contact(physics.pad_contact, self.client, self.robot_id, finger)
            if gripper.enabled and gripper.pad_stiffness_n_m > 0:
                # Silicone pads: a compliant contact instead of pybullet's rigid one.
                self.client.changeDynamics(
                    self.robot_id,
                    finger,
                    contactStiffness=gripper.pad_stiffness_n_m,
                    contactDamping=gripper.pad_damping_n_s_m,
                )
