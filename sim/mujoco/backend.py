"""The MuJoCo work cell as a ``bt_arrange.backends.Backend`` (entry point ``mujoco``).

Imports nothing heavy at module level (the command line loads it to build its help); mujoco is
imported when a command builds a cell, after ``bt_arrange_sim.mujoco`` has chosen OSMesa.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import py_trees

from bt_arrange_sim.backend import SimBackend, _read_calibration


class MujocoBackend:
    """Runs trees in a fresh headless MuJoCo cell: a ``bt_arrange.session.Session`` on a ``MujocoWorld``."""

    name = "mujoco"

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
        """A ``MujocoRun``: the plan and scene checked, the cell built, not yet ticked (``SimBackend``'s options).

        The MuJoCo cell is the ideal cell: ``cell`` other than ``ideal`` and ``gui`` are one-line
        ``PlanError``s. ``run_seed`` seeds nothing here (the ideal cell draws no per-run error).
        """
        from bt_arrange.errors import PlanError
        from bt_arrange_sim.mujoco.runs import MujocoRun

        _check_cell(cell)
        if gui:
            raise PlanError("--gui: the MuJoCo backend renders headless only; run without --gui")
        return MujocoRun(
            root,
            starts,
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=_read_calibration(calibration),
        )

    def scatter(
        self,
        colours: Sequence[str],
        seed: int,
        avoid: Iterable[Any] = (),
        object_types: Sequence[Any] | None = None,
        names: Sequence[str | None] | None = None,
    ) -> list[Any]:
        """The pybullet cell's scenes (``bt_arrange_sim.scenes.scatter``): the same starts in both engines."""
        return SimBackend().scatter(colours, seed, avoid, object_types=object_types, names=names)

    def check(self) -> Iterator[str]:
        """Build a headless MuJoCo cell, render one frame and report the TCP pose."""
        from bt_arrange.errors import BackendError

        try:
            import mujoco
        except ImportError as error:
            raise BackendError(
                f"the mujoco backend needs the mujoco package: pip install -e '.[mujoco]' ({error})"
            ) from error
        import os

        from bt_arrange.motion import default_urdf_path
        from bt_arrange_sim.mujoco.cell import MujocoCell

        try:
            cell = MujocoCell()
        except Exception as error:  # noqa: BLE001 - a GL library missing shows as many kinds of error
            raise BackendError(
                f"the MuJoCo cell cannot start (MUJOCO_GL={os.environ.get('MUJOCO_GL')}): {error}; "
                "headless rendering needs OSMesa (apt-get install libosmesa6)"
            ) from error
        with cell:
            cell.settle(0.1)
            assert cell.camera is not None
            frame = cell.camera.capture()
            yield f"mujoco {mujoco.__version__}, rendering through MUJOCO_GL={os.environ.get('MUJOCO_GL', '(default)')}"
            yield f"robot description: {default_urdf_path()} (compiled by MuJoCo)"
            size = f"{frame.rgb.shape[1]}x{frame.rgb.shape[0]}"
            yield f"headless MuJoCo cell: ok (TCP at {cell.arm.tcp_pose()}, a {size} frame rendered)"

    def prepare_out(self, path: Path) -> Path:
        """``bt_arrange.session.prepare_record_dir``."""
        from bt_arrange.session import prepare_record_dir

        return prepare_record_dir(path)

    @property
    def experiment(self) -> Any:
        """Table 1 in MuJoCo: the simulator's campaigns, each trial in a MuJoCo cell."""
        from bt_arrange_sim.mujoco.experiment import MUJOCO_EXPERIMENT

        return MUJOCO_EXPERIMENT


def _check_cell(cell: str) -> None:
    from bt_arrange.errors import PlanError

    if cell != "ideal":
        raise PlanError(
            f"--cell {cell}: the MuJoCo backend has the ideal cell only (a real cell's errors are pybullet's)"
        )
