"""The MuJoCo cell as a ``bt_arrange.session.World``, and ``MujocoRun``: a session in a fresh MuJoCo cell.

Everything that is the same for every backend is the session's (``bt_arrange.session``), and what
every simulated engine shares is ``bt_arrange_sim.world``'s; here is only what is MuJoCo's: the
cell it builds and the nominal pinhole its camera renders.
"""

from __future__ import annotations

from bt_arrange.plan.camera_view import CameraView
from bt_arrange.robot import CameraIntrinsics
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.mujoco.cell import MujocoCell
from bt_arrange_sim.mujoco.model import MujocoPhysics
from bt_arrange_sim.world import CellRun, CellWorld


def camera_view(config: CellConfig) -> CameraView:
    """What the MuJoCo cell's camera sees, for the plan check: the nominal pinhole OpenGL renders."""
    camera = config.camera
    intrinsics = CameraIntrinsics.from_fov(camera.width_px, camera.height_px, camera.horizontal_fov_deg)
    return CameraView(intrinsics, camera.pose_world())


class MujocoWorld(CellWorld):
    """A ``MujocoCell`` as a ``World`` (``CellWorld``). It has no ``parts_at_rest``: it settles the whole time asked."""

    cell: MujocoCell


def open_world(config: CellConfig, physics: MujocoPhysics | None = None) -> MujocoWorld:
    """A fresh MuJoCo cell of ``config`` (and MuJoCo's own ``physics``, the sensitivity study's variants) as a world."""
    return MujocoWorld(MujocoCell(config, physics))


class MujocoRun(CellRun):
    """One tree in one freshly built MuJoCo cell: a ``CellRun`` on a ``MujocoWorld``.

    ``MujocoRun(root, starts, cell_config=..., physics=..., record_dir=..., ...)``: ``physics`` are
    MuJoCo's own settings (``MujocoPhysics``), the rest is ``CellRun``'s.
    """

    world: MujocoWorld
    cell: MujocoCell
    open_world = staticmethod(open_world)
    camera_view = staticmethod(camera_view)
