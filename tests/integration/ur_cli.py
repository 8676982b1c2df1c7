"""``bt-arrange`` for the ur end-to-end tests, in a process of its own, as a user runs it.

ur_rtde's interfaces are made for one process per connection's life: after a dropped connection its
control interface reconnects on a thread of its own, and several runs in one process crashed it.
So each run of ``tests/integration/test_ur_cell.py`` is this script in a fresh process, with two
backends the tests need registered besides ``ur``:

- ``ur-small-box``: a cell whose workspace box ends at x = 0.30 m (every part lies beyond it);
- ``ur-fault``: sends ``BT_UR_FAULT`` to the controller's faults port (``BT_UR_FAULTS``, HOST:PORT)
  once the tree has run ``BT_UR_FAULT_AT_S`` seconds of world time: the arm is then on its way to the
  cube and nothing has been touched, so the cell is as it was for the next run.
"""

from __future__ import annotations

import os
import socket
import sys

from bt_arrange import backends
from bt_arrange.cli import main
from bt_arrange.motion.safety import WorkspaceBox
from bt_arrange.ur.backend import UrBackend


class SmallBoxBackend(UrBackend):
    """The ur backend in a cell whose workspace ends at x = 0.30 m."""

    workspace = WorkspaceBox(x_m=(0.10, 0.30), y_m=(-0.55, 0.55), z_m=(0.005, 0.65))


def send_fault(address: str, line: str) -> str:
    """One line to the controller's faults port; its answer."""
    host, _, port = address.rpartition(":")
    with socket.create_connection((host, int(port)), timeout=10.0) as connection:
        connection.sendall(line.encode() + b"\n")
        return connection.recv(1024).decode().strip()


class FaultBackend(UrBackend):
    """The ur backend with a fault sent at a moment of the run's world time."""

    def open_run(self, root, starts=(), **options):  # noqa: ANN001, ANN201, D102 - a test's backend
        session = super().open_run(root, starts, **options)
        at_s = float(os.environ.get("BT_UR_FAULT_AT_S", "1.0"))
        sent: list[str] = []

        def inject(tree_root: object) -> None:
            if not sent and session.elapsed_s() >= at_s:
                sent.append(send_fault(os.environ["BT_UR_FAULTS"], os.environ["BT_UR_FAULT"]))

        session.tick_hooks.append(inject)
        return session


backends.register("ur-small-box", SmallBoxBackend)
backends.register("ur-fault", FaultBackend)

if __name__ == "__main__":
    sys.exit(main())
