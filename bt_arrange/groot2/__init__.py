"""Watch a running py_trees tree in Groot2: a read-only publisher of BehaviorTree.CPP 4's Groot2 protocol.

``bt-arrange run TREE --groot [PORT]`` serves the tree while it runs; ``docs/groot2.md`` says how
to watch it (Groot2, ``btview``), what is served and the limits. The rooms: ``protocol`` (headers,
request types, status codes, after BehaviorTree.CPP's ``groot2_protocol.h``) and ``publisher``
(``Groot2Publisher``). The transport is ``pyzmq`` and the blackboard dump ``msgpack``: the
``[groot]`` extra; this package imports neither until a publisher is made.
"""

from bt_arrange.groot2.protocol import DEFAULT_PORT
from bt_arrange.groot2.publisher import Groot2Publisher, GrootError, check_port, preorder

__all__ = ["DEFAULT_PORT", "Groot2Publisher", "GrootError", "check_port", "preorder"]
