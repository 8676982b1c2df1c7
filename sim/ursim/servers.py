"""What every socket server of the controller shares: a listening thread, one thread per client, abrupt drops.

Each server listens on its own thread and serves each client on another; a client that
disconnects, or sends nonsense, ends only its own thread. ``ClientRegistry`` knows every live
client socket by server name, so that the faults port can drop them abruptly (a reset, as a
cable pulled out would look to the client).
"""

from __future__ import annotations

import contextlib
import socket
import struct
import sys
import threading


class ClientRegistry:
    """The live client sockets of every server, by server name (``rtde``, ``script``...)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._sockets: dict[str, set[socket.socket]] = {}

    def add(self, server: str, connection: socket.socket) -> None:
        """A client connected to ``server``."""
        with self._lock:
            self._sockets.setdefault(server, set()).add(connection)

    def remove(self, server: str, connection: socket.socket) -> None:
        """A client of ``server`` is gone."""
        with self._lock:
            self._sockets.get(server, set()).discard(connection)

    def drop(self, server: str | None) -> int:
        """Close every client of ``server`` (all servers with None) with a reset; how many were dropped."""
        with self._lock:
            names = list(self._sockets) if server is None else [server]
            victims = [c for name in names for c in self._sockets.get(name, set())]
        for connection in victims:
            with contextlib.suppress(OSError):
                # Linger 0: close sends a reset, not a polite end of stream.
                connection.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                connection.shutdown(socket.SHUT_RDWR)
        return len(victims)


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (address reuse on, so that a restart binds at once)."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind((host, port))
    listener.listen(16)
    return listener


class TcpServer:
    """A listening socket served on its own thread, each client on another (``handle``)."""

    name = "tcp"

    def __init__(self, host: str, port: int, clients: ClientRegistry) -> None:
        self.listener = listen(host, port)
        self.clients = clients
        self._thread = threading.Thread(target=self._accept, name=f"{self.name}-listener", daemon=True)

    def start(self) -> None:
        """Accept clients from now on."""
        self._thread.start()

    def close(self) -> None:
        """Stop listening and drop the clients."""
        with contextlib.suppress(OSError):
            self.listener.close()
        self.clients.drop(self.name)

    def _accept(self) -> None:
        while True:
            try:
                connection, _ = self.listener.accept()
            except OSError:
                return  # closed
            connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            threading.Thread(target=self._serve, args=(connection,), name=f"{self.name}-client", daemon=True).start()

    def _serve(self, connection: socket.socket) -> None:
        self.clients.add(self.name, connection)
        try:
            self.handle(connection)
        except OSError:
            pass  # the client went away: only its thread ends
        except Exception as error:  # noqa: BLE001 - a bug serving one client must not end the controller
            print(f"ursim: {self.name} client error: {type(error).__name__}: {error}", file=sys.stderr)
        finally:
            self.clients.remove(self.name, connection)
            with contextlib.suppress(OSError):
                connection.close()

    def handle(self, connection: socket.socket) -> None:
        """Serve one client until it leaves."""
        raise NotImplementedError


class LineServer(TcpServer):
    """A server of newline-terminated ASCII commands, each answered by ``reply`` (None: no answer)."""

    greeting: str | None = None

    def handle(self, connection: socket.socket) -> None:
        """Read lines and answer each until the client leaves or ``reply`` ends the session.

        The answers to every line of one read go out in one write: a client that sends several
        requests at once (the Robotiq client's ``getVars``) reads all the answers in one read.
        """
        if self.greeting is not None:
            connection.sendall((self.greeting + "\n").encode())
        buffer = b""
        while True:
            chunk = connection.recv(4096)
            if not chunk:
                return
            buffer += chunk
            replies: list[str] = []
            keep_open = True
            while b"\n" in buffer and keep_open:
                line, buffer = buffer.split(b"\n", 1)
                answer = self.reply(line.decode("utf-8", "replace").strip("\r"))
                if answer is not None:
                    reply, keep_open = answer
                    if reply is not None:
                        replies.append(reply)
            if replies:
                connection.sendall("".join(replies).encode())
            if not keep_open:
                return

    def reply(self, line: str) -> tuple[str | None, bool] | None:
        """The bytes to send for ``line`` and whether the session goes on; None to say nothing."""
        raise NotImplementedError
