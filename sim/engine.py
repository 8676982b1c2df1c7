"""What every simulated engine's backend shares: the ``--cell`` and ``--calibration`` options, scenes, the experiment.

An engine's backend (``bt_arrange_sim.pybullet.backend.SimBackend``,
``bt_arrange_sim.mujoco.backend.MujocoBackend``) subclasses ``CellBackend`` and says only what is
its own: how it opens a run in a fresh cell of a ``CellConfig`` (``open_cell_run``), how
``bt-arrange info`` checks it, and which cells it has (``ideal_cell_only``). It is found by the
command line and by the campaign alike through its ``bt_arrange.backends`` entry point: a third
engine is one package and one entry point.

Imports nothing heavy at module level: the command line loads the backends to build its help.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import py_trees


class CellBackend:
    """A ``bt_arrange.backends.Backend`` that runs trees in a fresh simulated cell (one engine's)."""

    name = ""
    #: The speed fraction of a run without ``--speed-fraction``: the simulators run the motions as planned.
    default_speed_fraction = 1.0
    #: Why a cell other than ``ideal`` is refused (the end of a one-line ``PlanError``), or None: every cell.
    ideal_cell_only: str | None = None

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
        inject: Sequence[str] = (),
        inject_seed: int = 0,
        speed_fraction: float | None = None,
    ) -> Any:
        """A run (a ``world.CellRun``): the plan and scene checked, the cell built, not yet ticked.

        ``cell`` is ``ideal``, ``real`` or a ``.toml`` file (``bt_arrange_sim.realcell``; a bad one is a
        one-line ``PlanError`` before the world is built); ``run_seed`` seeds a real cell's per-run errors;
        ``calibration`` is a ``camera.toml`` (``bt-arrange calibrate``) whose camera the detector uses.
        ``inject`` names errors of ``injectable_errors`` (``run --inject``), put into every part the tree
        picks and drawn from ``inject_seed`` (``injection.named``); the report lists them (``injected``).
        ``speed_fraction`` (``run --speed-fraction``) slows every motion (``bt_arrange.motion.safety.MotionSafety``).
        """
        if inject:
            from bt_arrange_sim.injection.named import check_named, parse_errors

            # An unknown name, or a tree that names no part to put them in, is refused before the world is built.
            inject = parse_errors(inject)
            check_named(root)
        config = self.cell_config(cell, run_seed)
        run = self.open_cell_run(
            root,
            starts,
            config,
            gui=gui,
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=read_calibration_option(calibration, config.camera),
            **({"motion_safety": _motion_safety(speed_fraction)} if speed_fraction is not None else {}),
        )
        if inject:
            try:
                attach_errors(run, inject, inject_seed)
            except BaseException:
                run.close()
                raise
        return run

    @property
    def injectable_errors(self) -> tuple[str, ...]:
        """The errors ``open_run(inject=...)`` knows: the paper's Sec. 3, by the names of ``experiment --rows``."""
        from bt_arrange_sim.injection.named import ERRORS

        return ERRORS

    def open_cell_run(
        self, root: py_trees.behaviour.Behaviour, starts: Iterable[Any], config: Any, **options: Any
    ) -> Any:
        """The engine's run in a fresh cell of ``config`` (``options``: ``gui``, and ``world.CellRun``'s)."""
        raise NotImplementedError(f"backend {self.name!r} opens no run")

    def open_trial_run(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        cell_config: Any,
        calibration: Any = None,
        mcap_path: Path | None = None,
    ) -> Any:
        """A campaign's trial (``experiment.engines.TrialEngine``): headless, in ``cell_config``.

        Unrecorded but for ``mcap_path`` (``experiment --record``): the trial's Foxglove streams, that file alone.
        """
        recording = {"mcap_path": mcap_path} if mcap_path is not None else {}
        return self.open_cell_run(root, starts, cell_config, calibration=calibration, **recording)

    def cell_config(self, cell: str, run_seed: int = 0) -> Any:
        """The ``CellConfig`` of ``--cell`` (a real cell's per-run errors seeded by ``run_seed``), or a PlanError."""
        from bt_arrange.errors import PlanError
        from bt_arrange_sim.config import CellConfig
        from bt_arrange_sim.realcell import parse_cell

        self.check_cells([cell])
        try:
            errors = parse_cell(cell)
        except PlanError as error:
            raise PlanError(f"--cell {cell}: {error}") from error
        return CellConfig(errors=errors.with_run_seed(run_seed)) if errors.enabled else CellConfig()

    def check_ready(self) -> None:
        """A one-line error when the engine cannot start here (a library missing); nothing by default."""

    def check_cells(self, cells: Sequence[str]) -> None:
        """A one-line ``PlanError`` when this engine has not every one of ``cells``."""
        from bt_arrange.errors import PlanError

        others = [c for c in cells if c != "ideal"]
        if self.ideal_cell_only is not None and others:
            raise PlanError(f"--cell {','.join(others)}: {self.ideal_cell_only}")

    def scatter(
        self,
        colours: Sequence[str],
        seed: int,
        avoid: Iterable[Any] = (),
        object_types: Sequence[Any] | None = None,
        names: Sequence[str | None] | None = None,
    ) -> list[Any]:
        """``bt_arrange_sim.scenes.scatter``: the same starts in every engine."""
        from bt_arrange_sim.scenes import scatter

        return scatter(list(colours), seed, avoid=list(avoid), object_types=object_types, names=names)

    def puzzle_scene(
        self, targets: Sequence[Any], puzzles: Sequence[Any], seed: int, *, starts: Sequence[Any] | None = None
    ) -> list[Any]:
        """``bt_arrange_sim.puzzles.puzzle_scene``: each puzzle's slab broken from ``seed``, its pieces scattered."""
        from bt_arrange_sim.puzzles import puzzle_scene

        return puzzle_scene(targets, puzzles, seed, starts=starts)

    def check(self) -> Iterator[str]:
        """Lines for ``bt-arrange info``: the engine starts."""
        raise NotImplementedError(f"backend {self.name!r} has no check")

    def prepare_out(self, path: Path) -> Path:
        """``bt_arrange.session.prepare_record_dir``."""
        from bt_arrange.session import prepare_record_dir

        return prepare_record_dir(path)

    @property
    def experiment(self) -> Any:
        """Table 1 and the Sec. 3 rows with every trial in this engine (``experiment.engine_experiment``)."""
        from bt_arrange_sim.experiment.engine_experiment import EngineExperiment

        return EngineExperiment(self)


def _motion_safety(speed_fraction: float) -> Any:
    from bt_arrange.motion.safety import MotionSafety

    return MotionSafety(speed_fraction=speed_fraction)


def attach_errors(run: Any, errors: Sequence[str], seed: int) -> None:
    """Put ``errors`` into every part ``run`` picks (``injection.named.Injection``); the report lists them."""
    from bt_arrange_sim.injection.named import Injection

    injection = Injection(run, errors, seed)

    def add_to_report(report: Any) -> None:
        report.injected = injection.records()

    run.report_hooks.append(add_to_report)


def read_calibration_option(path: str | Path | None, camera: Any = None) -> Any:
    """``read_calibration(path)``, its error prefixed by the option; None without a path.

    With ``camera`` (a ``config.CameraConfig``) the calibration must be for its image size too.
    """
    if path is None:
        return None
    from bt_arrange.calibration.file import read_calibration_option as read

    return read(path, *((camera.width_px, camera.height_px) if camera is not None else ()))
