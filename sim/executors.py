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
#: How long the check before a campaign waits for the scheduler's port to take a connection, in seconds.
PROBE_TIMEOUT_S = 3.0
#: Dask's default scheduler port, when an address names none.
DASK_PORT = 8786


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


def scheduler_host_port(scheduler: str) -> tuple[str, int] | None:
    """``(host, port)`` of a ``tcp://`` or ``tls://`` scheduler address (``tcp://10.0.0.5:8786``, ``[::1]:8786``).

    None for another transport (``ucx://``, ``inproc://``), which only Dask itself can try; a
    ``PlanError`` for an address that is not one.
    """
    text = scheduler.strip()
    scheme, _, rest = text.rpartition("://")
    if scheme and scheme not in ("tcp", "tls"):
        return None
    rest = rest.split("/", 1)[0]
    if rest.startswith("["):  # [IPv6]:port
        host, _, port_text = rest[1:].partition("]")
        port_text = port_text.removeprefix(":")
    else:
        host, _, port_text = rest.rpartition(":") if ":" in rest else (rest, "", "")
    try:
        port = int(port_text) if port_text else DASK_PORT
    except ValueError:
        raise PlanError(f"--scheduler {scheduler}: {port_text!r} is not a port number") from None
    if not host or not 0 < port < 65536:
        raise PlanError(f"--scheduler {scheduler} is not an address; give one such as tcp://10.0.0.5:8786")
    return host, port


def probe_scheduler(scheduler: str, timeout_s: float = PROBE_TIMEOUT_S) -> None:
    """A one-line ``PlanError`` when nothing takes a connection at the scheduler's address (within ``timeout_s``).

    Run before a campaign draws its progress bar: Dask's own client retries for
    ``SCHEDULER_TIMEOUT_S`` even when the connection is refused at once.
    """
    address = scheduler_host_port(scheduler)
    if address is not None:
        import socket

        try:
            with socket.create_connection(address, timeout=timeout_s):
                pass
        except OSError as error:
            reason = "no answer" if isinstance(error, TimeoutError) else (error.strerror or str(error))
            raise PlanError(
                f"cannot reach the Dask scheduler at {scheduler}: {reason} (within {timeout_s:g} s); "
                "is it running (dask scheduler), and is the address right?"
            ) from None
    # Something answers: that it is a Dask scheduler only Dask's handshake tells (another service
    # there made the client read its reply as a frame of exabytes).
    from dask.distributed import Client

    try:
        Client(scheduler, timeout=SCHEDULER_TIMEOUT_S).close()
    except Exception as error:  # noqa: BLE001 - whatever the client met, the campaign cannot use it
        raise _unreachable(scheduler, error) from None


def _unreachable(scheduler: str, error: BaseException) -> PlanError:
    cause = " ".join(f"{type(error).__name__}: {error}".split())[:300]
    return PlanError(f"cannot reach the Dask scheduler at {scheduler}: {cause}; is a Dask scheduler there?")


def check_dask(scheduler: str | None) -> None:
    """``--executor dask`` checked before anything runs: dask.distributed installed, the scheduler reachable."""
    import importlib.util

    if importlib.util.find_spec("distributed") is None:
        raise PlanError("--executor dask needs dask.distributed, an optional extra: pip install -e '.[cluster]'")
    if scheduler is not None:
        probe_scheduler(scheduler)


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
        except Exception as error:  # noqa: BLE001 - not only OSError: a reply that is not Dask's, a MemoryError
            raise _unreachable(scheduler, error) from None
    try:
        yield client.get_executor()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
