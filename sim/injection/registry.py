"""Every injector by its spec name, specs like ``pick_translation:0.025``, and attaching several to a run."""

from __future__ import annotations

import zlib
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from bt_arrange.checks import whole_number
from bt_arrange.errors import OutOfRangeError, PlanError
from bt_arrange_sim.injection.framework import Injector
from bt_arrange_sim.injection.perception import PerceptionOffset
from bt_arrange_sim.injection.picking import PickRotation, PickTranslation, PickTranslationXY, SurfaceShift
from bt_arrange_sim.injection.placement import ReleaseHeight, ReleaseStick, ReleaseTilt
from bt_arrange_sim.injection.transport import TransportSlip

if TYPE_CHECKING:
    from bt_arrange_sim.injection.framework import InjectableRun


#: Every injector by its spec name.
INJECTORS: dict[str, type[Injector]] = {
    cls.name: cls
    for cls in (
        PerceptionOffset,
        PickTranslation,
        PickTranslationXY,
        PickRotation,
        SurfaceShift,
        TransportSlip,
        ReleaseStick,
        ReleaseHeight,
        ReleaseTilt,
    )
}


def make_injector(spec: str) -> Injector:
    """An injector from a spec ``name[:value[,value...]]``, values in the order of its parameters.

    Metres, seconds, and degrees for angles: ``"pick_translation:0.025"``, ``"pick_rotation:40"``,
    ``"transport_slip:0.3,0.005"``, ``"release_tilt"`` (defaults). A ``PlanError`` names a malformed
    spec or an unknown injector; an ``OutOfRangeError`` a value outside the injector's range.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise PlanError(f"injector spec {spec!r} is empty; use name[:value], names: {', '.join(INJECTORS)}")
    name, _, rest = spec.strip().partition(":")
    cls = INJECTORS.get(name.strip())
    if cls is None:
        raise PlanError(f"injector spec {spec!r}: unknown injector {name.strip()!r}; known: {', '.join(INJECTORS)}")
    usage = f"{cls.name}[:{','.join(p.name for p in cls.PARAMETERS)}]"
    texts = [t.strip() for t in rest.split(",")] if rest.strip() else []
    if len(texts) > len(cls.PARAMETERS):
        raise PlanError(f"injector spec {spec!r}: too many values, expected {usage}")
    values: dict[str, float] = {}
    for parameter, text in zip(cls.PARAMETERS, texts, strict=False):
        try:
            values[parameter.name] = float(text)
        except ValueError:
            raise PlanError(
                f"injector spec {spec!r}: {parameter.name}={text!r} is not a number, expected {usage}"
            ) from None
    try:
        return cls(**values)
    except OutOfRangeError as error:
        raise OutOfRangeError(f"injector spec {spec!r}: {error}") from error


def make_injectors(specs: Iterable[str]) -> list[Injector]:
    """One injector per spec (see ``make_injector``)."""
    return [make_injector(spec) for spec in specs]


def child_generator(seed: int, name: str, index: int = 0) -> np.random.Generator:
    """The generator ``attach_all`` gives the ``index``-th injector called ``name`` for ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(zlib.crc32(name.encode()), index)))


def attach_all(run: InjectableRun, obj: str, injectors: Sequence[Injector], seed: int) -> None:
    """Attach several injectors to one run for the cube ``obj``, each with its own generator from ``seed``.

    The generator depends on the seed and the injector's name (and its rank among injectors of
    that name), so adding another injector does not change the others' draws. Hooks run in the
    order given: of two picking errors, the later one is drawn to fit with the earlier.
    """
    whole_number("injection seed", seed, style="unit")
    seen: dict[str, int] = {}
    for injector in injectors:
        index = seen.get(injector.name, 0)
        seen[injector.name] = index + 1
        injector.attach(run, obj, child_generator(int(seed), injector.name, index))
