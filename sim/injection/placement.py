"""4) Placement (the paper's Sec. 3, Fig. 2f-h): friction, release and tilting errors as the cube is let go."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Pick, Place
from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose, quaternion_to_matrix
from bt_arrange.runner import Transition
from bt_arrange.shapes import Shape
from bt_arrange_sim.injection.framework import (
    LIFT_STAGE,
    RELEASE_STAGE,
    Injector,
    Parameter,
    _deg,
    _horizontal,
    _mm,
    _NodeFinder,
)

if TYPE_CHECKING:
    from bt_arrange_sim.injection.framework import InjectableRun


class ReleaseStick(Injector):
    """Friction error (Fig. 2f): the cube sticks to one finger as the gripper opens.

    When ``place <obj>`` starts "release the part", one finger is chosen at random and a distance
    uniform in [0, ``max_m``]; for the following ticks the cube follows that finger's opening: it is
    put (``displace_part``) where it was when the release began plus the finger's travel since, along
    the closing axis, until it has been dragged that far; then it stays where it was let go.

    Record: ``finger`` (joint name), ``drag_mm``, ``dx_mm``, ``dy_mm`` (world), ``ticks``, ``start_s``, ``end_s``.
    """

    name = "release_stick"
    PARAMETERS = (Parameter("max_m", 0.003, 0.0, 0.015, "m"),)

    def __init__(self, max_m: float = 0.003) -> None:
        super().__init__(max_m=max_m)
        self._drag: dict[str, Any] | None = None

    def _attach(self, run: InjectableRun, obj: str) -> None:
        finder = _NodeFinder(Place, obj)

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            node = finder(root)
            if node is None:
                return
            if self._drag is None:
                if not self.fired and node.status == Status.RUNNING and node.feedback_message == RELEASE_STAGE:
                    self._begin()
                return
            if node.status != Status.RUNNING:  # interrupted: the cube is no longer there to drag
                self._finish()
                return
            self._follow(finish=node.feedback_message != RELEASE_STAGE)

        run.tick_hooks.append(hook)

    def _finger_state(self, finger: int) -> float:
        cell = self.run.cell
        return cell.finger_opening_m(finger)

    def _begin(self) -> None:
        cell = self.run.cell
        side = int(self.rng.integers(2))
        distance = float(self.rng.uniform(0.0, self.params["max_m"]))
        finger = cell.finger_joint_indices[side]
        tcp = cell.arm.tcp_pose()
        closing = _horizontal(tcp.rotation[:, 0])
        pad = cell.finger_pad_position_m(finger)
        direction = closing * math.copysign(1.0, float((pad - tcp.position_m)[:2] @ closing))
        self.fired = True
        self._drag = {
            "finger": finger,
            "direction": direction,
            "distance": distance,
            "opening_at_start": self._finger_state(finger),
            "from_xy": cell.part_pose_truth(self.cube).position_m[:2].copy(),
            "applied": 0.0,
            "ticks": 0,
        }
        self.details.update(
            start_s=self._now(),
            finger=cell.joint_name(finger),
            drag_mm=_mm(distance),
            dx_mm=_mm(distance * direction[0]),
            dy_mm=_mm(distance * direction[1]),
        )
        self._follow(finish=False)

    def _follow(self, finish: bool) -> None:
        drag = self._drag
        assert drag is not None
        travel = max(0.0, self._finger_state(drag["finger"]) - drag["opening_at_start"])
        target = drag["distance"] if finish else min(travel, drag["distance"])
        if target > drag["applied"]:
            # Absolute, not by increments: the pad's contact pushes the cube back a little every step.
            here = self.run.cell.part_pose_truth(self.cube).position_m[:2]
            dx, dy = drag["from_xy"] + target * drag["direction"] - here
            self.run.cell.displace_part(self.cube, float(dx), float(dy))
            drag["applied"] = target
            drag["ticks"] += 1
        if finish or drag["applied"] >= drag["distance"] - 1e-12:
            self._finish()

    def _finish(self) -> None:
        assert self._drag is not None
        self.details.update(end_s=self._now(), ticks=self._drag["ticks"], dragged_mm=_mm(self._drag["applied"]))
        self._drag = None


class ReleaseHeight(Injector):
    """Release error (Fig. 2g): the cube is let go above the table and drops.

    An execution error of the robot, not of its reports: the context's ``release_clearance_m``
    becomes ``height_m`` from the first "lift the part" of ``pick <obj>`` until the first
    ``place <obj>`` ends, then the nominal clearance is restored, so only that placing drops the
    cube (not another object's, nor the placing after a regrasp). Deterministic: no draw.

    Record: ``release_clearance_mm`` (injected), ``nominal_clearance_mm``, ``start_s``, ``end_s``.
    """

    name = "release_height"
    PARAMETERS = (Parameter("height_m", 0.005, 0.0, 0.030, "m", low_inclusive=True),)

    def __init__(self, height_m: float = 0.005) -> None:
        super().__init__(height_m=height_m)
        self._nominal_m: float | None = None

    def _attach(self, run: InjectableRun, obj: str) -> None:
        self._on_stage(Pick, LIFT_STAGE, self._apply)

        def restore(transition: Transition) -> None:
            node = run.node(transition)
            if (
                self._nominal_m is not None
                and isinstance(node, Place)
                and node.obj == obj
                and transition.old == Status.RUNNING.value
                and transition.new != Status.RUNNING.value
            ):
                run.context.settings = dataclasses.replace(run.context.settings, release_clearance_m=self._nominal_m)
                self._nominal_m = None
                self.details["end_s"] = round(transition.time_s, 4)

        run.transition_hooks.append(restore)

    def _apply(self, node: py_trees.behaviour.Behaviour) -> bool:
        context = self.run.context
        self._nominal_m = context.settings.release_clearance_m
        context.settings = dataclasses.replace(context.settings, release_clearance_m=self.params["height_m"])
        self.fired = True
        self.details.update(
            start_s=self._now(),
            release_clearance_mm=_mm(self.params["height_m"]),
            nominal_clearance_mm=_mm(self._nominal_m),
        )
        return True


class ReleaseTilt(Injector):
    """Tilting error (Fig. 2h): the cube tips as the gripper opens, falls back flat and moves.

    When ``place <obj>`` runs "release the part", as soon as the opening pads are clear of the
    tilted cube, it is turned about a random horizontal axis through its centre (direction uniform)
    by an angle uniform in [0, ``max_deg``], lifted just enough to keep its lowest corner above the
    table (pybullet reset of the cube's true pose), and left to fall back.

    Record: ``tilt_deg``, ``axis_deg`` (direction of the axis in the table plane, from world x),
    ``lift_mm``, ``time_s``.
    """

    name = "release_tilt"
    PARAMETERS = (Parameter("max_deg", 5.0, 0.0, 30.0, "deg"),)
    #: Gap kept between a pad and the tilted cube when it is turned, in metres.
    PAD_GAP_M = 0.0005

    def __init__(self, max_deg: float = 5.0) -> None:
        super().__init__(max_deg=max_deg)
        self._draw: tuple[float, float] | None = None

    def _attach(self, run: InjectableRun, obj: str) -> None:
        finder = _NodeFinder(Place, obj)

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            node = finder(root)
            if self.fired or node is None or node.status != Status.RUNNING:
                return
            if self._draw is None:
                if node.feedback_message != RELEASE_STAGE:
                    return
                self._draw = (
                    float(self.rng.uniform(-math.pi, math.pi)),
                    float(self.rng.uniform(0.0, math.radians(self.params["max_deg"]))),
                )
            if self._pads_clear() or node.feedback_message != RELEASE_STAGE:
                self._tilt()

        run.tick_hooks.append(hook)

    def _tilted(self) -> tuple[np.ndarray, np.ndarray]:
        """The cube's rotation after the tilt, and its current position."""
        assert self._draw is not None
        axis_rad, tilt_rad = self._draw
        truth = self.run.cell.part_pose_truth(self.cube)
        axis = np.array([math.cos(axis_rad), math.sin(axis_rad), 0.0])
        return _axis_angle(axis, tilt_rad) @ quaternion_to_matrix(truth.quaternion_xyzw), truth.position_m.copy()

    def _box(self) -> Shape:
        """The tilted part's shape: a box (the tilt row's parts are; the detector's tilt check is a box's)."""
        shape = self.object_type.shape
        if not shape.rectangular:
            raise PlanError(f"the tilt error tilts boxes only, not a {self.object_type.name}")
        return shape

    def _pads_clear(self) -> bool:
        cell = self.run.cell
        rotation, position = self._tilted()
        tcp = cell.arm.tcp_pose()
        closing = tcp.rotation[:, 0]
        centre_off_m = abs(float((position - tcp.position_m) @ closing))
        reach = self._box().support_m(rotation.T @ closing) + centre_off_m
        pads = [cell.finger_opening_m(f) for f in cell.finger_joint_indices]
        return min(pads) >= reach + self.PAD_GAP_M

    def _tilt(self) -> None:
        assert self._draw is not None
        cell = self.run.cell
        rotation, position = self._tilted()
        lowest_m = self._box().support_m(rotation[2, :])
        z = max(float(position[2]), lowest_m + 1e-4)
        moved = Pose.from_rotation([position[0], position[1], z], rotation)
        cell.place_part_truth(self.cube, moved)
        self.fired = True
        axis_rad, tilt_rad = self._draw
        self.details.update(
            time_s=self._now(), tilt_deg=_deg(tilt_rad), axis_deg=_deg(axis_rad), lift_mm=_mm(z - position[2])
        )


def _axis_angle(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Rotation matrix of ``angle_rad`` about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle_rad) * k + (1.0 - math.cos(angle_rad)) * (k @ k)
