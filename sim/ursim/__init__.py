"""A Universal Robots controller backed by the pybullet work cell (``python -m bt_arrange_sim.ursim``).

It serves, on the loopback, what a CB3 UR5 with a Robotiq 2F-85 and a network camera serve: the
dashboard (29999), RTDE (30004), the script port (30003, where ``ur_rtde`` uploads its control
program, run natively here), the Robotiq URCap's socket (63352), an HTTP camera, and a faults port
for tests. The physics is the simulated backend's own cell, stepped at 125 Hz in real time.
See docs/ursim.md.

``launch`` starts one as a subprocess for tests and benchmarks.
"""

from __future__ import annotations

from bt_arrange_sim.ursim.launcher import UrSim, launch

__all__ = ["UrSim", "launch"]
