"""The work cell in a second physics engine, MuJoCo: the same trees, behaviours, perception and plans.

Installed with the ``mujoco`` extra (``pip install -e '.[mujoco]'``); the backend is the entry point
``mujoco`` (``bt-arrange run|experiment|info --backend mujoco``). Headless rendering goes through
OSMesa (Debian's ``libosmesa6``): ``MUJOCO_GL`` is set to ``osmesa`` here, before mujoco is imported,
when it is unset and there is no display (EGL does not start on machines without a GPU driver).

The rooms: ``model`` (the ``MjSpec``: the bundled URDF plus what a URDF cannot say, and the contact
settings ``MujocoPhysics``), ``rendering`` (the offscreen camera), ``devices`` (the ``bt_arrange.robot``
interfaces), ``cell`` (``MujocoCell``: model, data, parts, ground truth, error-injection access),
``runs`` (``MujocoWorld`` and ``MujocoRun``) and ``backend`` (``MujocoBackend``). Only ``backend`` is
imported by the command line; mujoco itself is imported when a cell is built.
"""

from __future__ import annotations

import os


def configure_gl() -> None:
    """``MUJOCO_GL=osmesa`` when the variable is unset and there is no display (before mujoco is imported)."""
    if "MUJOCO_GL" not in os.environ and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        os.environ["MUJOCO_GL"] = "osmesa"
        # PyOpenGL reads its own variable to pick the platform: the same one.
        os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")


configure_gl()
