"""An unreachable Dask scheduler: one line and exit 2 before the progress bar is drawn, never a traceback.

Refused at once (nothing listens), or something that is not a Dask scheduler answering (its reply
made Dask's client read a frame of exabytes): both are checked before the campaign starts. A real
scheduler passes the check.
"""

from __future__ import annotations

import socket
import threading
from pathlib import Path

import pytest

from bt_arrange import cli
from bt_arrange.errors import PlanError
from bt_arrange_sim import executors

pytest.importorskip("distributed")


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def not_dask() -> str:
    """The address of a service that is not a Dask scheduler (it answers every connection with HTTP)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    stop = threading.Event()

    def serve() -> None:
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                connection, _ = server.accept()
            except OSError:
                continue
            with connection:
                connection.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 4)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join(timeout=5)
    server.close()


def _experiment(scheduler: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]):  # noqa: ANN202
    from bt_arrange_sim.experiment import campaign

    def moved(*args: object, **kwargs: object) -> None:
        raise AssertionError("a trial ran before the scheduler was checked")

    monkeypatch.setattr(campaign, "run_trial", moved)
    code = cli.main(["experiment", "--executor", "dask", "--scheduler", scheduler, "--trials", "1",
                     "--out", str(tmp_path / "out")])  # fmt: skip
    return code, capsys.readouterr()


def test_a_scheduler_nobody_listens_at_is_one_line_before_the_progress_bar(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    scheduler = f"tcp://127.0.0.1:{_free_port()}"
    # Dask's own client would retry for this long; the check must not wait for it.
    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT_S", 600.0)
    code, captured = _experiment(scheduler, tmp_path, monkeypatch, capsys)
    assert code == 2
    assert captured.err == (
        f"bt-arrange: error: cannot reach the Dask scheduler at {scheduler}: Connection refused (within 3 s); "
        "is it running (dask scheduler), and is the address right?\n"
    ), "one line, and no progress bar before it"
    assert not (tmp_path / "out").exists(), "nothing begun"


def test_a_service_that_is_not_a_dask_scheduler_is_one_line_not_a_traceback(
    not_dask: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT_S", 5.0)
    code, captured = _experiment(not_dask, tmp_path, monkeypatch, capsys)
    assert code == 2
    assert captured.err.count("\n") == 1 and "trials" not in captured.err, captured.err
    assert captured.err.startswith(f"bt-arrange: error: cannot reach the Dask scheduler at {not_dask}: "), captured.err
    assert captured.err.endswith("; is a Dask scheduler there?\n"), captured.err


def test_a_running_scheduler_passes_the_check() -> None:
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        executors.probe_scheduler(cluster.scheduler_address)


@pytest.mark.parametrize(
    ("address", "expected"),
    [
        ("tcp://10.0.0.5:8786", ("10.0.0.5", 8786)),
        ("10.0.0.5:9000", ("10.0.0.5", 9000)),
        ("tls://node-3", ("node-3", 8786)),
        ("tcp://[::1]:8786", ("::1", 8786)),
        ("ucx://10.0.0.5:13337", None),
    ],
)
def test_scheduler_addresses_are_read_as_dask_reads_them(address: str, expected: tuple[str, int] | None) -> None:
    assert executors.scheduler_host_port(address) == expected


def test_an_address_that_is_not_one_is_named() -> None:
    with pytest.raises(PlanError, match=r"--scheduler tcp://host:http: 'http' is not a port number"):
        executors.scheduler_host_port("tcp://host:http")
