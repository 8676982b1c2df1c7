"""A backend's ``experiment``: the campaign's functions with every trial in that backend's engine.

The engine's own refusals (``check_cells``: a cell it has not) come before anything runs.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from bt_arrange_sim.experiment.campaign import run_experiment
from bt_arrange_sim.experiment.engines import TrialEngine
from bt_arrange_sim.experiment.options import check_options, parse_cells, parse_rows
from bt_arrange_sim.experiment.rows import DEFAULT_ROWS, ROW_LABELS, ROWS
from bt_arrange_sim.experiment.summaries import markdown_table


class EngineExperiment:
    """The ``bt_arrange.backends.Experiment`` of an engine's backend: the campaign with every trial in it.

    The rows, seeds, starts, targets, injectors, records and summaries are the campaign's, so the
    engines' trials of one seed are the same trials.
    """

    def __init__(self, engine: TrialEngine) -> None:
        self.engine = engine
        self.ROWS = ROWS
        self.DEFAULT_ROWS = DEFAULT_ROWS
        self.ROW_LABELS = ROW_LABELS

    def parse_rows(self, text: str) -> list[str]:
        """``bt_arrange_sim.experiment.parse_rows``."""
        return parse_rows(text)

    def check_options(self, cell: str | Sequence[str] = "ideal", **options: Any) -> None:
        """The campaign's checks (``experiment.check_options``), the engine's cells first.

        First of all, that the engine starts here (``check_ready``: MuJoCo's OpenGL), so a missing
        library is one line before the progress bar, not an errored record in every trial.
        """
        check_ready = getattr(self.engine, "check_ready", None)
        if check_ready is not None:
            check_ready()
        self.engine.check_cells(parse_cells(cell) if isinstance(cell, str) else list(cell))
        check_options(cell=cell, **options)

    def run_experiment(
        self, rows: Iterable[str], trials: int, seed: int, threshold_mm: float, out_dir: Path, **options: Any
    ) -> list[dict[str, Any]]:
        """``bt_arrange_sim.experiment.run_experiment`` with every trial in this engine."""
        if "cell" in options:
            self.check_options(cell=options["cell"])
        return run_experiment(rows, trials, seed, threshold_mm, out_dir, engine=self.engine.name, **options)

    def markdown_table(self, summary: list[dict[str, Any]]) -> str:
        """Table 1 as Markdown (``bt_arrange_sim.experiment.markdown_table``)."""
        return markdown_table(summary)
