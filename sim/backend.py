"""The simulated work cell as a ``bt_arrange.backends.Backend`` (entry point ``sim``, the default).

Imports nothing heavy at module level: the command line loads this to build its help, and the
pybullet cell is built only when a command runs something.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import py_trees


class SimBackend:
    """Runs trees in a fresh headless pybullet cell: a ``bt_arrange.session.Session`` on a ``SimWorld``."""

    name = "sim"

    def open_run(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
        cell: str = "ideal",
        run_seed: int = 0,
        calibration: str | Path | None = None,
    ) -> Any:
        """A ``SimulatedRun`` (a session on a ``SimWorld``): the plan and scene checked, the cell built, not yet ticked.

        ``cell`` is ``ideal``, ``real`` or a ``.toml`` file (``bt_arrange_sim.realcell``; a bad one is a
        one-line ``PlanError`` before the world is built); ``run_seed`` seeds a real cell's per-run errors;
        ``calibration`` is a ``camera.toml`` (``bt-arrange calibrate``) whose camera the detector uses.
        """
        from bt_arrange.errors import PlanError
        from bt_arrange_sim.cell import CellConfig
        from bt_arrange_sim.realcell import parse_cell
        from bt_arrange_sim.runs import SimulatedRun

        try:
            errors = parse_cell(cell)
        except PlanError as error:
            raise PlanError(f"--cell {cell}: {error}") from error
        config = CellConfig(errors=errors.with_run_seed(run_seed)) if errors.enabled else CellConfig()
        return SimulatedRun(
            root,
            starts,
            cell_config=config,
            gui=gui,
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=_read_calibration(calibration),
        )

    def open_calibration(
        self,
        *,
        views: int = 20,
        cell: str = "ideal",
        run_seed: int = 0,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
    ) -> Any:
        """A ``SimCalibrationRun``: the ChArUco procedure in a cell with the board on the flange, not yet ticked.

        ``views`` poses (``bt_arrange.calibration.board_poses`` over the camera's nominal view);
        ``cell`` as for ``open_run``.
        """
        import dataclasses

        from bt_arrange.calibration import CharucoBoard, board_poses
        from bt_arrange.calibration.board import TABLE_SHEET
        from bt_arrange.calibration.procedure import working_plane_poses
        from bt_arrange.errors import PlanError
        from bt_arrange_sim.calibration import SimCalibrationRun
        from bt_arrange_sim.cell import CellConfig, WorkCell, require_display
        from bt_arrange_sim.realcell import parse_cell
        from bt_arrange_sim.runs import SimWorld

        try:
            errors = parse_cell(cell)
        except PlanError as error:
            raise PlanError(f"--cell {cell}: {error}") from error
        board = CharucoBoard()
        config = CellConfig(errors=errors.with_run_seed(run_seed)) if errors.enabled else CellConfig()
        config = dataclasses.replace(config, board=board)
        # The poses are planned on the camera the cell's software knows: the nominal one. Half the
        # views are the lens's (tilted, over the image), half where the arm works (docs/calibration.md).
        view = config.camera.view()
        poses = board_poses(view, board, config.board_mount, count=views - views // 2)
        plane_poses = working_plane_poses(view, board, config.board_mount, count=views // 2)

        def open_world() -> SimWorld:
            if gui:
                require_display()
            return SimWorld(WorkCell(config, gui=gui))

        return SimCalibrationRun(
            open_world,
            poses,
            board=board,
            cell=cell,
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            plane_poses=plane_poses,
            sheet=TABLE_SHEET,
        )

    def scatter(
        self,
        colours: Sequence[str],
        seed: int,
        avoid: Iterable[Any] = (),
        object_types: Sequence[Any] | None = None,
        names: Sequence[str | None] | None = None,
    ) -> list[Any]:
        """``bt_arrange_sim.scenes.scatter``: parts inside the camera's view and the arm's reach."""
        from bt_arrange_sim.scenes import scatter

        return scatter(list(colours), seed, avoid=list(avoid), object_types=object_types, names=names)

    def check(self) -> Iterator[str]:
        """Start a headless cell and report the TCP pose."""
        import bt_arrange_sim
        from bt_arrange.motion import default_urdf_path

        with bt_arrange_sim.WorkCell() as cell:
            cell.settle(0.1)
            yield f"robot description: {default_urdf_path()}"
            yield f"headless work cell: ok (TCP at {cell.arm.tcp_pose()})"

    def prepare_out(self, path: Path) -> Path:
        """``bt_arrange.session.prepare_record_dir``."""
        from bt_arrange.session import prepare_record_dir

        return prepare_record_dir(path)

    @property
    def experiment(self) -> Any:
        """The module ``bt_arrange_sim.experiment`` (Table 1 and Fig. 4 in simulation)."""
        from bt_arrange_sim import experiment

        return experiment


def _read_calibration(path: str | Path | None) -> Any:
    """``read_calibration(path)``, its error prefixed by the option; None without a path."""
    if path is None:
        return None
    from bt_arrange.calibration import read_calibration
    from bt_arrange.errors import PlanError

    try:
        return read_calibration(path)
    except PlanError as error:
        raise PlanError(f"--calibration {path}: {error}") from error
