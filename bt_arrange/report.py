"""A run's report: how each object ended (``ObjectOutcome``) and the run as a whole (``SessionReport``).

Offsets in millimetres, yaw errors in degrees; ``*_truth_*`` is the world's ground truth, for
evaluation only, None when the world has none (the report is then camera only).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

from py_trees.common import Status

from bt_arrange.runner import Transition

#: World time the scene settles for before the tree starts (parts dropped onto the table come to rest), seconds.


@dataclass
class ObjectOutcome:
    """How one object ended. Offsets in millimetres; ``*_truth_*`` is the world's ground truth (None without)."""

    name: str
    target: tuple[float, float, float]
    placed_offset_mm: float | None
    final_offset_mm: float | None
    final_offset_truth_mm: float | None
    placed_offset_truth_mm: float | None
    pushes: int
    status: str
    reason: str = ""
    #: Measured minus target yaw, folded to the part's symmetry (degrees): camera, then ground truth.
    placed_yaw_error_deg: float | None = None
    final_yaw_error_deg: float | None = None
    final_yaw_error_truth_deg: float | None = None
    #: The part's type and its size (mm), for the report.
    object_type: str = "cube"
    size_mm: tuple[float, float, float] = (50.0, 50.0, 50.0)
    #: The most later steps (a neighbour's release and pushes) moved it between two looks at it:
    #: by the camera (``Recheck``), and by ground truth at the same moments; None when never looked at again.
    moved_by_later_mm: float | None = None
    moved_by_later_truth_mm: float | None = None
    #: Times the part was picked up again after it was placed (``PlacementLog``): turned too far, its
    #: pushes stalled, or a push needed a blocked side. The ``placed_*`` figures stay the first placing's.
    regrasps_after_placing: int = 0
    #: The figures of the last placing again, at the first look after it (camera, ground truth; degrees
    #: for the yaw); None when the part was never picked up again.
    placed_again_offset_mm: float | None = None
    placed_again_offset_truth_mm: float | None = None
    placed_again_yaw_error_deg: float | None = None
    #: A puzzle's piece: where it belongs by the simulator's break, (x mm, y mm, yaw deg),
    #: evaluation only; its ``*_truth_*`` offsets are measured from there. Absent from the JSON otherwise.
    truth_home_mm: tuple[float, float, float] | None = None
    #: Times the part was set down where it was picked, to be looked at and picked again centred.
    set_downs: int = 0
    #: Times touching parts of its colour were pushed apart before its pick (``Separate``: it started
    #: touching another part).
    separations: int = 0
    #: Times the part was placed at its target again after its first placing (a regrasp's placing).
    placed_again: int = 0
    #: Among neighbours, how its place in the pads was known before its (last) placing: ``"held look"``
    #: (measured in the fingers, ``LookAtHeld``) or ``"set down"`` (set down and picked again centred,
    #: also a box among neighbours, which is never looked at in the fingers); empty for a part placed free.
    held_look: str = ""
    #: The neighbours pushed aside (``PushAside``) so that a blocked push of this part could be made, in order.
    moved_aside: list[str] = field(default_factory=list)

    def verdict(self) -> str:
        """The part, how far off and why, when it is not within: ``red outside at 1.23 mm (the reason)``."""
        offset = "" if self.final_offset_mm is None else f" at {self.final_offset_mm:.2f} mm"
        reason = f" ({self.reason})" if self.reason else ""
        return f"{self.name} {self.status}{offset}{reason}"


@dataclass
class SessionReport:
    """A run's outcome: per object, and for the whole tree."""

    objects: list[ObjectOutcome]
    tree_status: str
    threshold_mm: float | None
    sim_seconds: float
    wall_seconds: float
    timed_out: bool
    transitions: list[Transition] = field(default_factory=list, repr=False)
    yaw_threshold_deg: float | None = None
    #: False when the world had no ground truth: the ``*_truth_*`` figures are None, the report camera only.
    ground_truth: bool = True
    #: The camera's own error (mm) a measured offset had to leave under the threshold to count as
    #: within, and where the figure comes from (``bt_arrange.uncertainty``).
    camera_margin_mm: float = 0.0
    camera_margin_source: str = ""
    #: The errors injected into the run (``run --inject``): one JSON-able record per error and part,
    #: ``{"error", "part", "injector", <its magnitude>, "fired", <what it did>}``; None when none were asked for.
    injected: list[dict] | None = None
    #: The one-line reason of a safety stop that ended the run (``bt_arrange.motion.safety``), or "" when none did.
    safety_stop: str = ""
    #: A dry run's summary (``run --dry-run``): the motions it planned and what it could not plan; None in a run.
    dry_run: dict | None = None

    def verdict(self) -> str:
        """How many parts are within and, for each that is not, its offset and why (never the tree's status).

        ``4 of 4 objects within 1 mm and 1 deg``; ``2 of 3 objects within 1 mm; not within: blue outside
        at 1.23 mm (offset still 1.23 mm after 10 correction(s))``. A tree without parts: its status.
        """
        missed = self.not_within()
        return self.within_text() + (f"; not within: {missed}" if missed else "")

    def within_text(self) -> str:
        """``3 of 4 objects within 1 mm and 1 deg`` (``; stopped at the time limit`` when it stopped there)."""
        stopped = "stopped at the time limit" if self.timed_out else ""
        if self.safety_stop:
            stopped = f"safety stop: {self.safety_stop}"
        if not self.objects:
            return stopped or f"tree {self.tree_status}"
        within = sum(o.status == "within" for o in self.objects)
        yaw_text = f" and {self.yaw_threshold_deg:g} deg" if self.yaw_threshold_deg is not None else ""
        threshold = f"{self.threshold_mm:g} mm" if self.threshold_mm is not None else "the threshold"
        return f"{within} of {len(self.objects)} objects within {threshold}{yaw_text}" + (
            f"; {stopped}" if stopped else ""
        )

    def not_within(self) -> str:
        """Each part not within, with its offset and why, ``; ``-separated (empty when all are within)."""
        return "; ".join(o.verdict() for o in self.objects if o.status != "within")

    @property
    def all_within_threshold(self) -> bool:
        """True when every object ended within the threshold, as measured by the camera."""
        if not self.objects:
            return self.tree_status == Status.SUCCESS.value
        return all(o.status == "within" for o in self.objects)

    def to_dict(self) -> dict:
        """The ``--json`` form (``"ground_truth": false`` only when camera only, ``"injected"`` only with errors)."""
        data = {
            # target is [x_m, y_m, yaw_rad]; target_mm and target_yaw_deg repeat it in a plan's units (mm, degrees),
            # as the table shows it.
            "objects": [
                {
                    **{k: v for k, v in asdict(o).items() if k != "truth_home_mm" or v is not None},
                    "target_mm": [round(o.target[0] * 1000, 3), round(o.target[1] * 1000, 3)],
                    "target_yaw_deg": round(math.degrees(o.target[2]), 3),
                }
                for o in self.objects
            ],
            "objects_within": sum(o.status == "within" for o in self.objects),
            "threshold_mm": self.threshold_mm,
            "yaw_threshold_deg": self.yaw_threshold_deg,
            "camera_margin_mm": round(self.camera_margin_mm, 4),
            "tree_status": self.tree_status,
            "timed_out": self.timed_out,
            "sim_seconds": round(self.sim_seconds, 3),
            "wall_seconds": round(self.wall_seconds, 3),
        }
        if not self.ground_truth:
            data["ground_truth"] = False
        if self.injected is not None:
            data["injected"] = self.injected
        if self.safety_stop:
            data["safety_stop"] = self.safety_stop
        if self.dry_run is not None:
            data["dry_run"] = self.dry_run
        return data


@dataclass(frozen=True)
class Placement:
    """A look at a part just placed: the camera's offset (mm) and yaw error (deg), the ground truth's offset (mm)."""

    offset_mm: float | None
    yaw_error_deg: float | None
    offset_truth_mm: float | None


class PlacementLog:
    """Each part's placings as the tree runs: the first one's figures, the regrasps, the last placing again.

    The first placing is measured by the first Inspect after placing of the part to succeed; a Pick
    of the part started after it is a regrasp (a turned part picked up again, a stalled correction's
    fallback, a release on a free side); the first Inspect of the part to succeed after a regrasp
    measures its placing again. A later Inspect after placing with no regrasp before it (a tree that
    places a part twice its own way) counts as a placing again too. An Inspect that merely looks
    again (after a push) measures nothing here.
    """

    def __init__(self) -> None:
        self.first: dict[str, Placement] = {}
        self.again: dict[str, Placement] = {}
        self.regrasps: dict[str, int] = {}
        self._awaiting: set[str] = set()

    def pick_started(self, obj: str | None) -> None:
        """A Pick of ``obj`` started: after the part's first placing, a regrasp."""
        if obj is not None and obj in self.first:
            self.regrasps[obj] = self.regrasps.get(obj, 0) + 1
            self._awaiting.add(obj)

    def inspected(self, obj: str, after_placing: bool, measure: Callable[[bool], Placement]) -> str | None:
        """An Inspect of ``obj`` succeeded; ``measure(first)`` reads the figures. The recorded image's stem, or None."""
        if after_placing and obj not in self.first:
            self.first[obj] = measure(True)
            return f"after_placing_{obj}"
        if obj in self._awaiting or after_placing:
            self._awaiting.discard(obj)
            self.again[obj] = measure(False)
            return f"after_placing_{obj}_again_{self.regrasps.get(obj, 0)}"
        return None


# ----------------------------------------------------------------------------------------------
# The session
# ----------------------------------------------------------------------------------------------
