"""What every engine's cell shares: world time, the robot, settling, parts by colour and their folded truth.

An engine's cell (``pybullet.cell.WorkCell``, ``mujoco.cell.MujocoCell``) subclasses ``CellBase``
and has ``config`` (a ``CellConfig``), ``_steps`` (physics steps so far), ``object_types``, the
devices (``arm``, ``gripper``, ``camera``, ``clock``), ``step``, ``add_object``,
``part_pose_truth`` and ``close``.
"""

from __future__ import annotations

from typing import Any

from bt_arrange.deprecation import warn_once
from bt_arrange.geometry import Pose, fold_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.robot import Robot

#: The cell's methods that said cube for any part, old -> new (deprecated aliases, CHANGELOG).
RENAMED_METHODS = {
    "cube_pose_truth": "part_pose_truth",
    "cube_planar_truth": "part_planar_truth",
    "place_cube_truth": "place_part_truth",
    "cube_in_gripper_truth": "part_in_gripper_truth",
    "displace_cube": "displace_part",
    "remove_cube": "remove_part",
    "add_cubes": "add_parts",
}


class CellBase:
    """The engine-neutral half of a simulated cell (see the module)."""

    config: Any
    _steps: int
    object_types: dict[str, ObjectType]
    arm: Any
    gripper: Any
    camera: Any
    clock: Any

    @property
    def sim_time_s(self) -> float:
        """Seconds of simulated time since the cell was built."""
        return self._steps * self.config.physics.time_step_s

    @property
    def robot(self) -> Robot:
        """The cell's devices behind the interfaces behaviours use."""
        return Robot(arm=self.arm, gripper=self.gripper, camera=self.camera, clock=self.clock)

    def step(self, control_periods: int = 1) -> None:
        """Advance the world by whole control periods (each several physics steps)."""
        raise NotImplementedError

    def settle(self, seconds: float = 0.5) -> None:
        """Let the world run with the current commands, e.g. after adding parts."""
        self.step(max(1, round(seconds / self.config.physics.control_period_s)))

    def add_object(self, object_type: ObjectType, colour: Any, x_m: float, y_m: float, yaw_rad: float = 0.0,
                   name: str | None = None) -> str:  # fmt: skip
        """Put a part of ``object_type`` on the table, resting at (x, y, yaw), top face ``colour``; its name."""
        raise NotImplementedError

    def add_cube(self, colour: str, x_m: float, y_m: float, yaw_rad: float = 0.0, name: str | None = None) -> str:
        """Put a 5 cm cube of ``colour`` on the table, resting, at (x, y, yaw); returns its name."""
        return self.add_object(CUBE, colour, x_m, y_m, yaw_rad, name=name)

    def part_pose_truth(self, name: str) -> Pose:
        """The engine's true pose of a part's centre. Never steer the robot with it."""
        raise NotImplementedError

    def part_planar_truth(self, name: str) -> tuple[float, float, float]:
        """True (x_m, y_m, yaw_rad) of a part, yaw folded to its symmetry (90 degrees for a square top, else 180)."""
        pose = self.part_pose_truth(name)
        return pose.x_m, pose.y_m, fold_yaw(pose.yaw_rad, self.object_types.get(name, CUBE).shape.symmetry_rad)

    def close(self) -> None:
        """Free the engine's resources."""
        raise NotImplementedError

    # -- names that said cube for any part: deprecated aliases, warned once, for one release ----------

    @property
    def cubes(self) -> dict[str, int]:
        """Deprecated: ``parts``."""
        warn_once(f"{type(self).__name__}.cubes", f"{type(self).__name__}.parts")
        parts: dict[str, int] = getattr(self, "parts")  # noqa: B009  # the engine's cell sets it
        return parts

    def __getattr__(self, name: str) -> Any:
        new = RENAMED_METHODS.get(name)
        if new is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        warn_once(f"{type(self).__name__}.{name}", f"{type(self).__name__}.{new}")
        return getattr(self, new)

    def __enter__(self) -> Any:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
