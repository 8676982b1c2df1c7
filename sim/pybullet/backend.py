"""The pybullet work cell as a ``bt_arrange.backends.Backend`` (entry point ``sim``, the default).

Imports nothing heavy at module level: the command line loads this to build its help, and the
pybullet cell is built only when a command runs something. What every engine's backend shares
(the options, scenes, the experiment) is ``bt_arrange_sim.engine.CellBackend``'s.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange_sim.engine import CellBackend


class SimBackend(CellBackend):
    """Runs trees in a fresh pybullet cell (a window with ``gui``): a ``SimulatedRun`` on a ``SimWorld``."""

    name = "sim"

    def open_cell_run(
        self, root: py_trees.behaviour.Behaviour, starts: Iterable[Any], config: Any, **options: Any
    ) -> Any:
        """A ``SimulatedRun`` in a fresh cell of ``config``: plan and scene checked, cell built, not yet ticked."""
        from bt_arrange_sim.pybullet.runs import SimulatedRun

        return SimulatedRun(root, starts, cell_config=config, **options)

    def open_calibration(
        self,
        *,
        views: int = 20,
        cell: str = "ideal",
        run_seed: int = 0,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        speed_fraction: float | None = None,
    ) -> Any:
        """A ``SimCalibrationRun``: the ChArUco procedure in a cell with the board on the flange, not yet ticked.

        ``views`` poses (``bt_arrange.calibration.board_poses`` over the camera's nominal view);
        ``cell`` as for ``open_run``; ``speed_fraction`` (``calibrate --speed-fraction``) slows every motion.
        """
        import dataclasses

        from bt_arrange.calibration import CharucoBoard, board_poses
        from bt_arrange.calibration.board import TABLE_SHEET
        from bt_arrange.calibration.procedure import working_plane_poses
        from bt_arrange.motion.safety import MotionSafety
        from bt_arrange_sim.pybullet.calibration import SimCalibrationRun
        from bt_arrange_sim.pybullet.runs import SimWorld, open_world

        board = CharucoBoard()
        config = dataclasses.replace(self.cell_config(cell, run_seed), board=board)
        # The poses are planned on the camera the cell's software knows: the nominal one. Half the
        # views are the lens's (tilted, over the image), half where the arm works (docs/calibration.md).
        view = config.camera.view()
        poses = board_poses(view, board, config.board_mount, count=views - views // 2)
        plane_poses = working_plane_poses(view, board, config.board_mount, count=views // 2)

        def open_board_world() -> SimWorld:
            return open_world(config, gui)

        return SimCalibrationRun(
            open_board_world,
            poses,
            board=board,
            cell=cell,
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            plane_poses=plane_poses,
            sheet=TABLE_SHEET,
            **({"motion_safety": MotionSafety(speed_fraction)} if speed_fraction is not None else {}),
        )

    def check(self) -> Iterator[str]:
        """Start a headless cell and report the TCP pose."""
        from bt_arrange.motion import default_urdf_path
        from bt_arrange_sim.pybullet.cell import WorkCell

        with WorkCell() as cell:
            cell.settle(0.1)
            yield f"robot description: {default_urdf_path()}"
            yield f"headless work cell: ok (TCP at {cell.arm.tcp_pose()})"
