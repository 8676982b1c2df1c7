"""The engines a campaign's trials run in, found as the command line finds backends: by entry point name.

A trial names its engine (``TrialSpec.engine``, a ``bt_arrange.backends`` entry point such as
``sim`` or ``mujoco``); ``trial_engine`` loads that backend, in whatever process runs the trial,
and the trial opens its run through the backend's ``open_trial_run`` (``TrialEngine``). The
campaign names no engine module: a third engine is one package and one entry point.

A backend's ``experiment`` is ``engine_experiment.EngineExperiment``, the campaign with every
trial in that backend's engine.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, Protocol, runtime_checkable

import py_trees

from bt_arrange import backends
from bt_arrange.errors import BtArrangeError, PlanError

#: The engine of a trial that names none: the default backend's (pybullet's), unnamed in the records.
DEFAULT_ENGINE = backends.DEFAULT_BACKEND


@runtime_checkable
class TrialEngine(Protocol):
    """What the campaign needs of a backend to run a trial in its engine."""

    name: str

    def open_trial_run(
        self, root: py_trees.behaviour.Behaviour, starts: Iterable[Any], *, cell_config: Any, calibration: Any = None
    ) -> Any:
        """A run (with ``cell``, the hooks and ``run()``: ``injection.framework.InjectableRun``) in a fresh cell.

        A recorded campaign (``experiment --record``) also passes ``mcap_path``: the session's
        ``mcap_path`` (``bt_arrange.session.Session``), the trial's Foxglove streams to that file.
        """
        ...

    def check_cells(self, cells: Sequence[str]) -> None:
        """A one-line ``PlanError`` when the engine has not every one of ``cells``."""
        ...


def trial_engine(name: str) -> TrialEngine:
    """The backend called ``name`` as a trial's engine; a one-line ``PlanError`` when it cannot run trials."""
    try:
        backend = backends.load(name)
    except BtArrangeError as error:
        raise PlanError(f"engine {name!r}: {error}") from error
    if not isinstance(backend, TrialEngine):
        raise PlanError(f"backend {name!r} cannot run a campaign's trials (it has no open_trial_run)")
    return backend
