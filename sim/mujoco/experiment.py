"""Table 1 and the other Sec. 3 rows in MuJoCo: the simulator's campaigns, every trial in a MuJoCo cell.

The campaign code is ``bt_arrange_sim.experiment``'s (the same rows, seeds, starts, targets,
injectors, records and summaries); only the engine differs (``TrialSpec.engine = "mujoco"``), so
the two engines' trials of one seed are the same trials. The MuJoCo cell is the ideal cell: ``--cell``
other than ``ideal`` is refused.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from bt_arrange.errors import PlanError
from bt_arrange_sim import experiment as sim_experiment


class MujocoExperiment:
    """The ``bt_arrange.backends.Experiment`` of the MuJoCo backend."""

    ROWS = sim_experiment.ROWS
    ROW_LABELS = sim_experiment.ROW_LABELS

    def parse_rows(self, text: str) -> list[str]:
        """``bt_arrange_sim.experiment.parse_rows``."""
        return sim_experiment.parse_rows(text)

    def check_options(self, cell: str | Sequence[str] = "ideal", **options: Any) -> None:
        """The simulator's checks, and the ideal cell only."""
        cells = sim_experiment.parse_cells(cell) if isinstance(cell, str) else list(cell)
        others = [c for c in cells if c != "ideal"]
        if others:
            raise PlanError(
                f"--cell {','.join(others)}: the MuJoCo backend has the ideal cell only "
                "(a real cell's errors are pybullet's)"
            )
        sim_experiment.check_options(cell=cell, **options)

    def run_experiment(
        self, rows: Iterable[str], trials: int, seed: int, threshold_mm: float, out_dir: Path, **options: Any
    ) -> list[dict[str, Any]]:
        """``bt_arrange_sim.experiment.run_experiment`` with every trial in a MuJoCo cell."""
        self.check_options(**{k: v for k, v in options.items() if k not in ("on_trial",)})
        return sim_experiment.run_experiment(rows, trials, seed, threshold_mm, out_dir, engine="mujoco", **options)

    def markdown_table(self, summary: list[dict[str, Any]]) -> str:
        """Table 1 as Markdown (``bt_arrange_sim.experiment.markdown_table``)."""
        return sim_experiment.markdown_table(summary)


MUJOCO_EXPERIMENT = MujocoExperiment()
