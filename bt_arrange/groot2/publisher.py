"""A read-only Groot2 publisher for a py_trees tree: BehaviorTree.CPP 4's protocol on ZeroMQ.

``Groot2Publisher(root, port)`` numbers the nodes as BehaviorTree.CPP does (1, 2, ... top-down:
a parent before its children), writes the tree as BehaviorTree.CPP XML with each node's ``_uid``
and the ``TreeNodesModel`` (``bt_arrange.xmltree.to_xml``), binds the request/reply socket on
``port`` and the publisher socket on ``port + 1`` (``ADDR:PORT``, ``127.0.0.1`` unless told), and
answers requests on its own thread. The tree's thread only writes status bytes into a buffer:

- ``on_transition(transition)``: a session's transition hook (``session.transition_hooks``), fed
  with the changes the ``TransitionLog`` visitor sees, so the publisher never walks the tree;
- ``refresh(root)``: a walk over every node, for a tree ticked without a session.

A tree that grows while it runs (a puzzle's ``ArrangeSolved`` builds its pieces' subtrees once the
solve is known) is numbered again when either sees a node it does not know: the XML then holds
the new nodes, the statuses shown so far are kept, and every reply's header carries a new tree
UUID, which tells a client that the tree it holds is not the one served (fetch it again).

Statuses are shown as BehaviorTree.CPP's publisher shows its own tree's: when a control node or a
decorator finishes, its children are reset (``IDLE``, remembering what they were: 10 + status),
a decorator resets its child as soon as the child finishes, and the root is reset when it
finishes. py_trees keeps those nodes' last status until their parent starts them again; the code
"idle, was SUCCESS" keeps what they ended with.

A client can neither slow nor stop the tree: the server thread never holds the buffer's lock
while it talks, replies are sent with a timeout, and a client that vanishes mid-request leaves
its reply to ZeroMQ to drop. Requests that would change the tree (hooks, breakpoints, status
overrides) get the protocol's error reply.
"""

from __future__ import annotations

import collections
import dataclasses
import enum
import math
import threading
import time
import uuid
from collections.abc import Mapping
from typing import Any

import py_trees

from bt_arrange.errors import BtArrangeError
from bt_arrange.groot2 import protocol
from bt_arrange.groot2.protocol import DEFAULT_PORT

#: Wall time [s] the server thread waits for a request before it looks whether it should stop.
POLL_S = 0.1
#: Wall time [ms] a reply may wait to be sent (BehaviorTree.CPP's ``sndtimeo``).
SEND_TIMEOUT_MS = 1000
#: Transitions kept while recording (BehaviorTree.CPP keeps 1000).
RECORDED_TRANSITIONS = 1000
#: The most nodes a status buffer can name (UIDs are ``uint16``).
MAX_NODES = 0xFFFF

INSTALL_HINT = "pip install 'bt-arrange[groot]'"


@dataclasses.dataclass(frozen=True)
class SubTreeNode:
    """A part's ``<SubTree>`` in the Groot2 view: a node of BehaviorTree.CPP's with no py_trees node of its own.

    It shows the status of ``top``, the part's top node (the decorator BehaviorTree.CPP's
    ``SubTreeNode`` is: it resets its tree once that finishes).
    """

    top: py_trees.behaviour.Behaviour


class GrootError(BtArrangeError, ValueError):
    """The publisher cannot serve: a port out of range or in use, an address not of this machine, pyzmq missing."""


def check_port(port: object) -> int:
    """``port`` as the server port of a publisher: a whole number from 1 to 65534 (the next one is the PUB socket)."""
    if isinstance(port, bool) or not isinstance(port, int):
        raise GrootError(f"Groot2 port {port!r} is not a whole number")
    if not 1 <= port <= 65534:
        raise GrootError(
            f"Groot2 port {port} is out of range: it must be 1 to 65534 (the next port is the publisher socket)"
        )
    return port


def preorder(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    """The nodes top-down, a parent before its children: the order BehaviorTree.CPP numbers them in (from 1)."""
    order: list[py_trees.behaviour.Behaviour] = []
    stack = [root]
    while stack:
        node = stack.pop()
        order.append(node)
        stack.extend(reversed(node.children))
    return order


def to_plain(value: Any, depth: int = 0) -> Any:
    """A blackboard value as JSON-like data for the MessagePack dump (dataclasses by field, arrays as lists)."""
    if depth > 8:
        return str(value)
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, enum.Enum):
        return to_plain(value.value, depth + 1)
    if isinstance(value, uuid.UUID):
        return str(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_plain(getattr(value, f.name), depth + 1) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(key): to_plain(item, depth + 1) for key, item in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        return [to_plain(item, depth + 1) for item in value]
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return to_plain(value.tolist(), depth + 1)
    return str(value)


class Groot2Publisher:
    """Serves one py_trees tree to Groot2 (and any client of BehaviorTree.CPP 4's protocol), read-only.

    ``tree_id`` names the tree (the XML's ``BehaviorTree ID`` and the blackboard a client asks for;
    default the root's name). Raises ``GrootError`` (one line) when it cannot bind. Use it as a
    context manager, or call ``close()``.
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        port: int = DEFAULT_PORT,
        *,
        bind: str = "127.0.0.1",
        tree_id: str | None = None,
    ) -> None:
        try:
            import msgpack
            import zmq
        except ImportError as error:
            raise GrootError(
                f"serving Groot2 needs pyzmq and msgpack ({error.name} is missing): {INSTALL_HINT}"
            ) from None
        from bt_arrange import xmltree

        self._zmq = zmq
        self._packb = msgpack.packb
        self._xmltree = xmltree
        self.nodes: list[py_trees.behaviour.Behaviour] = []
        self.served: list[Any] = []
        self._subtree_of: dict[int, int] = {}
        self._status = bytearray()
        self.port = check_port(port)
        self.bind = bind
        self.root = root
        self.tree_id = tree_id or root.name
        self._lock = threading.Lock()
        self.tree_uuid = b""
        self._last: list[int] = []
        self._number(preorder(root))
        self._recording = False
        self._record_start_s = 0.0
        self._transitions: collections.deque[bytes] = collections.deque(maxlen=RECORDED_TRANSITIONS)
        #: Set once a client has fetched the tree (``wait_for_client``).
        self.tree_fetched = threading.Event()
        #: Requests answered, and error replies among them (for tests and the docs' figures).
        self.requests = 0
        self.errors = 0
        #: CPU time [s] the server thread used (known once closed).
        self.server_cpu_s = 0.0
        self._stop = threading.Event()
        self._context = zmq.Context()
        self._server = self._socket(zmq.REP, self.port, "request/reply")
        try:
            self._publisher = self._socket(zmq.PUB, self.port + 1, "publisher")
        except GrootError:
            self._server.close(linger=0)
            self._context.term()
            raise
        self._thread = threading.Thread(target=self._serve, name=f"groot2-{self.port}", daemon=True)
        self._thread.start()

    # -- binding -------------------------------------------------------------------------------

    @property
    def address(self) -> str:
        """Where clients connect for requests: ``tcp://ADDR:PORT``."""
        return self._endpoint(self.port)

    def _endpoint(self, port: int) -> str:
        host = f"[{self.bind}]" if ":" in self.bind else self.bind
        return f"tcp://{host}:{port}"

    def _socket(self, kind: int, port: int, role: str) -> Any:
        zmq = self._zmq
        sock = self._context.socket(kind)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.SNDTIMEO, SEND_TIMEOUT_MS)
        if ":" in self.bind:
            sock.setsockopt(zmq.IPV6, 1)
        endpoint = self._endpoint(port)
        try:
            sock.bind(endpoint)
        except zmq.ZMQError as error:
            sock.close(linger=0)
            if error.errno == zmq.EADDRINUSE:
                reason = f"port {port} is in use (another publisher, or another run with --groot?)"
            else:
                what = zmq.strerror(error.errno) if error.errno else str(error)
                reason = f"{what} (--groot-bind takes an address of this machine, e.g. 127.0.0.1 or 0.0.0.0)"
            raise GrootError(f"cannot serve Groot2 on {endpoint} ({role} socket): {reason}") from None
        return sock

    def _number(self, nodes: list[py_trees.behaviour.Behaviour]) -> None:
        """Number ``nodes`` (pre-order) and serve them under a new tree UUID, keeping the statuses already shown.

        Each part the XML writes as a ``<SubTree>`` (``xmltree.subtree_roots``) is served as
        BehaviorTree.CPP serves one: the SubTree is a node of its own, numbered just before the
        part's top node, showing that node's status.
        """
        try:
            tops = set(self._xmltree.subtree_roots(self.root))
        except self._xmltree.XmlTreeError:
            tops = set()
        served: list[Any] = []
        for node in nodes:
            if node in tops:
                served.append(SubTreeNode(node))
            served.append(node)
        if len(served) > MAX_NODES:
            raise GrootError(f"the tree has {len(served)} nodes; Groot2 numbers at most {MAX_NODES}")
        uids = {node: uid for uid, node in enumerate(served, 1)}
        subtree_uids = {entry.top: uid for entry, uid in uids.items() if isinstance(entry, SubTreeNode)}
        xml = self._xmltree.to_xml(self.root, tree_id=self.tree_id, uids=uids, generic=True, subtree_uids=subtree_uids)
        position = {node: index for index, node in enumerate(served)}

        def children(entry: Any) -> list[Any]:
            if isinstance(entry, SubTreeNode):
                return [entry.top]
            return [SubTreeNode(child) if child in tops else child for child in entry.children]

        # Pre-order: the descendants of node i are i+1 .. end[i]-1.
        end = [0] * len(served)
        for index in range(len(served) - 1, -1, -1):
            below = children(served[index])
            end[index] = end[position[below[-1]]] if below else index + 1
        # Who BehaviorTree.CPP resets when a node finishes: below it (a control node or decorator: from i+1),
        # the node too (under a decorator or a SubTree, or the root: from i), or nobody (a leaf elsewhere: None).
        reset_from: list[int | None] = [None] * len(served)
        for index, entry in enumerate(served):
            node = entry.top if isinstance(entry, SubTreeNode) else entry
            under_subtree = node in tops and not isinstance(entry, SubTreeNode)
            if index == 0 or under_subtree or isinstance(node.parent, py_trees.decorators.Decorator):
                reset_from[index] = index
            elif children(entry):
                reset_from[index] = index + 1
        with self._lock:
            shown = {node: (self._status[3 * i + 2], self._last[i]) for i, node in enumerate(self.served)}
            status, last = bytearray(), []
            for uid, entry in enumerate(served, 1):
                code, before = shown.get(entry, (protocol.IDLE, protocol.IDLE))
                status += uid.to_bytes(2, "little") + bytes((code,))
                last.append(before)
            self.nodes = nodes
            #: What is numbered: the nodes, and before each part's top node its ``SubTreeNode``.
            self.served = served
            #: Each node's UID, as in the XML served.
            self.uids: dict[Any, int] = uids
            #: The tree as BehaviorTree.CPP XML with ``_uid`` attributes (an unregistered node under its class name).
            self.xml = xml
            self._xml_bytes = xml.encode("utf-8")
            self._index = {
                str(entry.id): index for index, entry in enumerate(served) if not isinstance(entry, SubTreeNode)
            }
            #: A part's top node's index -> its SubTree's, which shows the same status.
            self._subtree_of = {
                position[entry.top]: index for index, entry in enumerate(served) if isinstance(entry, SubTreeNode)
            }
            self._end, self._reset_from = end, reset_from
            self._status, self._last = status, last
            # A new UUID in every reply's header: how a client learns that the tree it holds is not the one served.
            self.tree_uuid = protocol.random_uuid()

    def _renumber_if_grown(self) -> bool:
        """Serve the tree again if nodes were added or removed since it was numbered (a node building its children)."""
        nodes = preorder(self.root)
        if nodes == self.nodes or len(nodes) > MAX_NODES:
            return False
        self._number(nodes)
        return True

    # -- the tree's side -----------------------------------------------------------------------

    def on_transition(self, transition: Any) -> None:
        """Note one status change (a ``bt_arrange.runner.Transition``): the session's transition hook."""
        index = self._index.get(transition.node_id)
        if index is None and self._renumber_if_grown():
            index = self._index.get(transition.node_id)
        if index is not None:
            self._set(index, protocol.CODES[transition.new])

    def refresh(self, root: py_trees.behaviour.Behaviour | None = None) -> None:
        """Read every node's status (for a tree ticked without a session's transition hooks), after a tick."""
        codes = protocol.CODES
        self._renumber_if_grown()
        position = {node: index for index, node in enumerate(self.served)}
        for node in self.root.iterate():  # children before their parent, as a tick reports them
            index = position[node]
            now = codes[node.status.value]
            if now != self._last[index]:
                self._set(index, now)

    def _set(self, index: int, now: int) -> None:
        subtree = self._subtree_of.get(index)
        if subtree is not None:
            # BehaviorTree.CPP ticks the SubTree, then its tree: the SubTree shows its part's status first.
            self._set(subtree, now)
        with self._lock:
            before, self._last[index] = self._last[index], now
            buffer = self._status
            if now == protocol.IDLE:
                # Stopped or reset: "idle, was ..." unless it is shown so already.
                shown = buffer[3 * index + 2]
                if protocol.RUNNING <= shown <= protocol.FAILURE:
                    buffer[3 * index + 2] = protocol.IDLE_FROM_OFFSET + shown
                elif shown == protocol.IDLE and before != protocol.IDLE:
                    buffer[3 * index + 2] = protocol.IDLE_FROM_OFFSET + before
            else:
                buffer[3 * index + 2] = now
            if self._recording:
                stamp_us = int((time.monotonic() - self._record_start_s) * 1e6)
                self._transitions.append(protocol.pack_transition(stamp_us, index + 1, now))
            start = self._reset_from[index]
            if start is not None and now in (protocol.SUCCESS, protocol.FAILURE):
                for other in range(start, self._end[index]):
                    shown = buffer[3 * other + 2]
                    if protocol.RUNNING <= shown <= protocol.FAILURE:
                        buffer[3 * other + 2] = protocol.IDLE_FROM_OFFSET + shown

    def status_buffer(self) -> bytes:
        """The status buffer as a ``STATUS`` reply carries it (3 bytes a node)."""
        with self._lock:
            return bytes(self._status)

    def wait_for_client(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` seconds of wall time for a client to fetch the tree; True if one did."""
        return self.tree_fetched.wait(timeout_s) if timeout_s > 0 else self.tree_fetched.is_set()

    # -- the server's side ---------------------------------------------------------------------

    def _serve(self) -> None:
        try:
            self._serve_requests()
        finally:
            self.server_cpu_s = time.thread_time()

    def _serve_requests(self) -> None:
        zmq = self._zmq
        poller = zmq.Poller()
        poller.register(self._server, zmq.POLLIN)
        while not self._stop.is_set():
            try:
                if not poller.poll(POLL_S * 1000):
                    continue
                frames = self._server.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                continue
            except zmq.ZMQError:
                break  # the context is being closed
            reply = self.answer(frames)
            try:
                self._server.send_multipart(reply)
            except zmq.ZMQError:
                # The reply could not go out in time: start a fresh socket, so the next client is answered.
                poller.unregister(self._server)
                self._server.close(linger=0)
                try:
                    self._server = self._socket(zmq.REP, self.port, "request/reply")
                except GrootError:
                    break
                poller.register(self._server, zmq.POLLIN)

    def answer(self, frames: list[bytes]) -> list[bytes]:
        """The reply to one request (its frames), as ``Groot2Publisher::serverLoop`` makes it."""
        self.requests += 1
        try:
            reply = self._answer(frames)
        except Exception as error:  # a request must never end the server: BehaviorTree.CPP replies with the error
            reply = protocol.error_reply(str(error) or type(error).__name__)
        if reply[0] == b"error":
            self.errors += 1
        return reply

    def _answer(self, frames: list[bytes]) -> list[bytes]:
        if not frames or len(frames[0]) != protocol.REQUEST_HEADER_SIZE:
            return protocol.error_reply(protocol.WRONG_HEADER)
        protocol_id, request_type, request_id = protocol.unpack_header(frames[0])
        if protocol_id != protocol.PROTOCOL_ID:
            return protocol.error_reply(protocol.WRONG_PROTOCOL)
        with self._lock:  # the UUID and the XML of one numbering (the tree's thread renumbers a grown tree)
            tree_uuid, xml_bytes = self.tree_uuid, self._xml_bytes
        head = protocol.reply_header(request_type, request_id, tree_uuid)
        if request_type == protocol.FULLTREE:
            self.tree_fetched.set()
            return [head, xml_bytes]
        if request_type == protocol.STATUS:
            return [head, self.status_buffer()]
        if request_type == protocol.BLACKBOARD:
            if len(frames) != 2:
                return protocol.error_reply(protocol.TWO_PARTS)
            return [head, self.blackboard_dump(frames[1].decode("utf-8", "replace"))]
        if request_type in protocol.CHANGING_REQUESTS:
            return protocol.error_reply(protocol.READ_ONLY)
        if request_type in (protocol.REMOVE_ALL_HOOKS, protocol.DISABLE_ALL_HOOKS):
            return [head]  # there are none: nothing changes
        if request_type == protocol.HOOKS_DUMP:
            return [head, b"[]"]
        if request_type == protocol.TOGGLE_RECORDING:
            if len(frames) != 2:
                return protocol.error_reply(protocol.TWO_PARTS)
            return [head, *self._toggle_recording(frames[1])]
        if request_type == protocol.GET_TRANSITIONS:
            with self._lock:
                transitions, self._transitions = self._transitions, collections.deque(maxlen=RECORDED_TRANSITIONS)
            return [head, b"".join(transitions)]
        return protocol.error_reply(protocol.NOT_RECOGNIZED)

    def _toggle_recording(self, command: bytes) -> list[bytes]:
        if command == b"start":
            with self._lock:
                self._record_start_s = time.monotonic()
                self._transitions.clear()
                self._recording = True
            return [str(int(time.time() * 1e6)).encode()]
        if command == b"stop":
            with self._lock:
                self._recording = False
        return []

    def blackboard_dump(self, names: str) -> bytes:
        """The MessagePack map of the requested blackboards (``;``-separated): this tree's is ``tree_id``.

        py_trees has one blackboard for the whole tree; its keys are served as py_trees names them.
        Unknown names are left out, as BehaviorTree.CPP leaves out unknown subtrees (none known: nil).
        """
        dump: dict[str, Any] = {}
        for name in names.split(";"):
            if name == self.tree_id and name not in dump:
                storage = dict(py_trees.blackboard.Blackboard.storage)  # a copy: the tree's thread writes on
                dump[name] = {key: to_plain(value) for key, value in sorted(storage.items())}
        packed: bytes = self._packb(dump if dump else None, use_bin_type=True)
        return packed

    # -- closing -------------------------------------------------------------------------------

    def close(self) -> None:
        """Stop answering and release both ports (later calls do nothing)."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join(timeout=2 * POLL_S + SEND_TIMEOUT_MS / 1000)
        for sock in (self._server, self._publisher):
            sock.close(linger=0)
        self._context.term()

    def __enter__(self) -> Groot2Publisher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
