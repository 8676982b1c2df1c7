"""The MuJoCo cell as a ``bt_arrange.session.World``, and ``MujocoRun``: a session in a fresh MuJoCo cell.

The twins of ``bt_arrange_sim.runs``' ``SimWorld`` and ``SimulatedRun``: everything that is the same
for every backend is the session's (``bt_arrange.session``); here is only what is MuJoCo's.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange.calibration import CameraCalibration
from bt_arrange.plancheck import CameraView
from bt_arrange.robot import CameraIntrinsics
from bt_arrange.session import Session, World
from bt_arrange_sim.cell import CellConfig
from bt_arrange_sim.mujoco.cell import MujocoCell
from bt_arrange_sim.mujoco.model import MujocoPhysics
from bt_arrange_sim.runs import SimWorld


def camera_view(config: CellConfig) -> CameraView:
    """What the MuJoCo cell's camera sees, for the plan check: the nominal pinhole OpenGL renders."""
    camera = config.camera
    intrinsics = CameraIntrinsics.from_fov(camera.width_px, camera.height_px, camera.horizontal_fov_deg)
    return CameraView(intrinsics, camera.pose_world())


class MujocoWorld(SimWorld):
    """A ``MujocoCell`` as a ``World``: ``SimWorld`` over the MuJoCo cell, which has the same methods.

    ``cell`` is the MuJoCo cell itself, for what only a simulator can do (the error injectors).
    Only the scene's settling differs: the MuJoCo cell has no ``parts_at_rest``, so it settles the
    whole ``seconds``.
    """

    cell: MujocoCell  # type: ignore[assignment]

    def __init__(self, cell: MujocoCell) -> None:
        self.cell = cell

    def settle(self, seconds: float) -> None:
        """Run the physics for ``seconds`` of world time with the arm holding still."""
        self.cell.settle(seconds)


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
