"""The pybullet work cell as a ``bt_arrange.session.World``, and ``SimulatedRun``: a session in a fresh cell.

Everything that is the same for every backend (the plan check, the runner, the transition log,
the replay page, the per-object report) is ``bt_arrange.session``'s. Here stays what is pybullet's:
``SimWorld`` (a ``WorkCell`` behind the ``World`` protocol, with the simulator's ground truth), and
``SimulatedRun``, the session on a cell built from a ``CellConfig``, kept with its constructor and
attributes (``cell``, ``context``, the hooks, ...) for the experiment, the injectors and the tests.

The names other modules import from here (``ObjectOutcome``, ``SimulationReport``, ``REASON_TYPES``,
``check_colours_apart``, ``prepare_record_dir``, ``SETTLE_S``) are the session's.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange.calibration import CameraCalibration
from bt_arrange.geometry import Pose
from bt_arrange.perception import ColourTable
from bt_arrange.robot import CameraFrame, Clock, Robot
from bt_arrange.session import (
    REASON_TYPES,
    SETTLE_S,
    GroundTruth,
    ObjectOutcome,
    Session,
    SessionReport,
    World,
    check_colours_apart,
    prepare_record_dir,
)
from bt_arrange_sim.cell import CellConfig, WorkCell, require_display

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


class SimWorld:
    """A ``WorkCell`` as a ``World``: its robot, clock and camera, and the simulator's ground truth.

    ``cell`` is the pybullet cell itself, for what only a simulator can do (the error injectors).
    """

    def __init__(self, cell: WorkCell) -> None:
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
        """The simulator knows where every part is: this world is its own ground truth."""
        return self

    def place(self, starts: Sequence[Any], colours: ColourTable) -> None:
        """Paint with ``colours`` and put the parts on the table, resting, where they start."""
        self.cell.colours = colours
        self.cell.add_cubes(starts)

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

    def step(self) -> None:
        """One control period (several physics steps)."""
        self.cell.step()

    def capture_image(self) -> CameraFrame:
        """A frame of the cell's top camera."""
        return self.cell.camera.capture()

    def close(self) -> None:
        """Disconnect the physics client."""
        self.cell.close()

    def part_names(self) -> list[str]:
        """Every part in the cell, by name."""
        return list(self.cell.cubes)

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        """The simulator's true ``(x_m, y_m, yaw_rad)`` of a part (yaw folded to its symmetry)."""
        return self.cell.cube_planar_truth(name)

    def pose_truth(self, name: str) -> Pose:
        """The simulator's true 6-D pose of a part's centre (the Foxglove recording draws parts lifted too)."""
        return self.cell.cube_pose_truth(name)


class SimulatedRun(Session):
    """One tree in one freshly built cell: a ``Session`` on a ``SimWorld``.

    ``transition_hooks`` are called with every status change (e.g. to inject an error through
    the cell's ground-truth access at the moment the paper names); ``tick_hooks`` after every tick.
    The plan, the scene and the options are checked before the cell is built. ``calibration``
    (``bt_arrange.calibration.read_calibration``) makes the detector use a calibration file's camera.
    """

    world: SimWorld

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        cell_config: CellConfig | None = None,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
        calibration: CameraCalibration | None = None,
    ) -> None:
        config = cell_config or CellConfig()

        def open_world() -> World:
            if gui:
                require_display()
            return SimWorld(WorkCell(config, gui=gui))

        super().__init__(
            root,
            starts,
            open_world,
            view=config.camera.view(),
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=calibration,
        )

    @property
    def cell(self) -> WorkCell:
        """The pybullet cell the tree runs in (ground truth and error injection go through it)."""
        return self.world.cell

    def __enter__(self) -> SimulatedRun:
        return self
