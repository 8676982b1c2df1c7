"""A behaviour made of stages that never block: a motion, a gripper action, a check.

``StagedBehaviour.initialise()`` builds the stage list from the blackboard and starts the first
stage (planning its motion); each ``update()`` advances the current stage by one control period
and moves on to the next when it ends. Errors of the framework (``BtArrangeError``) become
FAILURE with the error as the feedback message. An interrupted motion is handed to the
context's ``ArmBrake``, which finishes its jerk-limited stop. An error raised while a stage
runs (a ``MotionError`` mid-motion) is a FAILURE too, and its motion goes to the brake as well.

The base class owns the behaviour's blackboard client: a subclass declares its keys with
``reads(...)`` and ``writes(...)`` in ``__init__`` and reads them with ``read(key, written_by)``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Access, Status

from bt_arrange.behaviours import keys
from bt_arrange.behaviours import stages as stage_names
from bt_arrange.behaviours.context import Context
from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.geometry import FloatArray
from bt_arrange.motion import Motion

#: The statuses, looked up once: ``Status.RUNNING`` goes through the enum's class on every use
#: (about 80 ns), and the tick's own code (here, the guards, the runner) runs every control period.
RUNNING, SUCCESS, FAILURE, INVALID = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID


class Stage(ABC):
    """One step of a behaviour. ``start`` and ``poll`` may raise ``BtArrangeError``; ``poll`` runs once per tick."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.reason = ""

    def start(self, context: Context) -> None:
        """Begin the step (plan a motion, command the gripper); a step that only polls needs nothing here."""
        return None

    @abstractmethod
    def poll(self, context: Context) -> Status:
        """Advance by one control period; RUNNING, SUCCESS, or FAILURE with ``self.reason`` set."""

    def interrupt(self, context: Context) -> None:
        """The behaviour was interrupted while this step ran; a step without a motion has nothing to hand on."""
        return None


#: py_trees' log levels, looked up once: ``debug_logging`` is asked several times a tick.
_DEBUG_LEVEL, _INFO_LEVEL = py_trees.logging.Level.DEBUG, py_trees.logging.Level.INFO
_PY_TREES_LOGGING = py_trees.logging


def debug_logging() -> bool:
    """Whether py_trees logs at DEBUG (its ``logger.debug`` prints only then): the per-tick message is built only so."""
    # ``level < Level.INFO``: the usual INFO and DEBUG told by identity, not through IntEnum's comparison.
    level = _PY_TREES_LOGGING.level
    return level is _DEBUG_LEVEL or (level is not _INFO_LEVEL and level < 1)


def end_tick(node: py_trees.behaviour.Behaviour, new_status: Status) -> None:
    """The end of py_trees' ``Behaviour.tick`` after ``update()``: an invalid status logged, a stop, the status set."""
    # A status a behaviour may return is a member of ``Status``: checked by its type (py_trees builds
    # ``list(Status)`` at every tick; a set of them would hash each member in Python).
    if type(new_status) is not Status:
        node.logger.error(f"A behaviour returned an invalid status, setting to INVALID [{new_status}][{node.name}]")
        new_status = INVALID
    if new_status is not RUNNING:
        node.stop(new_status)
    node.status = new_status


#: Decides, after each setpoint, whether a motion may be handed on at speed to the next stage.
HandOn = Callable[[Context, Motion], bool]


class MoveStage(Stage):
    """Follow a motion planned at the start of the step, then let the arm settle.

    ``plan(context, q)`` receives the measured joint positions and returns the motion. A plan that
    can start from a moving arm (``moving_start``: a joint move, e.g. ``moves.to_pose``) is called as
    ``plan(context, q, velocities, accelerations)`` when the previous stage handed its motion on at
    speed; any other waits for that motion to be braked to rest first.

    ``hand_on(context, motion)``, when given, is asked after every setpoint: once it holds, the
    step ends without stopping or settling and the motion runs on (``ArmBrake.carry_on``) until the
    next motion takes it over: the waypoint is passed at speed, where nothing needs the arm at rest.
    """

    def __init__(
        self,
        name: str,
        plan: Callable[..., Motion],
        hand_on: HandOn | None = None,
    ) -> None:
        super().__init__(name)
        self._plan = plan
        self._hand_on = hand_on
        self.motion: Motion | None = None
        #: The joint vector the motion starts from (rad): measured, or a handed-on motion's last setpoint.
        self.start_q: FloatArray | None = None
        self._done_at_s: float | None = None
        self._waiting_for_rest = False
        self._skip_command = False

    def start(self, context: Context) -> None:
        """Plan the motion from where the arm is now, taking over a motion handed on at speed if it can."""
        self._done_at_s = None
        self._skip_command = False
        self._waiting_for_rest = False
        self.motion = None
        brake = context.brake
        if brake.carrying:
            if not getattr(self._plan, "moving_start", False):
                brake.brake_carried()
                self._waiting_for_rest = True
                return
            q, velocities, accelerations, commanded = brake.take_over()
            self.start_q = q
            self.motion = self._plan(context, q, velocities, accelerations)
            # The handed-on motion already had this period's setpoint: the new one starts with the next.
            self._skip_command = commanded
            return
        self.start_q = context.robot.arm.joint_positions()
        self.motion = self._plan(context, self.start_q)

    def poll(self, context: Context) -> Status:
        """Send the next setpoint; after the last one, wait until the arm is still (at most ``settle_s``)."""
        if self._waiting_for_rest:
            if context.brake.active:
                return RUNNING
            self._waiting_for_rest = False
            self.start_q = context.robot.arm.joint_positions()
            self.motion = self._plan(context, self.start_q)
        assert self.motion is not None
        clock = context.robot.clock
        if self._skip_command:
            self._skip_command = False
            return RUNNING
        if not self.motion.done:
            setpoint = self.motion.step()
            context.robot.arm.command(setpoint.positions_rad, setpoint.velocities_rad_s)
            if not self.motion.done and self._hand_on is not None and self._hand_on(context, self.motion):
                context.brake.carry_on(self.motion)
                return SUCCESS
            if self.motion.done:
                self._done_at_s = clock.now()
            # Even after the last setpoint: the next stage commands the arm on the next tick, not this one.
            return RUNNING
        assert self._done_at_s is not None
        settings = context.settings
        # Settled when measured so, not after a fixed wait: the joints track a jerk-limited motion
        # closely and are usually still one control period after its last setpoint.
        still = float(np.max(np.abs(context.robot.arm.joint_velocities()))) < settings.settled_speed_rad_s
        if not still and clock.now() - self._done_at_s < settings.settle_s:
            return RUNNING
        return SUCCESS

    def interrupt(self, context: Context) -> None:
        """Hand a running motion to the brake."""
        if self.motion is not None and not self.motion.done and not self.motion.handed_on:
            context.brake.take(self.motion)


class GripperStage(Stage):
    """Command the gripper, then wait until the fingers stop (or fail after the timeout).

    An opening (``opens_to_m``, the width it commands) is done only when the fingers stopped there:
    fingers that stop short are held apart by the part, wedged between the pads. Then ``on_stall``
    (if given) is sent once, e.g. open all the way, and the fingers are waited for again; stopping
    short a second time fails, naming the widths.
    """

    #: Control periods to wait before reading the fingers' speed: they need a moment to start.
    START_PERIODS = 3
    #: Fingers stopped more than this short of an opening they were sent to (metres): held apart.
    STALL_SHORT_M = 0.002

    def __init__(
        self,
        name: str,
        command: Callable[[Context], None],
        wait: bool = True,
        start_periods: int | None = None,
        *,
        opens_to_m: Callable[[Context], float] | None = None,
        on_stall: Callable[[Context], None] | None = None,
    ) -> None:
        """``start_periods``: polls before the fingers' speed counts (``START_PERIODS``; 0 after a command)."""
        super().__init__(name)
        self._command = command
        self._wait = wait
        self._start_periods = self.START_PERIODS if start_periods is None else start_periods
        self._opens_to_m = opens_to_m
        self._on_stall = on_stall
        self._started_at_s = 0.0
        self._polls = 0
        self._commanded = False
        #: How often the fingers stopped short of the opening (0 when they reached it).
        self.stalled = 0

    def start(self, context: Context) -> None:
        """Send the command (a waiting one only with the arm at rest: a motion handed on is braked first)."""
        self._polls = 0
        self._commanded = False
        self.stalled = 0
        if self._wait and context.brake.carrying:
            context.brake.brake_carried()
            return
        self._send(context)

    def _send(self, context: Context) -> None:
        self._command(context)
        self._commanded = True
        self._started_at_s = context.robot.clock.now()

    def poll(self, context: Context) -> Status:
        """SUCCESS once the fingers stand still (where an opening sent them)."""
        if not self._wait:
            return SUCCESS
        if not self._commanded:
            if context.brake.active:
                return RUNNING
            self._send(context)
        self._polls += 1
        gripper = context.robot.gripper
        if self._polls <= self._start_periods or gripper.is_moving():
            waited_s = context.robot.clock.now() - self._started_at_s
            if waited_s > context.settings.gripper_timeout_s:
                self.reason = (
                    f"{self.name}: fingers still moving after {waited_s:.1f} s "
                    f"(limit {context.settings.gripper_timeout_s:.1f} s), width {gripper.width() * 1000:.1f} mm"
                )
                return FAILURE
            return RUNNING
        if self._opens_to_m is None:
            return SUCCESS
        wanted_m, width_m = self._opens_to_m(context), gripper.width()
        if width_m >= wanted_m - self.STALL_SHORT_M:
            return SUCCESS
        self.stalled += 1
        if self._on_stall is not None and self.stalled == 1:
            self._on_stall(context)
            self._polls = 0
            self._started_at_s = context.robot.clock.now()
            return RUNNING
        self.reason = (
            f"{self.name}: the fingers stopped at {width_m * 1000:.1f} mm, short of {wanted_m * 1000:.1f} mm: "
            "the part is wedged between the pads"
        )
        return FAILURE


class InstantStage(Stage):
    """A step done within one tick: ``action(context)`` returns ``None``, or a reason to fail."""

    def __init__(self, name: str, action: Callable[[Context], str | None]) -> None:
        super().__init__(name)
        self._action = action
        self._result: str | None = None

    def start(self, context: Context) -> None:
        """Do it."""
        self._result = self._action(context)

    def poll(self, context: Context) -> Status:
        """SUCCESS, or FAILURE with the action's reason."""
        if self._result is not None:
            self.reason = self._result
            return FAILURE
        return SUCCESS


class OnlyIf(Stage):
    """Run ``stage`` only when ``condition(context)`` holds as the step starts; otherwise skip it."""

    def __init__(self, stage: Stage, condition: Callable[[Context], bool]) -> None:
        super().__init__(stage.name)
        self._stage = stage
        self._condition = condition
        self._active = False

    def start(self, context: Context) -> None:
        """Decide, then start the wrapped step if it runs."""
        self._active = self._condition(context)
        if self._active:
            self._stage.start(context)

    def poll(self, context: Context) -> Status:
        """The wrapped step's status, or SUCCESS when skipped."""
        if not self._active:
            return SUCCESS
        status = self._stage.poll(context)
        self.reason = self._stage.reason
        return status

    def interrupt(self, context: Context) -> None:
        """Pass an interruption on."""
        if self._active:
            self._stage.interrupt(context)


class StagedBehaviour(py_trees.behaviour.Behaviour):
    """A behaviour that runs ``stages()`` one after the other, never blocking a tick.

    Subclasses declare their blackboard keys in ``__init__`` with ``reads()`` and ``writes()``
    (configuration only: a tree can be built and drawn without a robot), build their stages in
    ``stages()`` from the blackboard, and may say what they achieved in ``success_message()``.
    """

    def __init__(self, name: str) -> None:
        super().__init__(name=name)
        #: The behaviour's blackboard client; its keys are declared with ``reads()`` and ``writes()``.
        self.blackboard = self.attach_blackboard_client(name=name)
        self.context: Context | None = None
        self._stages: list[Stage] = []
        self._index = 0
        self._started = False
        self._failure: str | None = None
        #: The stage running now (a name of ``bt_arrange.behaviours.stages``), None between runs and
        #: while the arm brakes: what injectors and tests look for, the feedback being for people.
        self.stage: str | None = None
        #: The keys this behaviour cannot run without, each with who should write it: the tree's
        #: pre-run check (``bt_arrange.keycheck``) finds a writer for each before anything moves.
        self.required_reads: dict[str, str] = {}

    @property
    def facts(self) -> dict[str, Any]:
        """What this behaviour's last run established, as data (copied onto each ``Transition``)."""
        return {}

    def setup(self, **kwargs: Any) -> None:
        """Receive the ``context`` keyword that ``BehaviourTree.setup(context=...)`` hands out."""
        context = kwargs.get("context")
        if not isinstance(context, Context):
            raise BtArrangeError(
                f"behaviour {self.name!r} needs setup(context=Context(...)), got {type(context).__name__}"
            )
        self.context = context

    @abstractmethod
    def stages(self, context: Context) -> list[Stage]:
        """The steps of this run, built from the blackboard when the behaviour starts."""

    def success_message(self) -> str:
        """Feedback once every stage succeeded."""
        return "done"

    def reads(self, *keys: str, written_by: str | None = None) -> None:
        """Declare blackboard keys this behaviour reads (absolute, e.g. ``keys.key("red", keys.POSE)``).

        With ``written_by`` (who should write them, for the message) the keys are required: the
        tree's pre-run check (``bt_arrange.keycheck.check_keys``) refuses a tree in which no node
        before this one writes them. Without it a key is optional (read when it exists).
        """
        for key in keys:
            self.blackboard.register_key(key, access=Access.READ)
            if written_by is not None:
                self.required_reads[key] = written_by

    def writes(self, *keys: str) -> None:
        """Declare blackboard keys this behaviour writes."""
        for key in keys:
            self.blackboard.register_key(key, access=Access.WRITE)

    def read(self, key: str, written_by: str) -> Any:
        """A blackboard value this behaviour needs; a ``PlanError`` naming the key when it is missing."""
        if not self.blackboard.exists(key):
            raise PlanError(f"{self.name} needs {key} on the blackboard, written by {written_by}: run that first")
        return self.blackboard.get(key)

    def write(self, key: str, value: Any) -> None:
        """Write a declared key (overwriting)."""
        self.blackboard.set(key, value, overwrite=True)

    def initialise(self) -> None:
        """Build the stages and start the first one (plan its motion) unless the arm is still braking."""
        context = self._require_context()
        self._index = 0
        self._started = False
        self._failure = None
        try:
            self._stages = self.stages(context)
        except BtArrangeError as error:
            self._failure = str(error)
            self._stages = []
            return
        if self._stages and not context.brake.active:
            self._start_current(context)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """py_trees' ``Behaviour.tick``, step for step, without what it recomputes for nothing each tick.

        A behaviour is ticked every control period (125 Hz) while it runs: its debug message is
        formatted only when py_trees logs at DEBUG, and a status is checked by its type (``end_tick``)
        instead of against ``list(Status)`` built at every tick.
        """
        if debug_logging():
            self.logger.debug(f"{self.__class__.__name__}.tick()")
        if self.status != RUNNING:
            self.initialise()
        # Not self.status yet: terminate() may need to check what the current state is first.
        new_status = self.update()
        end_tick(self, new_status)
        yield self

    def update(self) -> Status:
        """Advance the current stage by one control period; move on when it ends."""
        context = self._require_context()
        self.stage = None
        if self._failure is not None:
            self.feedback_message = self._failure
            return FAILURE
        if context.brake.active:
            self.feedback_message = stage_names.WAITING_FOR_BRAKE
            return RUNNING
        while self._index < len(self._stages):
            stage = self._stages[self._index]
            if not self._started and not self._start_current(context):
                self.feedback_message = self._failure or ""
                return FAILURE
            try:
                status = stage.poll(context)
            except BtArrangeError as error:
                self.feedback_message = self._abandon(stage, context, error)
                return FAILURE
            if status == RUNNING:
                self.feedback_message = self.stage = stage.name
                return RUNNING
            if status == FAILURE:
                self.feedback_message = stage.reason or f"{stage.name} failed"
                return FAILURE
            self._index += 1
            self._started = False
        self.feedback_message = self.success_message()
        return SUCCESS

    def terminate(self, new_status: Status) -> None:
        """On interruption (INVALID), hand a running motion to the brake."""
        if new_status == INVALID and self.context is not None and self._index < len(self._stages):
            if self._started:
                self._stages[self._index].interrupt(self.context)
            self.feedback_message = stage_names.INTERRUPTED
        self.stage = None

    def _abandon(self, stage: Stage, context: Context, error: BtArrangeError) -> str:
        """A stage raised mid-run: hand its motion to the brake and say why the behaviour fails."""
        reason = f"{stage.name}: {error}"
        self._started = False  # the stage is over: a later interruption has nothing to hand on
        try:
            stage.interrupt(context)
        except BtArrangeError as stop_error:  # the motion cannot even be stopped: the arm holds its last setpoint
            reason += f" (and its stop failed: {stop_error})"
        return reason

    def _start_current(self, context: Context) -> bool:
        stage = self._stages[self._index]
        try:
            stage.start(context)
        except BtArrangeError as error:
            self._failure = f"{stage.name}: {error}"
            return False
        self._started = True
        return True

    def _require_context(self) -> Context:
        if self.context is None:
            raise BtArrangeError(f"behaviour {self.name!r} was not set up: call tree.setup(context=...) first")
        return self.context


def entry_remaps(node: py_trees.behaviour.Behaviour) -> dict[str, str]:
    """The entries of ``node``'s object it reads or writes elsewhere: field -> absolute key (none: all its own)."""
    remaps: dict[str, str] = node.__dict__.get("entry_remaps", {})
    return remaps


def remap_entry(node: py_trees.behaviour.Behaviour, field: str, key: str) -> None:
    """Make ``node`` read and write its object's entry ``field`` (``/<obj>/<field>``) at ``key`` instead.

    The node keeps asking for ``/<obj>/<field>``; its blackboard client stores it at ``key``
    (py_trees' ``remap_to``), so the pre-run key check and a watcher see the key it really uses.
    An entry the node has not registered (a key it reads only in some trees) is remembered all the same.
    """
    canonical = keys.key(node.obj, field)  # type: ignore[attr-defined]
    remaps = node.__dict__.setdefault("entry_remaps", {})
    if key == canonical:
        remaps.pop(field, None)
    else:
        remaps[field] = key
    for client in node.blackboards:
        held = [
            access
            for access, names in (
                (Access.READ, client.read),
                (Access.WRITE, client.write),
                (Access.EXCLUSIVE_WRITE, client.exclusive),
            )
            if canonical in names
        ]
        if not held:
            continue
        metadata = py_trees.blackboard.Blackboard.metadata.get(client.remappings.get(canonical, canonical))
        if metadata is not None:
            for holders in (metadata.read, metadata.write, metadata.exclusive):
                holders.discard(client.unique_identifier)
        for access in held:
            client.register_key(canonical, access=access, remap_to=key)
