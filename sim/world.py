"""A simulated cell as a ``bt_arrange.session.World``, and a run in a fresh one: what both engines' runs share.

``CellWorld`` puts any engine's cell behind the ``World`` protocol (its robot, clock and camera,
and the engine's ground truth); ``CellRun`` is a ``Session`` on one, built from a ``CellConfig``,
with the attributes the experiment, the injectors and the tests use (``cell``, ``context``, the
hooks). An engine subclasses both: its world says how its scene settles, its run how its cell
is built and what its camera sees (``bt_arrange_sim.pybullet.runs``, ``bt_arrange_sim.mujoco.runs``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange.calibration import CameraCalibration
from bt_arrange.perception import ColourTable
from bt_arrange.plancheck import CameraView
from bt_arrange.robot import CameraFrame, Clock, Robot
from bt_arrange.session import GroundTruth, Session, World
from bt_arrange_sim.config import CellConfig


class CellWorld:
    """A simulated cell as a ``World``: its robot, clock and camera, and the engine's ground truth.

    ``cell`` is the engine's cell itself (``injection.framework.InjectableCell``), for what only a
    simulator can do (the error injectors). ``settle`` runs the cell for the whole time asked; an
    engine that can tell when its parts rest stops sooner.
    """

    def __init__(self, cell: Any) -> None:
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
        """Run the physics for ``seconds`` of world time with the arm holding still."""
        self.cell.settle(seconds)

    def step(self) -> None:
        """One control period (several physics steps)."""
        self.cell.step()

    def capture_image(self) -> CameraFrame:
        """A frame of the cell's top camera."""
        return self.cell.camera.capture()

    def close(self) -> None:
        """Free the engine's resources (its physics client, its renderer)."""
        self.cell.close()

    def part_names(self) -> list[str]:
        """Every part in the cell, by name."""
        return list(self.cell.cubes)

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        """The simulator's true ``(x_m, y_m, yaw_rad)`` of a part (yaw folded to its symmetry)."""
        return self.cell.cube_planar_truth(name)


class CellRun(Session):
    """One tree in one freshly built cell of an engine: a ``Session`` on a ``CellWorld``.

    ``transition_hooks`` are called with every status change (e.g. to inject an error through
    the cell's ground-truth access at the moment the paper names); ``tick_hooks`` after every tick.
    The plan, the scene and the options are checked before the cell is built. ``calibration``
    (``bt_arrange.calibration.read_calibration``) makes the detector use a calibration file's camera.
    ``open_world`` builds the engine's world from the configuration; ``view`` is what its camera sees.
    """

    world: CellWorld

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        open_world: Callable[[CellConfig], CellWorld],
        view: Callable[[CellConfig], CameraView],
        *,
        cell_config: CellConfig | None = None,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
        calibration: CameraCalibration | None = None,
    ) -> None:
        config = cell_config or CellConfig()

        def open_configured_world() -> World:
            return open_world(config)

        super().__init__(
            root,
            starts,
            open_configured_world,
            view=view(config),
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=calibration,
        )

    @property
    def cell(self) -> Any:
        """The engine's cell the tree runs in (ground truth and error injection go through it)."""
        return self.world.cell

    def __enter__(self) -> CellRun:
        return self
