"""The work cell's configuration, engine-neutral: physics figures, the top camera, the table, a real cell's errors.

Both engines build their cell from a ``CellConfig`` (``bt_arrange_sim.pybullet.cell.WorkCell``,
``bt_arrange_sim.mujoco.cell.MujocoCell``): the time step and control period, gravity, the
friction coefficients, the gripper's speeds and forces, the camera's intrinsics and pose. The
figures were tuned in pybullet (``PhysicsConfig``'s notes); MuJoCo's own settings are its
``MujocoPhysics``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field

from bt_arrange import paper_cell
from bt_arrange.calibration import BoardMount, CharucoBoard
from bt_arrange.geometry import Pose
from bt_arrange.motion import DEFAULT_HOME_Q
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.robot import CameraIntrinsics
from bt_arrange_sim.noise import CameraNoiseConfig
from bt_arrange_sim.realcell import RealCellErrors


@dataclass(frozen=True)
class Contact:
    """Friction and contact parameters of one body (pybullet ``changeDynamics``)."""

    lateral_friction: float
    spinning_friction: float = 0.0
    rolling_friction: float = 0.0
    restitution: float = 0.0
    #: Bullet's friction anchors pin a sticking contact point instead of letting it drift a
    #: little every step; without them a held cube crept 1 to 3 mm down and along the pads.
    friction_anchor: bool = True


#: Joint vector the arm starts in: gripper straight down, out of the top camera's view.
HOME_Q = DEFAULT_HOME_Q


@dataclass(frozen=True)
class PhysicsConfig:
    """Integration and contact settings, tuned so a 5 cm cube is held by friction alone.

    The arm follows setpoints through pybullet's position motors; ``control_period_s`` must be a
    whole number of ``time_step_s``.

    Measured with ``benchmarks/cell.py`` (10 trials): 50 solver iterations place a cube 0.10 mm
    from its target on average at about 23x real time; 100 iterations place it 0.03 mm off but
    run at 17x, because a held cube brings the whole arm into the contact solve. A 4 ms step
    placed cubes 0.65 mm off. The gear constraint that mirrors the fingers needs a high
    ``gear_erp``: at 0.2 the fingers drifted 0.45 mm apart while closing and the cube sat 0.2 mm
    off the TCP; at 0.0 (velocity coupling only) 8 mm.
    """

    time_step_s: float = 1.0 / 500.0
    solver_iterations: int = 50
    #: A part lighter than this (kg; a cube is 0.1) squeezed between the pads needs more of the
    #: contact solve: at 50 iterations the pads ended 1.0 to 1.8 mm into a 20 to 60 g prism (0.05 mm
    #: into a cube; a 15 mm prism of 0.1 kg 0.3 mm), unevenly, and it was carried up to 0.8 mm off
    #: along the closing axis and set down 0.48 mm off on average, 1.0 mm at most, in isolation. At
    #: 150, 0.09 and 0.17 mm (``benchmarks/setdown.py``; docs/irregular.md). With
    #: such a part in the cell, it solves with ``light_part_solver_iterations`` from each close of the
    #: fingers (a grasp) until they are narrowed for a push: the release, the retreat and the look
    #: under the solve that held the part (switched back at the release, a released part moved up to
    #: 2.5 mm), pushes as before (at 150 a fragment's pushes stopped converging); cubes as before.
    light_part_mass_kg: float = 0.1
    light_part_solver_iterations: int = 150
    control_period_s: float = 0.008
    gravity_m_s2: float = 9.81
    arm_position_gain: float = 0.3
    arm_velocity_gain: float = 1.0
    finger_position_gain: float = 0.2
    finger_open_force_n: float = 40.0
    #: Closing speed: faster closes (0.1 m/s) left the force-limited fingers trembling on the cube
    #: for longer than the grasp's timeout in one trial of four.
    gripper_speed_m_s: float = 0.05
    #: Opening speed: the 2F-85's fastest; letting go faster did not move the released cube more.
    gripper_open_speed_m_s: float = 0.15
    #: Parts at rest sleep (Bullet's deactivation): they leave the contact solve until something
    #: touches them, which wakes them. With four cubes resting on the table the cell stepped at about
    #: half the bare robot's rate, with them asleep at 0.86 of it (``benchmarks/throughput.py``). A part
    #: counts as at rest when its mean squared velocity (m/s, rad/s) stays under ``sleep_threshold``
    #: (1e-6: about 1 mm/s) for Bullet's two seconds; every pose reset of a part wakes it.
    parts_sleep: bool = True
    sleep_threshold: float = 1e-6
    gear_max_force_n: float = 200.0
    gear_erp: float = 0.8
    cube_contact: Contact = Contact(lateral_friction=0.5, spinning_friction=0.001)
    #: Prisms (a compound of convex hulls) without friction anchors: a hull's table contact points
    #: outlive a push, so anchored ones pulled a pushed prism back to where it lay
    #: (docs/irregular.md, Limits, "Sub-millimetre pushes"); the pads' anchors still pin it.
    prism_contact: Contact = Contact(lateral_friction=0.5, spinning_friction=0.001, friction_anchor=False)
    pad_contact: Contact = Contact(lateral_friction=1.2, spinning_friction=0.002)
    #: A release of a prism starts from fresh contact points between it and the pads
    #: (``SimGripper._refresh_contacts``): Bullet's kept points, one facing the wrong way, made an
    #: opening pad drag the part. Measured over ``irregular_parts`` at scene seeds 0 to 9 (50
    #: releases, by truth): a release moved a part 0.47 mm and turned it 0.13 deg on average, up to
    #: 8.3 mm and 1.6 deg; with fresh points 0.03 mm and 0.004 deg, at most 0.16 mm and 0.04 deg.
    #: A box's release is as it was.
    fresh_prism_release_contacts: bool = True
    table_contact: Contact = Contact(lateral_friction=0.5, spinning_friction=0.001, friction_anchor=False)

    @property
    def substeps(self) -> int:
        """Physics steps per control period."""
        steps = round(self.control_period_s / self.time_step_s)
        if steps < 1 or not math.isclose(steps * self.time_step_s, self.control_period_s, rel_tol=1e-9):
            raise ValueError(
                f"control period {self.control_period_s} s is not a multiple of the time step {self.time_step_s} s"
            )
        return steps


@dataclass(frozen=True)
class CameraConfig:
    """The top camera: L515-like RGB intrinsics, 70 cm above the table, looking straight down.

    The nominal figures are the paper's cell's (``bt_arrange.paper_cell``), which a real cell starts from too.

    The long image axis runs along world y; image "down" points to world -x, towards the robot;
    the camera is turned ``roll_deg`` about its optical axis.
    """

    width_px: int = paper_cell.CAMERA_WIDTH_PX
    height_px: int = paper_cell.CAMERA_HEIGHT_PX
    horizontal_fov_deg: float = paper_cell.CAMERA_HORIZONTAL_FOV_DEG
    position_m: tuple[float, float, float] = paper_cell.CAMERA_POSITION_M
    near_m: float = 0.1
    far_m: float = 2.0
    light_direction: tuple[float, float, float] = (0.3, 0.2, 1.0)
    #: Turn of the camera about its optical axis. No real camera is mounted exactly square to the
    #: table; with 0, a cube square to the table (as every push leaves it) has its edges on whole
    #: pixels of the aliased render, and its position is only known to about half a pixel
    #: (0.25 mm); a few degrees give every edge a staircase to measure below a pixel.
    roll_deg: float = paper_cell.CAMERA_ROLL_DEG

    def calibrated_intrinsics(self) -> CameraIntrinsics:
        """The intrinsics of the rendered image, as a calibration would find them.

        TinyRenderer decides a pixel's coverage at its corner, not its centre, and flips rows:
        the rendered image sits half a pixel right of and half a pixel above the nominal
        pinhole (measured: +0.52, -0.59 px on blob centroids).
        """
        nominal = CameraIntrinsics.from_fov(self.width_px, self.height_px, self.horizontal_fov_deg)
        return dataclasses.replace(nominal, cx_px=nominal.cx_px + 0.5, cy_px=nominal.cy_px - 0.5)

    def view(self) -> CameraView:
        """What this camera sees, for the plan check (no world needed)."""
        return CameraView(self.calibrated_intrinsics(), self.pose_world())

    def pose_world(self) -> Pose:
        """``T_W_C`` in the OpenCV optical frame: x right (about world -y), y down (about world -x), z forward."""
        return paper_cell.camera_pose_world(self.position_m, self.roll_deg)


@dataclass(frozen=True)
class CellConfig:
    """Everything that makes one work cell."""

    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    camera_noise: CameraNoiseConfig = field(default_factory=CameraNoiseConfig)
    table_size_m: tuple[float, float] = (1.3, 1.4)
    table_centre_xy_m: tuple[float, float] = (0.35, 0.0)
    #: A real cell's errors (``bt_arrange_sim.realcell``); all off by default: the ideal cell.
    errors: RealCellErrors = field(default_factory=RealCellErrors)
    #: The calibration board bolted to the flange (``bt_arrange_sim.pybullet.calibration``), or None (a run's cell).
    board: CharucoBoard | None = None
    board_mount: BoardMount = field(default_factory=BoardMount)

    @classmethod
    def ideal(cls) -> CellConfig:
        """Today's simulated cell, exactly (no real-cell error term on)."""
        return cls()

    @classmethod
    def real(cls, cell_seed: int = 0) -> CellConfig:
        """The paper's real cell: ``realcell.real()``'s error terms (docs/simulation.md)."""
        from bt_arrange_sim import realcell

        return cls(errors=realcell.real(cell_seed))

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> CellConfig:
        """A cell with the user's own error values (``realcell.load_toml``; a ``PlanError`` names a bad key)."""
        from bt_arrange_sim import realcell

        return cls(errors=realcell.load_toml(path))

    @classmethod
    def named(cls, name: str) -> CellConfig:
        """``ideal``, ``real`` or a ``.toml`` file, as ``--cell`` takes it."""
        from bt_arrange_sim import realcell

        return cls(errors=realcell.parse_cell(name))
