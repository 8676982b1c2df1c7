"""The simulated work cell of bt-arrange, installed as ``bt_arrange_sim``: two engines on one neutral layer.

The top-level modules are engine-neutral (the cell's configuration, scenes, error injection, the
experiment campaign, a real cell's errors, camera noise, the devices' range checks, the world and
run every engine's share); ``bt_arrange_sim.pybullet`` is the pybullet engine (the default backend,
``sim``) and ``bt_arrange_sim.mujoco`` the MuJoCo engine (``mujoco``). Each engine builds on the
neutral layer and neither imports the other; the neutral layer imports neither.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

from bt_arrange_sim.config import HOME_Q, CameraConfig, CellConfig, Contact, PhysicsConfig
from bt_arrange_sim.noise import CameraNoise, CameraNoiseConfig
from bt_arrange_sim.parts import PAINT_RGB

__all__ = [
    "HOME_Q",
    "PAINT_RGB",
    "CameraConfig",
    "CameraNoise",
    "CameraNoiseConfig",
    "CellConfig",
    "Contact",
    "PhysicsConfig",
]

#: Names this package exported before the engines were siblings, and the engine module that has them now.
_MOVED = {
    "WorkCell": "bt_arrange_sim.pybullet.cell",
    "SimWorld": "bt_arrange_sim.pybullet.runs",
    "SimulatedRun": "bt_arrange_sim.pybullet.runs",
}


def __getattr__(name: str) -> Any:
    # Only a deprecated name loads its engine, and only when asked for: importing the package loads none.
    if name not in _MOVED:
        raise AttributeError(f"module 'bt_arrange_sim' has no attribute {name!r}")
    warnings.warn(
        f"bt_arrange_sim.{name} is deprecated: import it from {_MOVED[name]}", DeprecationWarning, stacklevel=2
    )
    return getattr(importlib.import_module(_MOVED[name]), name)
