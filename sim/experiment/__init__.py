"""The paper's evaluation (Sec. 5.3, Table 1, Fig. 4) as reproducible experiment campaigns.

Each row runs its trials with a single-cube arrangement (a random start and a random target per
trial, both seeded from the experiment's seed, the row and the trial number), with the row's
injected errors. A campaign is the product of its lists (the thresholds and the cells); the part's
type (``--object``: the cube, or a built-in type such as the 80 x 40 x 40 mm bar) is one value
for the whole campaign, like the push strategy: every combination gets its own folder with ``trials.jsonl``, the
summaries and Fig. 4. Each finished trial is appended at once; a rerun into the same folder runs only the
trials missing there. Offsets are the camera's measurements, as in the paper; the simulator's
ground truth is recorded beside them.

Trials run through any ``concurrent.futures.Executor`` (``bt_arrange_sim.executors``: a local
process pool, or a Dask cluster through ``Client.get_executor()``). A trial is a pure function of
its ``TrialSpec``, so the records are the same (order and wall times aside) whatever runs them.

The package's rooms, each importing only those above it: ``rows`` (the rows, their labels and
injectors), ``engines`` (a trial's engine, found by its backend's entry point), ``options`` (a
trial's spec, the combinations, the options' parsing and checks), ``trial`` (one trial),
``summaries`` (Table 1, the summary files, Fig. 4, the threshold figure), ``specification``
(``specification.json`` and the check of ``--resume``), ``campaign`` (many trials on an executor,
``trials.jsonl``) and ``engine_experiment`` (a backend's
``experiment``: the campaign in its engine). The names the command line, the executors, the
benchmarks and the tests use are importable from here.
"""

from bt_arrange_sim.experiment.campaign import CampaignIncompleteError, read_trials, run_campaign, run_experiment
from bt_arrange_sim.experiment.options import (
    TrialSpec,
    check_options,
    combinations,
    parse_cells,
    parse_objects,
    parse_rows,
    parse_thresholds,
)
from bt_arrange_sim.experiment.rows import DEFAULT_ROWS, ROW_INJECTORS, ROW_LABELS, ROWS, row_injectors
from bt_arrange_sim.experiment.summaries import markdown_table, summarise
from bt_arrange_sim.experiment.trial import run_trial

__all__ = [
    "CampaignIncompleteError",
    "DEFAULT_ROWS",
    "ROWS",
    "ROW_INJECTORS",
    "ROW_LABELS",
    "TrialSpec",
    "check_options",
    "combinations",
    "markdown_table",
    "parse_cells",
    "parse_objects",
    "parse_rows",
    "parse_thresholds",
    "read_trials",
    "row_injectors",
    "run_campaign",
    "run_experiment",
    "run_trial",
    "summarise",
]
