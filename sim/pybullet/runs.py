"""The pybullet work cell as a ``bt_arrange.session.World``, and ``SimulatedRun``: a session in a fresh cell.

Everything that is the same for every backend (the plan check, the runner, the transition log,
the replay page, the per-object report) is ``bt_arrange.session``'s, and what every simulated
engine shares is ``bt_arrange_sim.world``'s. Here stays what is pybullet's: ``SimWorld`` settles
its scene by the simulator's velocities, and ``SimulatedRun`` builds a ``WorkCell`` (in a window
with ``gui``) whose camera the plan check sees through ``CameraConfig.view``.

The names other modules import from here (``ObjectOutcome``, ``SimulationReport``, ``REASON_TYPES``,
``check_colours_apart``, ``prepare_record_dir``, ``SETTLE_S``) are the session's.
"""

from __future__ import annotations

from bt_arrange.plan.camera_view import CameraView
from bt_arrange.session import (
    REASON_TYPES,
    SETTLE_S,
    ObjectOutcome,
    SessionReport,
    check_colours_apart,
    prepare_record_dir,
)
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.pybullet.cell import WorkCell, require_display
from bt_arrange_sim.world import CellRun, CellWorld

#: The session's report, by its name of before the session left the simulator.
SimulationReport = SessionReport

__all__ = [
    "REASON_TYPES",
    "SETTLE_S",
    "ObjectOutcome",
    "SimWorld",
    "SimulatedRun",
    "SimulationReport",
    "check_colours_apart",
    "prepare_record_dir",
]


#: The scene has settled once its parts rest (``WorkCell.parts_at_rest``) this many control periods running.
RESTING_PERIODS = 3


class SimWorld(CellWorld):
    """A ``WorkCell`` as a ``World`` (``CellWorld``), settling until its parts rest."""

    cell: WorkCell

    def settle(self, seconds: float) -> None:
        """Run the physics with the arm holding still until every part rests, at most ``seconds`` of world time.

        At rest: the cell's ``parts_at_rest`` (the simulator's velocities: the scene's own state,
        never the robot's input) for ``RESTING_PERIODS`` control periods running. Parts placed on
        the table rest within a few periods.
        """
        periods = max(1, round(seconds / self.cell.robot.arm.control_period_s))
        resting = 0
        for _ in range(periods):
            self.cell.step()
            resting = resting + 1 if self.cell.parts_at_rest() else 0
            if resting >= RESTING_PERIODS:
                return


def open_world(config: CellConfig, gui: bool = False) -> SimWorld:
    """A fresh pybullet cell of ``config`` as a world (a window with ``gui``, which needs a display)."""
    if gui:
        require_display()
    return SimWorld(WorkCell(config, gui=gui))


def camera_view(config: CellConfig) -> CameraView:
    """What the pybullet cell's camera sees, for the plan check: TinyRenderer's calibrated pinhole."""
    return config.camera.view()


class SimulatedRun(CellRun):
    """One tree in one freshly built pybullet cell: a ``CellRun`` on a ``SimWorld``.

    ``SimulatedRun(root, starts, cell_config=..., gui=..., record_dir=..., time_limit_s=..., title=...,
    calibration=...)``: ``gui`` opens the pybullet window, the rest is ``CellRun``'s.
    """

    world: SimWorld
    cell: WorkCell
    open_world = staticmethod(open_world)
    camera_view = staticmethod(camera_view)
