"""BehaviorTree.CPP 4's Groot2 protocol: message headers, request types, status codes.

Followed from BehaviorTree.CPP 4.10's ``include/behaviortree_cpp/loggers/groot2_protocol.h`` and
``src/loggers/groot2_publisher.cpp``:

- every exchange is a multipart ZeroMQ request/reply on the server port; the publisher's second
  socket (PUB, server port + 1) only announces breakpoints, which a read-only server never reaches;
- a request's first frame is 6 bytes: protocol id (``uint8``, 2), request type (``uint8``, an ASCII
  letter), request id (``uint32``, little-endian); a reply's first frame echoes them (the protocol id
  set to 2) followed by the 16-byte UUID of the tree; an error reply is ``["error", message]``
  (a request of another protocol id gets one, ``WRONG_PROTOCOL``, where BehaviorTree.CPP answers it);
- the status buffer is 3 bytes per node: its UID (``uint16``, little-endian) and its status
  (``IDLE`` 0, ``RUNNING`` 1, ``SUCCESS`` 2, ``FAILURE`` 3, ``SKIPPED`` 4; a node back to ``IDLE``
  is 10 + the status it had);
- the recorded transitions (``GET_TRANSITIONS``) are 9 bytes each: a timestamp in microseconds since
  recording started (6 bytes, little-endian), the UID (2 bytes), the new status (1 byte).
"""

from __future__ import annotations

import os
import struct

from py_trees.common import Status

#: ``BT::Monitor::kProtocolID``.
PROTOCOL_ID = 2
#: ``Groot2Publisher``'s default server port; the publisher socket is the next one.
DEFAULT_PORT = 1667

HEADER = struct.Struct("<BBI")
REQUEST_HEADER_SIZE = HEADER.size  # 6
UUID_SIZE = 16

# ``BT::Monitor::RequestType`` (an ASCII letter each).
FULLTREE = ord("T")
STATUS = ord("S")
BLACKBOARD = ord("B")
HOOK_INSERT = ord("I")
HOOK_REMOVE = ord("R")
BREAKPOINT_REACHED = ord("N")
BREAKPOINT_UNLOCK = ord("U")
HOOKS_DUMP = ord("D")
REMOVE_ALL_HOOKS = ord("A")
DISABLE_ALL_HOOKS = ord("X")
TOGGLE_RECORDING = ord("r")
GET_TRANSITIONS = ord("t")

#: Requests that would change how the tree runs (insert or remove a hook, release a breakpoint
#: with a status of the client's choosing): a read-only server answers them with an error reply.
CHANGING_REQUESTS = frozenset({HOOK_INSERT, HOOK_REMOVE, BREAKPOINT_UNLOCK})

# ``BT::NodeStatus``, and the "idle, was ..." codes of the status buffer.
IDLE, RUNNING, SUCCESS, FAILURE, SKIPPED = 0, 1, 2, 3, 4
IDLE_FROM_OFFSET = 10

#: A py_trees status as BehaviorTree.CPP's (``INVALID``: not ticked, or stopped, is ``IDLE``).
CODES: dict[str, int] = {
    Status.INVALID.value: IDLE,
    Status.RUNNING.value: RUNNING,
    Status.SUCCESS.value: SUCCESS,
    Status.FAILURE.value: FAILURE,
}

# The texts of BehaviorTree.CPP's error replies, kept word for word.
WRONG_HEADER = "wrong request header"
TWO_PARTS = "must be 2 parts message"
NOT_RECOGNIZED = "Request not recognized"
#: Our own: BehaviorTree.CPP 4.10 does not look at a request's protocol id (it answers with its
#: own, 2, whatever was asked); a client of another version would read a reply it cannot parse, so
#: it is told in the protocol's error reply instead (Groot2 itself always asks with 2).
WRONG_PROTOCOL = f"wrong protocol version: this publisher speaks protocol {PROTOCOL_ID} (BehaviorTree.CPP 4's Groot2)"
READ_ONLY = (
    "read-only: this bt-arrange publisher does not change the running tree (no hooks, breakpoints or status overrides)"
)


def pack_header(request_type: int, request_id: int, protocol: int = PROTOCOL_ID) -> bytes:
    """A request header: protocol id, type, request id (6 bytes)."""
    return HEADER.pack(protocol & 0xFF, request_type & 0xFF, request_id & 0xFFFFFFFF)


def unpack_header(frame: bytes) -> tuple[int, int, int]:
    """``(protocol, request type, request id)`` of a 6-byte header (``ValueError`` for another size)."""
    if len(frame) != REQUEST_HEADER_SIZE:
        raise ValueError(WRONG_HEADER)
    protocol, request_type, request_id = HEADER.unpack(frame)
    return protocol, request_type, request_id


def reply_header(request_type: int, request_id: int, tree_uuid: bytes) -> bytes:
    """A reply's first frame: the request's header (protocol id 2) and the tree's UUID (22 bytes)."""
    return pack_header(request_type, request_id) + tree_uuid


def error_reply(message: str) -> list[bytes]:
    """BehaviorTree.CPP's error reply: two frames, ``error`` and the message."""
    return [b"error", message.encode("utf-8")]


def random_uuid() -> bytes:
    """16 random bytes with the version-4 and variant bits set, as ``CreateRandomUUID`` makes them."""
    raw = bytearray(os.urandom(UUID_SIZE))
    raw[8] = (raw[8] & 0xBF) | 0x80
    raw[6] = (raw[6] & 0x4F) | 0x40
    return bytes(raw)


def pack_transition(timestamp_us: int, uid: int, status: int) -> bytes:
    """One recorded transition: 6 bytes of microseconds, the UID, the status (9 bytes)."""
    return (timestamp_us & 0xFFFFFFFFFFFF).to_bytes(6, "little") + struct.pack("<HB", uid, status)
