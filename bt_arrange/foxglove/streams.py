"""Where a session's Foxglove streams go: ``run.mcap`` in the record folder, the live server, or both.

Nothing here imports the Foxglove SDK until a run asks for it, so ``bt_arrange.session`` can call
``start`` whether or not the ``foxglove`` extra is installed: without it a recorded run writes
everything but ``run.mcap`` and says so in one line, and ``--foxglove`` is refused before the world
is built (``LiveServer``).

The MCAP file is written into memory while the run goes and to the disk once, whole, at the end
(``bt_arrange.files.write_bytes``), so it is complete or absent like every other recorded file,
and a full disk is the same one-line ending (exit 3).
"""

from __future__ import annotations

import errno
import io
import sys
import time
from typing import Any

from bt_arrange.errors import BtArrangeError

#: The recording's file name in the record folder (a contract: tools and users look for it).
MCAP_NAME = "run.mcap"
#: The command that installs what the recording and the live view need.
INSTALL_HINT = "pip install 'bt-arrange[foxglove]'"
#: The live server's default port (Foxglove's own default).
DEFAULT_PORT = 8765
#: Wall time the live server stays up after the run, so that its last messages are sent before it stops.
LINGER_S = 0.5


class FoxgloveError(BtArrangeError, ValueError):
    """The live view cannot serve: the extra missing, a port out of range or in use."""


def sdk_available() -> bool:
    """True when the Foxglove SDK (the ``foxglove`` extra) is installed."""
    try:
        import foxglove  # noqa: F401
    except ImportError:
        return False
    return True


def check_port(port: object) -> int:
    """``port`` as the live server's port: 0 (any free one, printed) to 65535."""
    if isinstance(port, bool) or not isinstance(port, int):
        raise FoxgloveError(f"Foxglove port {port!r} is not a whole number")
    if not 0 <= port <= 65535:
        raise FoxgloveError(f"Foxglove port {port} is out of range: it must be 0 (any free port) to 65535")
    return port


def port_argument(text: str) -> int:
    """An argparse type: the live server's port."""
    import argparse

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a port number (put the tree file before --foxglove, or give the port)"
        ) from None
    try:
        return check_port(value)
    except FoxgloveError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


class LiveServer:
    """Foxglove's WebSocket protocol on ``bind:port``, read-only: no client may publish or call a service.

    The server advertises no capability but the time (world time, with each ``/tf``): a client's
    advertisement, parameter request or service call is refused by the SDK, which also drops a
    client that sends what is not the protocol. Raises ``FoxgloveError`` (one line) when it cannot serve.
    """

    def __init__(self, port: int = DEFAULT_PORT, *, bind: str = "127.0.0.1") -> None:
        try:
            import foxglove
            from foxglove.websocket import Capability
        except ImportError:
            raise FoxgloveError(f"--foxglove needs the Foxglove SDK: {INSTALL_HINT}") from None
        check_port(port)
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(
                name="bt-arrange",
                host=bind,
                port=port,
                capabilities=[Capability.Time],
                context=self.context,
            )
        except Exception as error:  # the SDK raises its own error type for a port in use or a bad address
            raise FoxgloveError(f"cannot serve Foxglove on {bind}:{port}: {str(error).splitlines()[0]}") from None
        self.bind = bind
        self.port = int(self.server.port)
        from bt_arrange.foxglove.observer import Channels

        #: The run's topics, advertised from now on: a client can subscribe while the world is built.
        self.channels = Channels(self.context)

    @property
    def address(self) -> str:
        """``ws://ADDR:PORT``, what Foxglove's "Open connection" asks for."""
        return f"ws://{self.bind}:{self.port}"

    def close(self) -> None:
        """Stop serving, after ``LINGER_S`` for the last messages (the report, the final poses) to reach the clients."""
        time.sleep(LINGER_S)
        self.server.stop()

    def __enter__(self) -> LiveServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class RunStreams:
    """One session's observer and its MCAP writer (when recording); ``finish`` ends both."""

    def __init__(self, observer: Any, writer: Any, buffer: io.BytesIO | None, context: Any) -> None:
        self.observer = observer
        # The context binds the channels to the writer: it must live as long as the run (the SDK keeps no reference).
        self.context = context
        self._writer = writer
        self._buffer = buffer

    @property
    def records(self) -> bool:
        """True when the streams go to ``run.mcap`` too."""
        return self._buffer is not None

    def finish(self, report: Any) -> None:
        """The last messages (final poses, the report); the MCAP file's summary."""
        self.observer.finish(report)
        if self._writer is not None:
            writer, self._writer = self._writer, None
            try:
                writer.close()
            except Exception as error:  # noqa: BLE001 - the SDK's own error type: the file, not the run, failed
                self.observer.failed = self.observer.failed or f"{type(error).__name__}: {error}"

    def mcap_bytes(self) -> bytes:
        """The finished MCAP file; an ``OSError`` (the record's one-line fault, exit 3) if the recording failed."""
        assert self._buffer is not None and self._writer is None, "finish() first"
        if self.observer.failed is not None:
            raise OSError(errno.EIO, f"the recording stopped ({self.observer.failed})")
        return self._buffer.getvalue()


def start(session: Any) -> RunStreams | None:
    """The streams of ``session`` (its record folder or ``mcap_path``, its ``foxglove_live`` server), or None.

    A recorded run without the SDK writes its other files and says in one line that ``run.mcap`` is not among them.
    """
    live: LiveServer | None = getattr(session, "foxglove_live", None)
    mcap_path = getattr(session, "mcap_path", None)
    recording = session.record_dir is not None or mcap_path is not None
    if not recording and live is None:
        return None
    if not sdk_available():
        name = MCAP_NAME if session.record_dir is not None else mcap_path
        print(f"bt-arrange: {name} not written: it needs the Foxglove SDK ({INSTALL_HINT})", file=sys.stderr)
        return None
    import foxglove

    from bt_arrange.foxglove.observer import Channels, RunObserver

    context = live.context if live is not None else foxglove.Context()
    buffer = writer = None
    if recording:
        buffer = io.BytesIO()
        # One thread: zstd on more would take the cores the physics and the renderer run on (two here).
        options = foxglove.mcap.MCAPWriteOptions(compression_threads=0)
        writer = foxglove.open_mcap(buffer, context=context, writer_options=options)
    channels = live.channels if live is not None else Channels(context)
    observer = RunObserver(session, channels, server=live.server if live is not None else None).attach()
    return RunStreams(observer, writer, buffer, context)
