"""Whether MuJoCo can render here: mujoco imported and its OpenGL loaded, or one line saying what to install.

Headless, ``bt_arrange_sim.mujoco`` picks OSMesa (``MUJOCO_GL=osmesa``). Without Debian's
``libosmesa6``, PyOpenGL finds no library and ``import mujoco`` itself fails, not with an
``ImportError`` but deep inside PyOpenGL (``AttributeError: 'NoneType' object has no attribute
'glGetError'``). ``check_gl()`` turns that, and any other failure to load or start the renderer,
into one ``BackendError`` naming what to install (``libosmesa6``, or ``MUJOCO_GL=egl`` with a GPU);
``run``, ``experiment`` and ``info --backend mujoco`` call it before anything moves.
"""

from __future__ import annotations

import os
from typing import Any

from bt_arrange.errors import BackendError

#: What a user does about it (the end of the one line).
INSTALL = "install OSMesa (apt-get install libosmesa6), or on a machine with a GPU set MUJOCO_GL=egl"


def gl_error(error: BaseException) -> BackendError:
    """The one-line ``BackendError`` for a renderer that did not load or start because of ``error``."""
    cause = " ".join(f"{type(error).__name__}: {error}".split())  # one line, whatever the library said
    return BackendError(
        f"the MuJoCo backend cannot render: OpenGL through MUJOCO_GL={os.environ.get('MUJOCO_GL', '(unset)')} "
        f"did not load ({cause}); {INSTALL}"
    )


def import_mujoco() -> Any:
    """The ``mujoco`` module; a one-line ``BackendError`` when it is not installed or its OpenGL does not load."""
    try:
        import mujoco
    except ImportError as error:
        if (error.name or "").split(".")[0] == "mujoco":
            raise BackendError(
                f"the mujoco backend needs the mujoco package: pip install -e '.[mujoco]' ({error})"
            ) from None
        raise gl_error(error) from None
    except Exception as error:  # noqa: BLE001 - a GL library missing shows as many kinds of error
        raise gl_error(error) from None
    return mujoco


def check_gl() -> None:
    """A one-line ``BackendError`` unless mujoco and the OpenGL it renders through load here.

    Only imports (the context itself is made when a cell is built): cheap, and safe before a pool forks.
    """
    import_mujoco()
    if os.environ.get("MUJOCO_GL") == "osmesa":
        try:
            from mujoco.osmesa import GLContext  # noqa: F401 - loading it loads libOSMesa
        except Exception as error:  # noqa: BLE001 - as above
            raise gl_error(error) from None
