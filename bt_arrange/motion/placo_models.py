"""placo models of a URDF, built once per process and lent to each ``ArmKinematics`` in turn.

placo 0.10 never frees what a ``RobotWrapper`` allocates (its pinocchio ``Data``: about 0.22 MB,
measured with heaptrack and by resident memory over 60 constructions): a process that built two
models a run (the plan check's and the context's) grew by about 0.65 MB a run, a gigabyte over a
thousand-trial campaign worker. So a model is never dropped: an ``ArmKinematics`` borrows one
(``borrow``), and when it is garbage, the model goes back to the free models of its URDF. A
process holds as many models of a URDF as it ever had kinematics of it alive at once.

A model is lent with its arm joints where a fresh one has them (``PlacoModel.reset``), so a
borrowed model answers exactly as a new one would: the solver keeps no state between solves
(``solve(False)`` applies nothing), its task's target is set before each solve.
"""

from __future__ import annotations

import os
import threading
import weakref
from dataclasses import dataclass

import numpy as np
import placo

from bt_arrange.errors import MotionError
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES, TCP_FRAME

__all__ = ["PlacoModel", "borrow", "free_models"]


@dataclass
class PlacoModel:
    """A URDF's placo robot, its IK solver (floating base and fingers masked, joint limits on) and TCP task."""

    robot: placo.RobotWrapper
    solver: placo.KinematicsSolver
    task: placo.FrameTask
    #: The robot's configuration as built: every loan starts from it.
    initial_q: np.ndarray

    @classmethod
    def build(cls, path: str) -> PlacoModel:
        """Load ``path`` with placo and set up the IK problem; ``MotionError`` if the URDF lacks a joint of the arm."""
        robot = placo.RobotWrapper(path, placo.Flags.ignore_collisions)
        missing = [n for n in (*ARM_JOINT_NAMES, *FINGER_JOINT_NAMES) if n not in robot.joint_names()]
        if missing:
            raise MotionError(f"URDF {path} lacks the joints {missing}")
        solver = placo.KinematicsSolver(robot)
        solver.mask_fbase(True)
        for name in FINGER_JOINT_NAMES:
            solver.mask_dof(name)
        solver.enable_joint_limits(True)
        task = solver.add_frame_task(TCP_FRAME, np.eye(4))
        task.configure(TCP_FRAME, "soft", 1.0, 1.0)
        return cls(robot, solver, task, np.array(robot.state.q, dtype=float).copy())

    def reset(self) -> None:
        """Back to the configuration of a freshly built model."""
        self.robot.state.q = self.initial_q.copy()
        self.robot.update_kinematics()


_lock = threading.Lock()
#: The models not lent out, by URDF (``_key``: its path, size and modification time).
_free: dict[str, list[PlacoModel]] = {}


def borrow(owner: object, path: str) -> tuple[PlacoModel, weakref.finalize]:
    """A model of the URDF at ``path`` for ``owner`` alone, and what gives it back.

    The second is called once: by ``owner`` when it is done, at the latest when ``owner`` is garbage
    (a cycle's garbage may wait for the collector).

    Models are kept by the file's path, size and modification time: a URDF changed in place is loaded again.
    """
    key = _key(path)
    with _lock:
        free = _free.setdefault(key, [])
        model = free.pop() if free else None
    if model is None:
        model = PlacoModel.build(path)
    model.reset()
    return model, weakref.finalize(owner, _give_back, key, model)


def _key(path: str) -> str:
    try:
        stat = os.stat(path)
    except OSError:
        return path  # placo names the missing file when it fails to load it
    return f"{path}|{stat.st_size}|{stat.st_mtime_ns}"


def _give_back(key: str, model: PlacoModel) -> None:
    with _lock:
        _free.setdefault(key, []).append(model)


def free_models(path: str) -> int:
    """How many models of the URDF at ``path`` wait to be lent (for the tests and the memory benchmark)."""
    with _lock:
        return len(_free.get(_key(path), []))
