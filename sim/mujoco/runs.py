"""The MuJoCo cell as a ``bt_arrange.session.World``, and ``MujocoRun``: a session in a fresh MuJoCo cell.

The twins of ``bt_arrange_sim.runs``' ``SimWorld`` and ``SimulatedRun``: everything that is the same
for every backend is the session's (``bt_arrange.session``); here is only what is MuJoCo's.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange.calibration import CameraCalibration
from bt_arrange.perception import ColourTable
from bt_arrange.plancheck import CameraView
from bt_arrange.robot import CameraFrame, CameraIntrinsics, Clock, Robot
from bt_arrange.session import GroundTruth, Session, World
from bt_arrange_sim.cell import CellConfig
from bt_arrange_sim.mujoco.cell import MujocoCell
from bt_arrange_sim.mujoco.model import MujocoPhysics


def camera_view(config: CellConfig) -> CameraView:
    """What the MuJoCo cell's camera sees, for the plan check: the nominal pinhole OpenGL renders."""
    camera = config.camera
    intrinsics = CameraIntrinsics.from_fov(camera.width_px, camera.height_px, camera.horizontal_fov_deg)
    return CameraView(intrinsics, camera.pose_world())


class MujocoWorld:
    """A ``MujocoCell`` as a ``World``: its robot, clock and camera, and the engine's ground truth.

    ``cell`` is the MuJoCo cell itself, for what only a simulator can do (the error injectors).
    """

    def __init__(self, cell: MujocoCell) -> None:
        self.cell = cell

    @property
    def robot(self) -> Robot:
        """The cell's arm, gripper, camera and clock."""
        return self.cell.robot

    @property
    def clock(self) -> Clock:
        """Simulated time, seconds: it advances only when the cell is stepped."""
        return self.cell.clock

    @property
    def truth(self) -> GroundTruth:
        """The engine knows where every part is: this world is its own ground truth."""
        return self

    def place(self, starts: Sequence[Any], colours: ColourTable) -> None:
        """Paint with ``colours`` and put the parts on the table, resting, where they start."""
        self.cell.colours = colours
        self.cell.add_cubes(starts)

    def settle(self, seconds: float) -> None:
        """Run the physics for ``seconds`` of world time with the arm holding still."""
        self.cell.settle(seconds)

    def step(self) -> None:
        """One control period (several physics steps)."""
        self.cell.step()

    def capture_image(self) -> CameraFrame:
        """A frame of the cell's top camera."""
        assert self.cell.camera is not None
        return self.cell.camera.capture()

    def close(self) -> None:
        """Free the renderer."""
        self.cell.close()

    def part_names(self) -> list[str]:
        """Every part in the cell, by name."""
        return list(self.cell.cubes)

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        """The engine's true ``(x_m, y_m, yaw_rad)`` of a part (yaw folded to its symmetry)."""
        return self.cell.cube_planar_truth(name)


class MujocoRun(Session):
    """One tree in one freshly built MuJoCo cell: a ``Session`` on a ``MujocoWorld`` (``SimulatedRun``'s twin)."""

    world: MujocoWorld

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        cell_config: CellConfig | None = None,
        physics: MujocoPhysics | None = None,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
        calibration: CameraCalibration | None = None,
    ) -> None:
        config = cell_config or CellConfig()

        def open_world() -> World:
            return MujocoWorld(MujocoCell(config, physics))

        super().__init__(
            root,
            starts,
            open_world,
            view=camera_view(config),
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=calibration,
        )

    @property
    def cell(self) -> MujocoCell:
        """The MuJoCo cell the tree runs in (ground truth and error injection go through it)."""
        return self.world.cell

    def __enter__(self) -> MujocoRun:
        return self
