"""3) Transport (the paper's Sec. 3, Fig. 2e): the cube slips in the gripper during the carry."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import py_trees
from py_trees.common import Status

from bt_arrange.behaviours import Place, keys
from bt_arrange_sim.injection.framework import CARRY_STAGE, Injector, Parameter, _mm, _NodeFinder, read_blackboard

if TYPE_CHECKING:
    from bt_arrange_sim.injection.framework import InjectableRun


class TransportSlip(Injector):
    """Grip error (Fig. 2e): the cube slips in the gripper during transport.

    At a random point of the carry (while ``place <obj>`` runs "carry above the target", once the
    TCP has covered a fraction, uniform in [0.1, 0.9], of its horizontal distance to the target)
    the pads' lateral friction is scaled by ``friction_scale`` for ``duration_s`` of world time, then
    restored to ``pad_contact``; it is restored early if the carry stops (the cube fell out and
    the guard interrupted it). Defaults: the grip is lost (scale 0) for 50 ms, so the cube falls
    about 16 mm down the pads and slides along them under the carry's acceleration, then is caught
    again. Windows of 0.1 s or more drop it: the guard and a regrasp take over. The 40 N grip holds
    the 0.1 kg cube down to a scale of about 0.04; above that nothing slips.

    Record: ``carry_fraction``, ``lateral_friction`` (during the window), ``start_s``, ``end_s``,
    ``slip_mm`` (the cube's true displacement in the TCP frame over the window, for the log:
    x along the closing axis, y along the pads, z down the pads), ``held_after`` (both pads touch it).
    """

    name = "transport_slip"
    PARAMETERS = (
        Parameter("duration_s", 0.05, 0.0, 10.0, "s"),
        Parameter("friction_scale", 0.0, 0.0, 1.0, "", low_inclusive=True),
    )
    #: Range of the carry's progress (fraction of the horizontal distance to the target) where the slip begins.
    CARRY_FRACTION = (0.1, 0.9)

    def __init__(self, duration_s: float = 0.05, friction_scale: float = 0.0) -> None:
        super().__init__(duration_s=duration_s, friction_scale=friction_scale)
        self._start: tuple[float, np.ndarray] | None = None
        self._carry: dict[str, Any] | None = None

    def _attach(self, run: InjectableRun, obj: str) -> None:
        finder = _NodeFinder(Place, obj)

        def hook(root: py_trees.behaviour.Behaviour) -> None:
            node = finder(root)
            if node is None:
                return
            if self._start is None:
                if not self.fired and node.status == Status.RUNNING and node.feedback_message == CARRY_STAGE:
                    self._maybe_begin()
                return
            elapsed = run.cell.sim_time_s - self._start[0]
            if elapsed >= self.params["duration_s"] - 1e-9 or node.status != Status.RUNNING:
                self._end()

        run.tick_hooks.append(hook)

    def _maybe_begin(self) -> None:
        """Begin the slip once the carry has covered the drawn fraction of its way."""
        tcp_xy = self.run.cell.arm.tcp_pose().position_m[:2]
        if self._carry is None:
            target = read_blackboard(keys.key(self.cube, keys.TARGET))
            goal = np.array([target.x_m, target.y_m]) if target is not None else tcp_xy
            self._carry = {
                "from": tcp_xy.copy(),
                "distance": float(np.linalg.norm(goal - tcp_xy)),
                "fraction": float(self.rng.uniform(*self.CARRY_FRACTION)),
            }
        travelled = float(np.linalg.norm(tcp_xy - self._carry["from"]))
        if travelled >= self._carry["fraction"] * self._carry["distance"]:
            self._begin()

    def _set_pad_friction(self, friction: float) -> None:
        """Give both pads ``friction``, effective at once for the held cube (``WorkCell.set_pad_friction``)."""
        self.run.cell.set_pad_friction(self.cube, friction)

    def _cube_in_tcp(self) -> np.ndarray:
        cell = self.run.cell
        return cell.arm.tcp_pose().inverse().transform_point(cell.part_pose_truth(self.cube).position_m)

    def _begin(self) -> None:
        cell = self.run.cell
        friction = cell.config.physics.pad_contact.lateral_friction * self.params["friction_scale"]
        self._set_pad_friction(friction)
        self.fired = True
        self._start = (cell.sim_time_s, self._cube_in_tcp())
        assert self._carry is not None
        self.details.update(
            carry_fraction=round(self._carry["fraction"], 4), start_s=self._now(), lateral_friction=round(friction, 6)
        )

    def _end(self) -> None:
        assert self._start is not None
        cell = self.run.cell
        slip = self._cube_in_tcp() - self._start[1]
        held = bool(cell.part_in_gripper_truth(self.cube))
        self._set_pad_friction(cell.config.physics.pad_contact.lateral_friction)
        self.details.update(end_s=self._now(), slip_mm=[_mm(v) for v in slip], held_after=held)
        self._start = None
