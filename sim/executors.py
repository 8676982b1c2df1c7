"""Where a campaign's trials run: this process, a local process pool, or a Dask cluster.

Every choice is a ``concurrent.futures.Executor`` (or ``None``: one trial after the other in this
process), so ``run_campaign`` does not care which. Dask is an optional extra
(``pip install -e '.[cluster]'``): ``dask.distributed`` is imported only when asked for.

    with open_executor("dask", workers=2) as executor:        # a LocalCluster on this machine
        run_campaign(rows, trials, seed, combos, out_dir, executor=executor)
    with open_executor("dask", scheduler="tcp://10.0.0.5:8786") as executor:   # an existing cluster
        ...
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager

from bt_arrange.errors import PlanError

#: The executors ``--executor`` accepts.
EXECUTORS = ("local", "dask")
#: How long to wait for an existing Dask scheduler to answer, in seconds.
SCHEDULER_TIMEOUT_S = 10.0


def check_choice(kind: str, workers: int, scheduler: str | None) -> None:
    """A ``PlanError`` naming a bad combination of ``--executor``, ``--workers`` and ``--scheduler``."""
    if kind not in EXECUTORS:
        raise PlanError(f"unknown executor {kind!r}; choose from {', '.join(EXECUTORS)}")
    if workers < 1:
        raise PlanError(f"--workers must be at least 1, got {workers}")
    if scheduler is not None:
        if kind != "dask":
            raise PlanError("--scheduler needs --executor dask")
        if not scheduler.strip():
            raise PlanError("--scheduler is empty; give the scheduler's address, e.g. tcp://10.0.0.5:8786")


@contextmanager
def open_executor(kind: str = "local", workers: int = 1, scheduler: str | None = None) -> Iterator[Executor | None]:
    """The executor for ``kind``; shut down (its cluster closed, if it started one) on leaving.

    - ``local``: ``None`` for one worker (trials run in this process, one after the other), else a
      ``ProcessPoolExecutor`` of ``workers`` processes;
    - ``dask`` without ``scheduler``: a ``dask.distributed.LocalCluster`` of ``workers`` worker
      processes with one thread each, no dashboard;
    - ``dask`` with ``scheduler`` (``tcp://host:port``): a client of that running cluster; its
      workers are what the cluster has (``workers`` is not used).
    """
    check_choice(kind, workers, scheduler)
    if kind == "local":
        if workers == 1:
            yield None
            return
        pool = ProcessPoolExecutor(max_workers=workers)
        try:
            yield pool
        finally:
            pool.shutdown(cancel_futures=True)
        return
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise PlanError(
            "--executor dask needs dask.distributed, an optional extra: pip install -e '.[cluster]'"
        ) from None
    cluster = None
    if scheduler is None:
        # One thread per worker: a trial holds a process-wide py_trees blackboard (run_trial locks anyway).
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as error:
            raise PlanError(f"cannot reach the Dask scheduler at {scheduler}: {error}") from None
    try:
        yield client.get_executor()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
