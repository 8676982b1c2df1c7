"""What the layout's search has judged, kept while it searches and between the times a run asks.

``bt_arrange.plan.layout.plan_layout`` tries the same volumes (a staged release's pads, a push's
sweep) under thousands of placed sets; a run asks for the same layout four times. These keep the
verdicts for one search (``judging``: context variables, so nothing outlives it) and the last
layouts (``KeptLayouts``), each the same answer as judging again: the same overlaps, the same
placing orders.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field

from bt_arrange.plan.footprints import Footprint, overlap

#: While ``plan_layout`` searches, every overlap it has judged, by volume and then by the placed
#: footprint (its id, the footprint kept beside the verdict): the search asks the same volume
#: against the same target under thousands of placed sets (a 12-piece fresco: a million tests, of
#: fifty thousand kinds). None outside a search, so nothing outlives it.
_JUDGED_OVERLAPS: ContextVar[dict[tuple[Footprint, float], dict[int, tuple[Footprint, bool]]] | None] = ContextVar(
    "judged_overlaps", default=None
)


@dataclass
class _Targets:
    """While ``plan_layout`` searches: every part's target footprint, and which of them each volume tried meets.

    A volume the search tries (the pads of a staged release, a push's sweep) is the same under
    every placed set; only which parts are placed changes. So it is judged once against every
    target, under a key naming it (part, distance, direction, what), and a placed set then asks
    only whether it holds one of those names: the same verdict as testing the placed footprints.
    """

    footprints: dict[str, Footprint]
    met: dict[tuple[object, ...], frozenset[str]] = field(default_factory=dict)

    def placed_names(self, placed: Sequence[tuple[str, Footprint]]) -> frozenset[str] | None:
        """The names of ``placed`` when each is its target's footprint (else None: judge them one by one)."""
        if all(self.footprints.get(name) is footprint for name, footprint in placed):
            return frozenset(name for name, _ in placed)
        return None

    def meeting(
        self, key: tuple[object, ...], volumes: Callable[[], Sequence[Footprint]], clearance_m: float
    ) -> frozenset[str]:
        """The targets any of the volumes ``key`` names meets (with ``clearance_m``), judged the first time asked."""
        found = self.met.get(key)
        if found is None:
            built = volumes()
            found = self.met[key] = frozenset(
                name for name, footprint in self.footprints.items() if blockers(built, [(name, footprint)], clearance_m)
            )
        return found


_TARGETS: ContextVar[_Targets | None] = ContextVar("layout_targets", default=None)


def blocked(
    key: tuple[object, ...],
    volumes: Callable[[], Sequence[Footprint]],
    placed: Sequence[tuple[str, Footprint]],
    clearance_m: float,
) -> bool:
    """True when a placed part meets one of the volumes (``bool(blockers(volumes(), placed, clearance_m))``)."""
    targets = _TARGETS.get()
    names = targets.placed_names(placed) if targets is not None else None
    if targets is None or names is None:
        return bool(blockers(volumes(), placed, clearance_m))
    return not targets.meeting(key, volumes, clearance_m).isdisjoint(names)


def blockers(volumes: Iterable[Footprint], placed: Sequence[tuple[str, Footprint]], clearance_m: float) -> list[str]:
    """Names of the placed parts that any of ``volumes`` meets."""
    judged = _JUDGED_OVERLAPS.get()
    names = []
    for volume in volumes:
        verdicts = judged.setdefault((volume, clearance_m), {}) if judged is not None else None
        for name, footprint in placed:
            if name in names:
                continue
            if verdicts is None:
                meets = overlap(volume, footprint, clearance_m)
            else:
                kept = verdicts.get(id(footprint))
                if kept is None or kept[0] is not footprint:
                    kept = verdicts[id(footprint)] = (footprint, overlap(volume, footprint, clearance_m))
                meets = kept[1]
            if meets:
                names.append(name)
    return names


@contextmanager
def judging(footprints: dict[str, Footprint]) -> Iterator[None]:
    """While a search runs: its overlaps kept, and every volume judged once against these target footprints."""
    overlaps = _JUDGED_OVERLAPS.set({})
    targets = _TARGETS.set(_Targets(footprints))
    try:
        yield
    finally:
        _TARGETS.reset(targets)
        _JUDGED_OVERLAPS.reset(overlaps)


def current_targets() -> _Targets | None:
    """The running search's targets (None outside a search)."""
    return _TARGETS.get()


class KeptLayouts:
    """The last ``size`` answers by key, the oldest dropped first; safe to share between threads."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._kept: OrderedDict[tuple[object, ...], object] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: tuple[object, ...]) -> object | None:
        """The answer kept under ``key`` (now the newest), or None."""
        with self._lock:
            kept = self._kept.get(key)
            if kept is not None:
                self._kept.move_to_end(key)
            return kept

    def put(self, key: tuple[object, ...], value: object) -> None:
        """Keep ``value`` under ``key``, dropping the oldest beyond ``size``."""
        with self._lock:
            self._kept[key] = value
            while len(self._kept) > self.size:
                self._kept.popitem(last=False)

    def clear(self) -> None:
        """Forget every answer."""
        with self._lock:
            self._kept.clear()

    def __len__(self) -> int:
        return len(self._kept)


__all__ = ["KeptLayouts", "blocked", "blockers", "current_targets", "judging"]
