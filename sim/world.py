"""A simulated cell as a ``bt_arrange.session.World``, and a run in a fresh one: what both engines' runs share.

``CellWorld`` puts any engine's cell behind the ``World`` protocol (its robot, clock and camera,
and the engine's ground truth); ``CellRun`` is a ``Session`` on one, built from a ``CellConfig``,
with the attributes the experiment, the injectors and the tests use (``cell``, ``context``, the
hooks). An engine subclasses both: its world may say how its scene settles, its run says how its
cell is built and what its camera sees (``bt_arrange_sim.pybullet.runs``, ``bt_arrange_sim.mujoco.runs``).
"""

from __future__ import annotations

import inspect
from collections.abc import Iterable, Sequence
from typing import Any

import py_trees

from bt_arrange.geometry import Pose
from bt_arrange.perception import ColourTable
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.robot import CameraFrame, Clock, Robot
from bt_arrange.session import GroundTruth, Session, World
from bt_arrange.uncertainty import IDEAL_CELL_CAMERA_MM
from bt_arrange_sim.config import CellConfig


class CellWorld:
    """A simulated cell as a ``World``: its robot, clock and camera, and the engine's ground truth.

    ``cell`` is the engine's cell itself (``injection.framework.InjectableCell``), for what only a
    simulator can do (the error injectors). ``settle`` runs the cell for the whole time asked; an
    engine that can tell when its parts rest stops sooner.
    """

    def __init__(self, cell: Any) -> None:
        self.cell = cell
        #: Each puzzle piece's puzzle and home by its part's name (evaluation only; ``bt_arrange_sim.puzzles``).
        self.homes: dict[str, tuple[str, tuple[float, float, float]]] = {}

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
        from bt_arrange_sim.puzzles import homes_of

        self.cell.colours = colours
        self.cell.add_parts(starts)
        self.homes = homes_of(starts)

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
        return list(self.cell.parts)

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        """The simulator's true ``(x_m, y_m, yaw_rad)`` of a part (yaw folded to its symmetry)."""
        return self.cell.part_planar_truth(name)

    @property
    def camera_margin_mm(self) -> float | None:
        """The camera's measured error (mm, ``bt_arrange.uncertainty``): the ideal cell's; None in a real cell."""
        errors = self.cell.config.errors
        return None if errors.enabled else IDEAL_CELL_CAMERA_MM

    def home_pose(self, name: str) -> tuple[str, tuple[float, float, float]] | None:
        """A puzzle piece's puzzle and home ``(x_m, y_m, yaw_rad)`` (where the break says it belongs), else None."""
        return self.homes.get(name)

    def pose_truth(self, name: str) -> Pose:
        """The simulator's true 6-D pose of a part's centre (the Foxglove recording draws parts lifted too)."""
        return self.cell.part_pose_truth(name)


class CellRun(Session):
    """One tree in one freshly built cell of an engine: a ``Session`` on a ``CellWorld``.

    ``transition_hooks`` are called with every status change (e.g. to inject an error through
    the cell's ground-truth access at the moment the paper names); ``tick_hooks`` after every tick.
    The plan, the scene and the options are checked before the cell is built. ``calibration``
    (``bt_arrange.calibration.read_calibration``) makes the detector use a calibration file's camera.

    Of ``options``, ``SESSION_OPTIONS`` are the session's; the others are the engine's, for its
    world (``open_world``: pybullet's ``gui``, MuJoCo's ``physics``), checked before anything runs.
    An engine's run says only how it builds its world and what its camera sees (``camera_view``).
    """

    world: CellWorld
    SESSION_OPTIONS = ("record_dir", "time_limit_s", "title", "calibration", "mcap_path", "motion_safety")

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        cell_config: CellConfig | None = None,
        **options: Any,
    ) -> None:
        config = cell_config or CellConfig()
        session = {key: options.pop(key) for key in self.SESSION_OPTIONS if key in options}
        # An unknown option is refused now, not when the world is built after the plan's checks.
        inspect.signature(self.open_world).bind(config, **options)

        def open_configured_world() -> World:
            return self.open_world(config, **options)

        super().__init__(root, starts, open_configured_world, view=self.camera_view(config), **session)

    @staticmethod
    def open_world(config: CellConfig) -> CellWorld:
        """A fresh world of the engine's cell built from ``config``."""
        raise NotImplementedError

    @staticmethod
    def camera_view(config: CellConfig) -> CameraView:
        """What the engine's camera sees, for the plan check."""
        raise NotImplementedError

    @property
    def cell(self) -> Any:
        """The engine's cell the tree runs in (ground truth and error injection go through it)."""
        return self.world.cell

    def __enter__(self) -> CellRun:
        return self
