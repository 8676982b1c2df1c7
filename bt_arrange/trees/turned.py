"""A part placed free and turned: how far turned it is placed again, not pressed square, and the loop doing it.

``turned_limit_deg`` gives a plan's limit; ``regrasp_while_turned`` picks the part up at its camera
pose and places it again while it lies turned that far or more (``trees.steps`` re-exports both).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import py_trees

from bt_arrange.behaviours import GraspGuard, Inspect, Pick, Place, keys
from bt_arrange.checks import positive_number, whole_number
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.geometry import PlanarPose
from bt_arrange.plan.targets import Target

#: A part placed turned this far or more from its target's yaw (deg, measured by the camera) is picked
#: up again rather than pushed. A push that moves a part a long way also squares it (a triangle 2.45 deg
#: off, pushed 3.7 mm, ended 0.01 deg off), but near its place a squaring press turns it back 0.16 to
#: 0.33 deg (the runs, seeds 0 and 4: an ell 2.07 deg off took two presses, stalled and was
#: placed again, 0.01 deg off); a push with its look costs 2.4 s of world time, a placing again about 3 s.
#: Over ``irregular_parts`` at seeds 0 to 9, 1.5 deg took 3.87 s a part against 3.97 s at 12 deg.
REGRASP_YAW_DEG = 1.5
#: A part corrected by position alone (no yaw threshold) is picked up again only when turned this far
#: or more (deg): its square pushes meet a turned edge on a corner.
REGRASP_ANY_YAW_DEG = 12.0
#: The most times a turned part is picked up again before its correction is left to fail.
MAX_TURNED_REGRASPS = 2
#: From this yaw threshold (deg) up, a free part is placed again once turned past the threshold less
#: ``CAMERA_YAW_MARGIN_DEG``, not pressed square: a kite held across an edge and a corner, set down
#: 1.0 to 1.5 deg off, took two presses (5.9 s of world time) and still ended 1.04 deg off by truth;
#: placed again it ended 0.02 deg off.
COARSE_YAW_THRESHOLD_DEG = 1.0
#: The camera's yaw error (deg) a free part's measured yaw must leave under a coarse yaw threshold after
#: placing: the outlines' 95th percentile in the cell (0.074 deg, ``benchmarks/outlines.py --cell``),
#: rounded up. A hexagon measured 0.969 deg off lay 1.002 deg off by truth.
CAMERA_YAW_MARGIN_DEG = 0.08


def turned_limit_deg(yaw_threshold_deg: float | None, rechecked: bool = False) -> float:
    """How far turned (deg) a part placed free is picked up again.

    A yaw threshold of ``COARSE_YAW_THRESHOLD_DEG`` or more: the threshold less the camera's yaw
    margin (0.92 deg for 1 deg), so a part left in place is within by more than the camera's error.
    A finer one: ``REGRASP_YAW_DEG`` (placed again a part seldom lands within it; presses square it).
    With no yaw threshold (position only), and for a part a later neighbour is placed beside
    (``rechecked``: a fresco's first piece), ``REGRASP_ANY_YAW_DEG``: in the real-cell model a
    fresco's first piece placed again at 1.5 deg took ten pushes and a later piece ended 1.5 mm off
    (seed 2), where it ended within.
    """
    if yaw_threshold_deg is None or rechecked:
        return REGRASP_ANY_YAW_DEG
    if yaw_threshold_deg >= COARSE_YAW_THRESHOLD_DEG:
        return round(yaw_threshold_deg - CAMERA_YAW_MARGIN_DEG, 6)
    return REGRASP_YAW_DEG


def regrasp_while_turned(
    target: Target,
    *,
    yaw_limit_deg: float = REGRASP_YAW_DEG,
    max_regrasps: int = MAX_TURNED_REGRASPS,
    kind_targets: Sequence[PlanarPose] = (),
) -> py_trees.behaviour.Behaviour:
    """Pick the part up again at its camera pose and place it again while it lies turned ``yaw_limit_deg`` or more.

    After the inspect after placing (which writes ``/<obj>/pose`` and ``/<obj>/yaw_error_deg``)::

        RepeatUntilWithin "regrasp <obj> while turned 1.5 deg or more"   (yaw only: any offset will do)
        └── Sequence "pick and place <obj> again"
            ├── Pick "pick <obj> again"                  at /<obj>/pose, from the camera
            ├── GraspGuard "while holding <obj> again"
            │   └── Place "place <obj> again"
            └── Inspect "inspect <obj> after placing again"

    A part turned less than the limit passes at once, in the same tick: nothing moves. An irregular
    part held across an edge and a corner can turn in the pads (the close, the carry, the release)
    by a degree or two, at worst tens; a squaring press near its place corrects a few tenths.
    ``max_regrasps`` attempts, then it fails with the yaw. ``turned_limit_deg`` gives a plan's limit.
    """
    positive_number("yaw_limit_deg", yaw_limit_deg, "deg")
    whole_number("max_regrasps", max_regrasps)
    obj = target.obj
    kind = target.object_type
    again = py_trees.composites.Sequence(
        name=f"pick and place {obj} again",
        memory=True,
        children=[
            Pick(f"pick {obj} again", obj, kind, z_m=target.z_m),
            GraspGuard(f"while holding {obj} again", Place(f"place {obj} again", obj, kind, z_m=target.z_m)),
            Inspect(
                f"inspect {obj} after placing again",
                obj,
                target.colour,
                True,
                object_type=kind,
                kind_targets=kind_targets,
                z_m=target.z_m,
            ),
        ],
    )
    return RepeatUntilWithin(
        name=f"regrasp {obj} while turned {yaw_limit_deg:g} deg or more",
        child=again,
        offset_key=keys.key(obj, keys.OFFSET_MM),
        threshold_mm=math.inf,  # the offset is the pushes' business: only the yaw decides
        max_attempts=max_regrasps,
        obj=obj,
        yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
        yaw_threshold_deg=yaw_limit_deg,
    )
