"""A real UR5 cell: ur_rtde for the arm, the Robotiq URCap's socket for the 2F-85, OpenCV for the top camera.

``bt_arrange.ur.backend.UrBackend`` is the ``ur`` backend (``bt-arrange run --backend ur --robot HOST``);
docs/real-cell.md says how to wire a cell, what to check before a first run, and what was proven
against the emulated controller (``bt_arrange_sim.ursim``). Nothing here is imported by the framework.
"""
