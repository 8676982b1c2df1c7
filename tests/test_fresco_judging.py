"""A fresco plan judged in bounded work, to the same pieces and layouts as one step at a time.

The fracture's cells are clipped for every cell at once, the layout's search keeps what it
judged: each is checked here against the plain way of doing it (the reference below, the loop
over one bisector at a time it replaced), bit for bit, and by the work it saves (counted, not
timed: ``benchmarks/fresco_limits.py`` times it).
"""

from __future__ import annotations

import numpy as np
import pytest

from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectType
from bt_arrange.plan import layout, layout_judged
from bt_arrange.plan.layout import Pads, plan_layout
from bt_arrange.plan.targets import parts_of
from bt_arrange.shapes import Prism
from bt_arrange.shapes import fracture as fracture_module
from bt_arrange.shapes.fracture import _cells, _dedupe, fracture
from bt_arrange.trees import Target


def _reference_cells(sites: np.ndarray, half_l: float, half_w: float, shrink_m: float) -> list[np.ndarray]:
    """The cells as clipped before they were bounded: one cell, one bisector, one corner at a time, in numpy."""

    def clip(polygon: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
        out = []
        sides = [float(normal @ point) - offset for point in polygon]
        for k in range(len(polygon)):
            a, b = polygon[k], polygon[(k + 1) % len(polygon)]
            da, db = sides[k], sides[(k + 1) % len(polygon)]
            if da <= 0:
                out.append(a)
            if da * db < 0:
                out.append(a + (b - a) * (da / (da - db)))
        return np.array(out) if out else np.zeros((0, 2))

    slab = np.array([[-half_l, -half_w], [half_l, -half_w], [half_l, half_w], [-half_l, half_w]])
    cells = []
    for i, site in enumerate(sites):
        cell = slab
        for j, other in enumerate(sites):
            if i == j or len(cell) == 0:
                continue
            normal = other - site
            normal = normal / np.linalg.norm(normal)
            cell = clip(cell, normal, float(normal @ (site + other)) / 2 - shrink_m)
        cells.append(_dedupe(cell))
    return cells


@pytest.mark.parametrize("count", [3, 5, 8, 12])
def test_cells_clipped_at_once_are_the_cells_clipped_one_bisector_at_a_time_to_the_bit(count: int) -> None:
    rng = np.random.default_rng(count)
    for _ in range(40):
        sites = rng.uniform([-0.08, -0.06], [0.08, 0.06], size=(count, 2))
        for shrink_m in (0.0, 0.001, 0.00025):
            fast = _cells(sites, 0.08, 0.06, shrink_m)
            plain = _reference_cells(sites, 0.08, 0.06, shrink_m)
            assert [cell.tobytes() for cell in fast] == [cell.tobytes() for cell in plain]


def test_a_long_slab_is_refused_at_the_half_turn_without_a_grasp_search(monkeypatch: pytest.MonkeyPatch) -> None:
    """A 300 x 40 mm slab's pieces are near-rectangles, each the same under a half turn: no draw passes."""
    searches = []
    grasps = Prism.grasps
    monkeypatch.setattr(Prism, "grasps", lambda self, *a, **k: searches.append(1) or grasps(self, *a, **k))
    with pytest.raises(PlanError, match="no fracture of a 300 x 40 mm slab into 3 pieces"):
        fracture((0.3, 0.04, 0.02), 3, 0.002, 0)
    assert searches == []  # before the screen: 1,200 grasp searches, four fifths of the refusal's time
    # The screen refuses only what the whole yaw cue refuses: the example fresco's pieces are the same.
    assert fracture_module.yaw_cue_m(fracture((0.16, 0.12, 0.02), 6, 0.002, 3)[0].prism) >= 0.002


def kind(piece) -> ObjectType:  # noqa: ANN001 - a fracture's Piece
    return ObjectType(f"tile {piece.index}", shape=piece.prism)


def _fresco_parts(pieces: int, seed: int) -> list:
    broken = fracture((0.16, 0.12, 0.02), pieces, 0.002, seed, (0.5, 0.0, 0.0))
    targets = [
        Target(
            "ochre",
            p.x_m,
            p.y_m,
            p.yaw_rad,
            name=f"tile {p.index}",
            object_type=ObjectType(f"tile {p.index}", shape=p.prism),
        )
        for p in broken
    ]
    return parts_of(targets)


def test_the_search_keeping_its_verdicts_finds_the_steps_the_plain_search_finds() -> None:
    parts = _fresco_parts(6, 3)
    layout._LAYOUTS.clear()
    kept = plan_layout(parts, Pads())
    plain = layout._plan_layout(parts, Pads(), None)  # no verdicts kept: every overlap judged again
    assert repr(kept) == repr(plain)


def test_a_layout_asked_again_is_not_searched_again_and_a_moved_part_is(monkeypatch: pytest.MonkeyPatch) -> None:
    searched = []
    search = layout._plan_layout
    monkeypatch.setattr(layout, "_plan_layout", lambda *a: searched.append(1) or search(*a))
    layout._LAYOUTS.clear()
    parts = _fresco_parts(4, 1)
    first = plan_layout(parts, Pads())
    again = plan_layout(list(parts), Pads())
    assert searched == [1] and repr(again) == repr(first) and again is not first
    moved = [parts[0].__class__(p.name, p.x_m + 0.3, p.y_m, p.yaw_rad, p.shape, p.gripper) for p in parts]
    plan_layout(moved, Pads())
    assert searched == [1, 1]
    assert len(layout._LAYOUTS) <= layout.KEPT_LAYOUTS


def test_a_fresco_no_order_builds_is_refused_judging_each_overlap_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """160 x 120 mm in 12 pieces, seed 1: tile 11 never has room, found after thousands of placed sets."""
    judged = []
    overlap = layout_judged.overlap
    monkeypatch.setattr(layout_judged, "overlap", lambda *a: judged.append(1) or overlap(*a))
    layout._LAYOUTS.clear()
    parts = _fresco_parts(12, 1)
    with pytest.raises(PlanError, match="tile 11 has no room for the pads"):
        plan_layout(parts, Pads())
    assert len(judged) < 20_000  # judged again under every placed set, as before: 542,003
