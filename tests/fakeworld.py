"""A kinematic fake world for ``bt_arrange.session``: no simulator, no ground truth for the report.

``FakeWorld`` implements the ``World`` protocol over the fake devices of the testing kit (``bt_arrange.testing``):

- the arm tracks every setpoint perfectly (``FakeArm``);
- a close of the gripper takes the cube between its pads (its centre within the open pads, the
  TCP below its top): the pads centre it along the closing axis and square it to the pads, and
  it then moves with the TCP; an open lets it go, and it rests on the table where it was;
- a pad that moves into a free cube's side, below its top, pushes it ahead by the overlap and
  squares it to the pads' face (a line contact);
- the camera renders the cubes where they are (``bt_arrange.perception.synthetic``);
- ``release_errors_m`` (by cube: dx, dy in metres) lands a cube that far from where its first
  release let it go, as a placing error would, for the pushes to correct.

It has no ground truth for the session (``truth`` is None: the report is camera only) unless
built with ``truth=True``; a test reads where the cubes are from ``FakeWorld.poses`` either way.
``FakeBackend`` serves it to the command line (``backends.register("fake", FakeBackend)``), with
fixed starts for ``scatter``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import py_trees

from bt_arrange.objects import CUBE, ObjectStart
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourTable
from bt_arrange.perception.synthetic import SyntheticCube, sim_intrinsics, top_down_camera_pose
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.robot import CameraFrame, Robot
from bt_arrange.session import Session, prepare_record_dir
from bt_arrange.settings import ManipulationSettings
from bt_arrange.testing import CAMERA_HEIGHT_PX, CAMERA_WIDTH_PX, FakeArm, FakeCamera, FakeClock, FakeGripper

SETTINGS = ManipulationSettings()
EDGE_M = CUBE.size_m[0]
PADS = SETTINGS.gripper
QUARTER_TURN = math.pi / 2


def camera_view() -> CameraView:
    """What the fake world's top camera sees (for the plan check, before the world is built)."""
    return CameraView(sim_intrinsics(CAMERA_WIDTH_PX, CAMERA_HEIGHT_PX), top_down_camera_pose())


def _square_to(yaw_rad: float, pads_yaw_rad: float) -> float:
    """The yaw of a cube turned by the least angle to be square to pads at ``pads_yaw_rad``."""
    return pads_yaw_rad + (yaw_rad - pads_yaw_rad + QUARTER_TURN / 2) % QUARTER_TURN - QUARTER_TURN / 2


@dataclass
class _Part:
    colour: str
    x_m: float
    y_m: float
    yaw_rad: float
    z_m: float = 0.0


@dataclass
class _Held:
    name: str
    along_pads_m: float
    yaw_from_pads_rad: float
    below_tcp_m: float


class FakeWorld:
    """Cubes on a table, an arm that is where it is told, a gripper that holds and pushes them."""

    def __init__(self, release_errors_m: dict[str, tuple[float, float]] | None = None, truth: bool = False) -> None:
        self.release_errors_m = dict(release_errors_m or {})
        self.clock = FakeClock()
        self.arm = FakeArm(self.clock)
        self.gripper = _KinematicGripper(self)
        self.camera = _WorldCamera(self)
        self.colours: ColourTable = DEFAULT_COLOUR_TABLE
        self.parts: dict[str, _Part] = {}
        self.held: _Held | None = None
        self.closed = False
        self._pads_before: list[np.ndarray] | None = None
        #: No ground truth to report unless asked for: the session's report is then camera only.
        self.truth: _Truth | None = _Truth(self) if truth else None

    # -- the World protocol --------------------------------------------------------------------

    @property
    def robot(self) -> Robot:
        """The fake devices."""
        return Robot(arm=self.arm, gripper=self.gripper, camera=self.camera, clock=self.clock)

    def place(self, starts: Sequence[Any], colours: ColourTable) -> None:
        """Put the cubes on the table."""
        self.colours = colours
        for start in starts:
            kind = getattr(start, "object_type", None) or CUBE
            assert kind == CUBE, "the fake world has cubes only"
            self.parts[start.name or start.colour] = _Part(start.colour, start.x_m, start.y_m, start.yaw_rad)

    def settle(self, seconds: float) -> None:
        """Nothing moves by itself: only time passes."""
        self.clock.advance(seconds)

    def step(self) -> None:
        """One control period: the held cube follows the TCP, the pads push what they meet."""
        self.clock.advance(self.arm.control_period_s)
        self._follow()
        self._push()

    def capture_image(self) -> CameraFrame:
        """A frame of the top camera."""
        return self.camera.capture()

    def close(self) -> None:
        """Nothing to release."""
        self.closed = True

    # -- what a test reads ----------------------------------------------------------------------

    def poses(self) -> dict[str, tuple[float, float, float]]:
        """Where each cube is, ``(x_m, y_m, yaw_rad)``: for the test's own check, not the report."""
        return {name: (float(p.x_m), float(p.y_m), float(p.yaw_rad)) for name, p in self.parts.items()}

    # -- the kinematics --------------------------------------------------------------------------

    def _tcp(self) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
        """TCP position, the pads' yaw, the closing axis and the axis along the pads (both in the plane)."""
        pose = self.arm.tcp_pose()
        yaw = pose.yaw_rad
        closing = np.array([math.cos(yaw), math.sin(yaw)])
        return pose.position_m, yaw, closing, np.array([-closing[1], closing[0]])

    def grasp(self) -> float | None:
        """The gripper closes: hold the cube between the open pads, if one is; the width it stops at."""
        position, yaw, closing, along = self._tcp()
        half_open_m = self.gripper.width() / 2
        for name, part in self.parts.items():
            rel = np.array([part.x_m, part.y_m]) - position[:2]
            between = abs(rel @ closing) <= half_open_m - EDGE_M / 2 + 1e-4
            if between and abs(rel @ along) <= PADS.pad_width_m / 2 and position[2] < EDGE_M:
                self.held = _Held(
                    name, float(rel @ along), _square_to(part.yaw_rad, yaw) - yaw, position[2] - EDGE_M / 2
                )
                self._follow()
                return EDGE_M
        return None

    def release(self) -> None:
        """The gripper opens: the held cube comes to rest on the table where it is."""
        if self.held is not None:
            part = self.parts[self.held.name]
            dx, dy = self.release_errors_m.pop(self.held.name, (0.0, 0.0))
            part.x_m, part.y_m, part.z_m = part.x_m + dx, part.y_m + dy, 0.0
            self.held = None

    def _follow(self) -> None:
        if self.held is None:
            return
        position, yaw, _, along = self._tcp()
        part = self.parts[self.held.name]
        centre = position[:2] + along * self.held.along_pads_m
        part.x_m, part.y_m = float(centre[0]), float(centre[1])
        part.yaw_rad = yaw + self.held.yaw_from_pads_rad
        part.z_m = max(0.0, float(position[2]) - EDGE_M / 2 - self.held.below_tcp_m)

    def _pads(self) -> tuple[list[np.ndarray], float, np.ndarray, np.ndarray]:
        """The two pads' centres (in the plane), the pads' yaw, the closing axis and the axis along the pads."""
        position, yaw, closing, along = self._tcp()
        offset_m = self.gripper.width() / 2 + PADS.pad_thickness_m / 2
        return [position[:2] + side * offset_m * closing for side in (-1, 1)], yaw, closing, along

    def _push(self) -> None:
        """A pad (a box beside the TCP) that moved into a free cube's side, below its top, pushes it ahead.

        The cube moves along the pad's motion until it is clear of the pad, and squares to its face.
        """
        pads, yaw, closing, along = self._pads()
        before, self._pads_before = self._pads_before, pads
        if before is None or self.arm.tcp_pose().position_m[2] >= EDGE_M + 0.005:
            return
        half_across_m, half_along_m = PADS.pad_thickness_m / 2, PADS.pad_width_m / 2
        for pad, pad_before in zip(pads, before, strict=True):
            motion = pad - pad_before
            if np.linalg.norm(motion) < 1e-7:
                continue
            ahead = motion / np.linalg.norm(motion)
            for name, part in self.parts.items():
                if self.held is not None and self.held.name == name:
                    continue
                turn = part.yaw_rad - yaw
                half_m = EDGE_M / 2 * (abs(math.cos(turn)) + abs(math.sin(turn)))  # along either pad axis
                rel = np.array([part.x_m, part.y_m]) - pad
                if abs(rel @ closing) >= half_m + half_across_m or abs(rel @ along) >= half_m + half_along_m:
                    continue
                reach_m = half_m * (abs(ahead @ closing) + abs(ahead @ along))
                reach_m += half_across_m * abs(ahead @ closing) + half_along_m * abs(ahead @ along)
                overlap_m = reach_m - float(rel @ ahead)
                if overlap_m > 0 and rel @ ahead > 0:
                    part.x_m = float(part.x_m + overlap_m * ahead[0])
                    part.y_m = float(part.y_m + overlap_m * ahead[1])
                    part.yaw_rad = _square_to(part.yaw_rad, yaw)


class _Truth:
    """The fake world's ground truth (``bt_arrange.session.GroundTruth``), when a test asks for one."""

    def __init__(self, world: FakeWorld) -> None:
        self._world = world

    def part_names(self) -> list[str]:
        """Every cube, by name."""
        return list(self._world.parts)

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        """Where the cube is."""
        return self._world.poses()[name]


class _KinematicGripper(FakeGripper):
    """A fake 2F-85 whose close takes the cube between its pads, and whose open lets it go."""

    def __init__(self, world: FakeWorld) -> None:
        super().__init__(world.clock)
        self._world = world

    def close(self, force_n: float, speed_m_s: float | None = None) -> None:
        """Close; stop at the cube's width when one is between the pads."""
        self.object_width_m = self._world.grasp()
        super().close(force_n, speed_m_s)

    def open(self, width_m: float, speed_m_s: float | None = None) -> None:
        """Open; a held cube stays where it is."""
        self._world.release()
        self.object_width_m = None
        super().open(width_m, speed_m_s)


class _WorldCamera(FakeCamera):
    """The fake top camera, rendering the world's cubes where they are now."""

    def __init__(self, world: FakeWorld) -> None:
        super().__init__(world.clock, arm=world.arm)
        self._world = world

    def capture(self, with_depth: bool = False, window: Any = None) -> CameraFrame:
        """Render the cubes, each painted with its colour."""
        world = self._world
        self.parts = [
            SyntheticCube(p.colour, p.x_m, p.y_m, p.yaw_rad, rgb=world.colours[p.colour].paint_rgb, table_z_m=p.z_m)
            for p in world.parts.values()
        ]
        return super().capture(with_depth, window)


class FakeBackend:
    """The fake world as a backend for the command line: runs are sessions on a ``FakeWorld``."""

    name = "fake"
    experiment = None
    #: Where ``scatter`` puts the parts of each colour (clear of ``TARGETS`` below).
    STARTS = {"red": (0.42, -0.22), "green": (0.58, -0.22), "blue": (0.42, 0.22), "yellow": (0.58, 0.22)}
    #: Every world it built, the last one last.
    worlds: list[FakeWorld] = []
    #: The placing errors of the next worlds (``FakeWorld.release_errors_m``).
    release_errors_m: dict[str, tuple[float, float]] = {}
    #: Every ``scatter`` call: its colours and seed.
    scattered: list[tuple[list[str], int]] = []

    def open_run(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any],
        *,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
    ) -> Session:
        """A session on a fresh fake world."""

        def open_world() -> FakeWorld:
            world = FakeWorld(FakeBackend.release_errors_m)
            FakeBackend.worlds.append(world)
            return world

        return Session(
            root,
            starts,
            open_world,
            view=camera_view(),
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
        )

    def scatter(
        self,
        colours: Sequence[str],
        seed: int,
        avoid: Iterable[Any] = (),
        object_types: Sequence[Any] | None = None,
        names: Sequence[str | None] | None = None,
    ) -> list[ObjectStart]:
        """The fixed start of each colour (the seed is ignored)."""
        FakeBackend.scattered.append((list(colours), seed))
        names = list(names) if names is not None else [None] * len(colours)
        return [ObjectStart(c, *self.STARTS[c], 0.1, name=n) for c, n in zip(colours, names, strict=True)]

    def check(self) -> Iterator[str]:
        """Always ready."""
        yield "fake world: ok"

    def prepare_out(self, path: Path) -> Path:
        """The session's own check of a folder."""
        return prepare_record_dir(path)
