"""RepeatUntilWithin: repeat a correction until an offset on the blackboard is within a threshold.

The paper's inner loop (Algorithm 1, lines 11-15) as a py_trees decorator::

    while offset >= threshold:
        push; inspect (which writes the new offset)

It behaves like py_trees' ``Repeat`` (a success of the child runs it again, a failure ends the
loop), with the offset checked before each run, not like ``Retry`` (which runs again on failure).
``RetryUntilThreshold`` is its former name, kept as an alias.
"""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Access, Status

from bt_arrange.behaviours import keys
from bt_arrange.checks import whole_number
from bt_arrange.numbers import fixed
from bt_arrange.plan.layout_part import pushed_from
from bt_arrange.plan.tolerance import Tolerance
from bt_arrange.ports import BOOL, INT, KEY, LIMIT, OFF_DOUBLE, OUTPUT, Port
from bt_arrange.uncertainty import CAMERA_MARGIN_KEY

#: A correction that closes less than this share of the best offset (and of the best yaw error)
#: so far counts towards ``stall_after``.
STALL_FRACTION = 0.1


class RepeatUntilWithin(py_trees.decorators.Decorator):
    """Run the child until the blackboard value at ``offset_key`` drops below ``threshold_mm``.

    - Before each run of the child: SUCCESS at once when the offset is already under the
      threshold (no correction is started).
    - The child (e.g. Sequence[Push, Inspect]) must update the offset; each SUCCESS of the child
      counts one correction, recorded at ``corrections_key`` when given.
    - FAILURE with the residual offset in the feedback message once ``max_attempts`` corrections
      left it above the threshold; FAILURE with the child's reason when the child fails.

    ``obj`` names the object corrected, for reports that look for the reason an object failed.
    With ``yaw_key`` and ``yaw_threshold_deg`` the object is within only when the absolute yaw error
    there (degrees) is under ``yaw_threshold_deg`` too: the loop also corrects yaw.

    The offset counts as under the threshold only with the camera's own error added: the margin
    the session writes at ``bt_arrange.uncertainty.CAMERA_MARGIN_KEY`` (mm; none there, no margin),
    ``margins`` times (2 for a part a neighbour's recheck will read again).
    """

    #: The node's description in the XML ``TreeNodesModel``.
    node_description = "re-run the child until the offset is under the threshold"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        """The offset's key and threshold, the attempts, the counter's key, the yaw's (``providedPorts``)."""
        return (
            Port("offset_key", KEY, description="blackboard key of the offset [mm]"),
            Port("threshold_mm", LIMIT, description="succeed once the offset is under this [mm] (inf: yaw only)"),
            Port("max_attempts", INT, 10, "corrections before giving up"),
            Port(
                "corrections_key", KEY, None, "blackboard key counting the corrections (empty: none)", direction=OUTPUT
            ),
            Port("yaw_key", KEY, None, "blackboard key of the yaw error [deg] (empty: position only)"),
            Port("yaw_threshold_deg", OFF_DOUBLE, None, "succeed once the yaw error is under this too [deg] (0: off)"),
            Port("stall_after", INT, 0, "fail once this many corrections in a row closed nothing (0: off)"),
            Port("accumulate", BOOL, False, "count on from what the corrections key holds (a second loop)"),
            Port("margins", INT, 1, "the camera's error counted this many times (2: a later recheck reads it again)"),
            Port(
                "release_again",
                BOOL,
                False,
                "the child may release the part again past its place for a blocked push: allowed only with a "
                "correction left to push it back, and while doing so brings it closer",
            ),
        )

    def __init__(
        self,
        name: str,
        child: py_trees.behaviour.Behaviour,
        offset_key: str,
        threshold_mm: float,
        max_attempts: int,
        corrections_key: str | None = None,
        obj: str | None = None,
        yaw_key: str | None = None,
        yaw_threshold_deg: float | None = None,
        stall_after: int = 0,
        accumulate: bool = False,
        margins: int = 1,
        release_again: bool = False,
    ) -> None:
        #: The thresholds and the one "within" rule the loop asks (the report asks the plan's too).
        self.tolerance = Tolerance(threshold_mm, yaw_threshold_deg)
        whole_number("margins", margins, style="unit")
        if stall_after:
            whole_number("stall_after", stall_after, style="unit")
        whole_number("max_attempts", max_attempts, style="unit")
        super().__init__(name=name, child=child)
        self.offset_key = offset_key
        self.max_attempts = max_attempts
        self.corrections_key = corrections_key
        #: The object corrected: ``obj``, else the one whose offset it watches (``/<obj>/offset_mm``).
        self.obj = obj if obj is not None else keys.object_of_key(offset_key)
        self.attempts = 0
        self.yaw_key = yaw_key if yaw_threshold_deg is not None else None
        #: Corrections in a row that closed less than ``STALL_FRACTION`` of the best offset and yaw error so far
        #: end the loop with FAILURE ("stopped converging"), for a fallback above it; 0: never.
        self.stall_after = int(stall_after)
        self._best: tuple[float, float] | None = None
        self._stalls = 0
        #: With ``accumulate`` the count at ``corrections_key`` goes on from what it held (a second loop of one object).
        self.accumulate = accumulate
        self._counted_before = 0
        #: The camera's error is added this many times: twice for a part a later neighbour's recheck
        #: reads again (a reading beside a neighbour differs by up to that error once more), so that
        #: a part accepted here is still within when looked at again, not left a hair outside.
        self.margins = int(margins)
        self.stalled_key = keys.key(self.obj, keys.PUSHES_STALLED) if stall_after and self.obj else None
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(offset_key, access=Access.READ)
        #: The key it cannot judge without, and who writes it (``bt_arrange.keycheck``).
        self.required_reads: dict[str, str] = {offset_key: f"an Inspect{'' if self.obj is None else ' of ' + self.obj}"}
        if self.yaw_key is not None:
            self.blackboard.register_key(self.yaw_key, access=Access.READ)
        self.blackboard.register_key(CAMERA_MARGIN_KEY, access=Access.READ)
        #: What the last look measured the part on (``keys.MEASURED_ON``): free edges cannot confirm "within".
        self.measured_on_key = keys.key(self.obj, keys.MEASURED_ON) if self.obj else None
        if self.measured_on_key is not None:
            self.blackboard.register_key(self.measured_on_key, access=Access.READ)
        if corrections_key is not None:
            self.blackboard.register_key(corrections_key, access=Access.WRITE)
        if self.stalled_key is not None:
            self.blackboard.register_key(self.stalled_key, access=Access.WRITE)
        #: The child may release the part again past its place (a restaging, for a push a neighbour
        #: blocks): the loop says before each correction whether it may (``keys.RELEASE_AGAIN``), and
        #: ends when releasing it again did not bring it closer than its best before, where it would cycle.
        self.release_again = bool(release_again) and self.obj is not None
        self.blocked_key = keys.key(self.obj, keys.BLOCKED_TOWARDS) if self.release_again and self.obj else None
        self.release_again_key = keys.key(self.obj, keys.RELEASE_AGAIN) if self.release_again and self.obj else None
        #: The last push a neighbour blocked in this loop, and that neighbour: its last word names them.
        self.blocked_by_key = keys.key(self.obj, keys.BLOCKED_BY) if self.obj else None
        self.any_blocked_key = keys.key(self.obj, keys.BLOCKED_TOWARDS) if self.obj else None
        if self.blocked_by_key is not None and self.any_blocked_key is not None:
            self.blackboard.register_key(self.blocked_by_key, access=Access.READ)
            self.blackboard.register_key(self.any_blocked_key, access=Access.READ)
        self.last_blocked: tuple[str, str] | None = None
        self.offset_xy_key = keys.key(self.obj, keys.OFFSET_XY_MM) if self.release_again and self.obj else None
        if self.blocked_key is not None and self.release_again_key is not None and self.offset_xy_key is not None:
            self.blackboard.register_key(self.blocked_key, access=Access.READ)
            self.blackboard.register_key(self.offset_xy_key, access=Access.READ)
            self.blackboard.register_key(self.release_again_key, access=Access.WRITE)
        #: The smallest offset measured (mm) and the first one (as placed), for the last word.
        self.best_offset_mm: float | None = None
        self.first_offset_mm: float | None = None
        #: Per direction the part was released again for, how far it had to go that way then (mm).
        self._released_for: dict[str, float] = {}
        #: The offset (target frame, mm) before the correction running now.
        self._offset_xy_before: tuple[float, float] | None = None

    @property
    def threshold_mm(self) -> float:
        """The offset's threshold [mm] (``inf``: yaw only)."""
        return self.tolerance.threshold_mm

    @property
    def yaw_threshold_deg(self) -> float | None:
        """The yaw error's threshold [deg], or None: position only."""
        return self.tolerance.yaw_threshold_deg

    def initialise(self) -> None:
        """Start counting corrections from zero."""
        self.attempts = 0
        self._best = None
        self._stalls = 0
        self._counted_before = 0
        self.best_offset_mm = None
        self.first_offset_mm = None
        self._released_for = {}
        self._offset_xy_before = None
        self.last_blocked = None
        if self.accumulate and self.corrections_key is not None and self.blackboard.exists(self.corrections_key):
            self._counted_before = int(self.blackboard.get(self.corrections_key) or 0)
        if self.stalled_key is not None:
            self.blackboard.set(self.stalled_key, "no", overwrite=True)
        self._record()

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Check the offset before the child runs; run it only while a correction is needed."""
        if self.status != Status.RUNNING:
            self.initialise()
        if self.decorated.status != Status.RUNNING:
            verdict = self._verdict()
            if verdict is not None:
                self.stop(verdict)
                yield self
                return
        yield from self.decorated.tick()
        new_status = self.update()
        if new_status != Status.RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def update(self) -> Status:
        """After a tick of the child: count a finished correction, pass on a failure."""
        child = self.decorated
        if child.status == Status.FAILURE:
            self._note_blocked()
            self.feedback_message = f"correction failed: {child.feedback_message or self._not_released_text()}"
            return Status.FAILURE
        if child.status == Status.SUCCESS:
            self.attempts += 1
            self._record()
            self._note_release_again()
            self._note_blocked()
            self.feedback_message = f"{self.attempts} correction(s), offset {self._offset_text()}"
            return Status.RUNNING  # the next tick checks the new offset before anything else
        self.feedback_message = f"correcting ({self.attempts} done), offset {self._offset_text()}"
        return Status.RUNNING

    def _verdict(self) -> Status | None:
        """SUCCESS or FAILURE when the loop is over, None to run the child once more."""
        offset = self._offset()
        if offset is None:
            self.feedback_message = f"no offset at {self.offset_key}: inspect the object before correcting it"
            return Status.FAILURE
        yaw = self._yaw_error()
        yaw_within = self.tolerance.yaw_within(yaw)
        yaw_text = "" if yaw is None or self.yaw_threshold_deg is None else f", yaw error {fixed(yaw, sign=True)} deg"
        margin = self._margin_mm()
        margin_text = f" + camera {margin:.2f} mm" if margin > 0 else ""
        if self.tolerance.within(offset, yaw, margin) and self._measured_on_free_edges():
            # The camera's margin covers a whole face, not a face merged with a neighbour's: pushing
            # further cannot make this measurement better, so the part is left unconfirmed, never within.
            self.feedback_message = (
                f"unconfirmed: offset {offset:.2f} mm{yaw_text} measured on its free edges only (its face merged "
                f"with a neighbour's of its colour), which cannot confirm it within {self.threshold_mm:.2f} mm"
            )
            return Status.FAILURE
        if self.tolerance.within(offset, yaw, margin):
            under = (
                f"offset {offset:.2f} mm"  # no offset threshold: the yaw alone decides (a regrasp)
                if self.tolerance.yaw_only
                else f"offset {offset:.2f} mm{margin_text} < {self.threshold_mm:.2f} mm"
            )
            self.feedback_message = f"{under}{yaw_text} after {self.attempts} correction(s)"
            return Status.SUCCESS
        self._remember(offset)
        if self._stalled(offset, yaw):
            if self.stalled_key is not None:
                self.blackboard.set(self.stalled_key, keys.STALLED, overwrite=True)
            self.feedback_message = (
                f"pushes stopped converging: offset {offset:.2f} mm{yaw_text} after {self.attempts} correction(s), "
                f"{self._stalls} in a row closing less than {STALL_FRACTION:.0%}{self._blocked_text()}"
            )
            return Status.FAILURE
        if self.attempts >= self.max_attempts:
            outside = not self.tolerance.offset_within(offset, margin)
            what = f"offset still {offset:.2f} mm" + (f"{margin_text} >= {self.threshold_mm:.2f} mm" if outside else "")
            if not yaw_within:
                what += f"{yaw_text} (>= {self.yaw_threshold_deg:.2f} deg)"
            self.feedback_message = (
                f"{what} after {self.attempts} correction(s){self._best_text(offset)}{self._blocked_text()}"
            )
            return Status.FAILURE
        self._allow_release_again()
        return None

    def _note_release_again(self) -> None:
        """After a correction that released the part again for a blocked push: remember how far it had to go."""
        if self.blocked_key is None or self._offset_xy_before is None:
            return
        towards = self.blackboard.get(self.blocked_key) if self.blackboard.exists(self.blocked_key) else None
        if towards in (None, keys.NOT_BLOCKED):
            return
        needed = _along(self._offset_xy_before, str(towards))
        if needed is not None:
            self._released_for[str(towards)] = needed

    def _allow_release_again(self) -> None:
        """Before a correction: say whether the child may release the part again (``keys.RELEASE_AGAIN``).

        Not with less than two corrections left (the push back would be missing), and not for a push
        whose way is no shorter than when the part was last released for it: released, pushed back
        and left as far short, it would only cycle. Free pushes go on either way.
        """
        if self.release_again_key is None or self.offset_xy_key is None:
            return
        offset_xy = self.blackboard.get(self.offset_xy_key) if self.blackboard.exists(self.offset_xy_key) else None
        self._offset_xy_before = (float(offset_xy[0]), float(offset_xy[1])) if offset_xy is not None else None
        allowed = keys.ALLOWED
        if self.max_attempts - self.attempts < 2:
            allowed = "no correction would be left to push it back"
        elif self._offset_xy_before is not None:
            for towards, before_mm in self._released_for.items():
                now_mm = _along(self._offset_xy_before, towards)
                if now_mm is not None and now_mm > 0.0 and now_mm >= before_mm * (1.0 - STALL_FRACTION):
                    allowed = (
                        f"released past its place for a push of {before_mm:.2f} mm towards {towards}, it came back "
                        f"{now_mm:.2f} mm short: released again, it would only cycle"
                    )
        self.blackboard.set(self.release_again_key, allowed, overwrite=True)

    def _note_blocked(self) -> None:
        """After a correction: remember a push a neighbour blocked (``/<obj>/blocked_towards``, ``blocked_by``)."""
        if self.any_blocked_key is None or self.blocked_by_key is None:
            return
        if not (self.blackboard.exists(self.any_blocked_key) and self.blackboard.exists(self.blocked_by_key)):
            return
        towards, by = self.blackboard.get(self.any_blocked_key), self.blackboard.get(self.blocked_by_key)
        if towards != keys.NOT_BLOCKED and by != keys.NOT_BLOCKED:
            self.last_blocked = (str(towards), str(by))

    def _blocked_text(self) -> str:
        """``"; its push towards +y was blocked on its -y side by blue"`` when a neighbour blocked one, else ``""``."""
        if self.last_blocked is None:
            return ""
        towards, by = self.last_blocked
        side = pushed_from(towards)
        if side is not None:
            return f"; its push towards {towards} was blocked on its {side} side by {by}"
        return f"; its push squarely towards {towards.lstrip('@')} deg was blocked by {by}"

    def _not_released_text(self) -> str:
        """Why a correction whose push was blocked ended: the push, and why the part was not released again."""
        if self.blocked_key is None or self.release_again_key is None or not self.blackboard.exists(self.blocked_key):
            return ""
        towards = self.blackboard.get(self.blocked_key)
        allowed = self.blackboard.get(self.release_again_key) if self.blackboard.exists(self.release_again_key) else ""
        if towards == keys.NOT_BLOCKED or allowed == keys.ALLOWED:
            return ""
        offset = self._offset()
        at = "" if offset is None else f" at {offset:.2f} mm{self._best_text(offset)}"
        return f"its push towards {towards} is blocked{at}, and it was not released again: {allowed}"

    def _remember(self, offset: float) -> None:
        """Keep the first offset (as placed) and the smallest, for the last word."""
        if self.first_offset_mm is None:
            self.first_offset_mm = offset
        self.best_offset_mm = offset if self.best_offset_mm is None else min(self.best_offset_mm, offset)

    def _best_text(self, offset: float) -> str:
        """``" (best 0.35 mm, placed 1.19 mm)"`` when the loop measured better than where it ends, else ``""``."""
        best, first = self.best_offset_mm, self.first_offset_mm
        if best is None or first is None or best >= offset - 0.005:
            return ""
        return f" (best {best:.2f} mm, placed {first:.2f} mm)"

    def _stalled(self, offset: float, yaw: float | None) -> bool:
        """Count a correction that closed less than ``STALL_FRACTION`` of the best offset and yaw error so far."""
        if not self.stall_after:
            return False
        now = (offset, abs(yaw) if yaw is not None else 0.0)
        if self._best is None:
            self._best = now
            return False
        keep = 1.0 - STALL_FRACTION
        # Only what is still outside its threshold counts: a yaw already within shrinking by a hundredth is no progress.
        offset_outside = not self.tolerance.offset_within(offset, self._margin_mm())
        yaw_outside = yaw is not None and not self.tolerance.yaw_within(yaw)
        improved = (offset_outside and now[0] < self._best[0] * keep) or (yaw_outside and now[1] < self._best[1] * keep)
        self._best = (min(self._best[0], now[0]), min(self._best[1], now[1]))
        self._stalls = 0 if improved else self._stalls + 1
        return self._stalls >= self.stall_after

    def _measured_on_free_edges(self) -> bool:
        """True when the last look measured the part on its free edges only (``keys.FREE_EDGES``)."""
        key = self.measured_on_key
        return key is not None and self.blackboard.exists(key) and self.blackboard.get(key) == keys.FREE_EDGES

    def _margin_mm(self) -> float:
        """The camera's own error (mm) the session wrote, 0 without one."""
        if not self.blackboard.exists(CAMERA_MARGIN_KEY):
            return 0.0
        value = self.blackboard.get(CAMERA_MARGIN_KEY)
        return 0.0 if value is None else self.margins * float(value)

    def _yaw_error(self) -> float | None:
        if self.yaw_key is None or not self.blackboard.exists(self.yaw_key):
            return None
        value = self.blackboard.get(self.yaw_key)
        return None if value is None else float(value)

    def _offset(self) -> float | None:
        if not self.blackboard.exists(self.offset_key):
            return None
        value = self.blackboard.get(self.offset_key)
        return None if value is None else float(value)

    def _offset_text(self) -> str:
        offset = self._offset()
        return "unknown" if offset is None else f"{offset:.2f} mm"

    def _record(self) -> None:
        if self.corrections_key is not None:
            self.blackboard.set(self.corrections_key, self._counted_before + self.attempts, overwrite=True)


def _along(offset_xy_mm: tuple[float, float], towards: str) -> float | None:
    """How far (mm) the part must still go ``towards`` (``"+y"``: the offset's y, target frame); None: a square push."""
    if len(towards) != 2 or towards[0] not in "+-" or towards[1] not in "xy":
        return None
    value = offset_xy_mm[0] if towards[1] == "x" else offset_xy_mm[1]
    return value if towards[0] == "+" else -value


#: The former name of ``RepeatUntilWithin`` (it repeats on success, like py_trees' ``Repeat``).
RetryUntilThreshold = RepeatUntilWithin
