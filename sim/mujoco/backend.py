"""The MuJoCo work cell as a ``bt_arrange.backends.Backend`` (entry point ``mujoco``).

Imports nothing heavy at module level (the command line loads it to build its help); mujoco is
imported when a command builds a cell, after ``bt_arrange_sim.mujoco`` has chosen OSMesa. What
every engine's backend shares (the options, scenes, the experiment) is
``bt_arrange_sim.engine.CellBackend``'s.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

import py_trees

from bt_arrange_sim.engine import CellBackend


class MujocoBackend(CellBackend):
    """Runs trees in a fresh headless MuJoCo cell: a ``MujocoRun`` on a ``MujocoWorld``. The ideal cell only."""

    name = "mujoco"
    ideal_cell_only = "the MuJoCo backend has the ideal cell only (a real cell's errors are pybullet's)"

    def open_cell_run(
        self, root: py_trees.behaviour.Behaviour, starts: Iterable[Any], config: Any, *, gui: bool = False,
        **options: Any,
    ) -> Any:  # fmt: skip
        """A ``MujocoRun`` in a fresh cell of ``config``; ``gui`` is a one-line ``PlanError`` (headless only)."""
        from bt_arrange.errors import PlanError
        from bt_arrange_sim.mujoco.gl import check_gl

        if gui:
            raise PlanError("--gui: the MuJoCo backend renders headless only; run without --gui")
        check_gl()  # one line naming what to install, before the plan check and the world
        from bt_arrange_sim.mujoco.runs import MujocoRun

        return MujocoRun(root, starts, cell_config=config, **options)

    def check_ready(self) -> None:
        """A one-line ``BackendError`` when mujoco or its OpenGL does not load (``gl.check_gl``)."""
        from bt_arrange_sim.mujoco.gl import check_gl

        check_gl()

    def check(self) -> Iterator[str]:
        """Build a headless MuJoCo cell, render one frame and report the TCP pose."""
        import os

        from bt_arrange.motion import default_urdf_path
        from bt_arrange_sim.mujoco.cell import MujocoCell
        from bt_arrange_sim.mujoco.gl import check_gl, gl_error, import_mujoco

        mujoco = import_mujoco()
        check_gl()
        try:
            cell = MujocoCell()
        except Exception as error:  # noqa: BLE001 - a GL library missing shows as many kinds of error
            raise gl_error(error) from error
        with cell:
            cell.settle(0.1)
            assert cell.camera is not None
            frame = cell.camera.capture()
            yield f"mujoco {mujoco.__version__}, rendering through MUJOCO_GL={os.environ.get('MUJOCO_GL', '(default)')}"
            yield f"robot description: {default_urdf_path()} (compiled by MuJoCo)"
            size = f"{frame.rgb.shape[1]}x{frame.rgb.shape[0]}"
            yield f"headless MuJoCo cell: ok (TCP at {cell.arm.tcp_pose()}, a {size} frame rendered)"
