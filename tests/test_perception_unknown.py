"""Outlines measured without a model, on synthetic frames: a fracture's pieces scattered at random.

Each piece's vertices are matched to the nearest true vertex (``bt_arrange.perception.synthetic``
renders the exact polygons); the bad cases are two pieces touching, two under a millimetre apart,
and a piece cut by the image border. A painted slab's pieces (a colour each, no colour range holds
them all) are measured in a foreground mask.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from bt_arrange.perception import MeasuredOutline, PartDetector, measure_unknown_outlines
from bt_arrange.perception import measure_unknown_outlines_in_mask as in_mask
from bt_arrange.perception.colours import PAINT_RGB
from bt_arrange.perception.synthetic import SIM_TABLE_RGB, SyntheticPrism, render_frame
from bt_arrange.shapes.base import footprint_m
from bt_arrange.shapes.fracture import Piece, fracture, polygon_gap_m

TOP_Z_M = 0.02
#: A 6-piece fracture (the issue's 300 x 200 mm slab gives pieces too wide for the 2F-85 to grasp).
SLAB_M = (0.20, 0.15, TOP_Z_M)
PLACES = [(0.38, -0.25), (0.38, 0.0), (0.38, 0.25), (0.62, -0.25), (0.62, 0.0), (0.62, 0.25)]


@functools.cache
def pieces(seed: int = 1) -> tuple[Piece, ...]:
    return tuple(fracture(SLAB_M, 6, 0.002, seed))


def scattered(seed: int, rgb: list | None = None) -> tuple[list[SyntheticPrism], list[np.ndarray]]:
    """The fracture's pieces on a grid of places, each moved a little and turned at random: parts and true outlines."""
    rng = np.random.default_rng(seed)
    parts, truth = [], []
    for k, (piece, (x, y)) in enumerate(zip(pieces(), PLACES, strict=True)):
        x, y, yaw = x + rng.uniform(-0.01, 0.01), y + rng.uniform(-0.02, 0.02), rng.uniform(-math.pi, math.pi)
        colour = None if rgb is None else tuple(rgb[k])
        parts.append(SyntheticPrism("red", x, y, yaw, piece.prism, rgb=colour))
        truth.append(footprint_m(piece.prism, x, y, yaw))
    return parts, truth


def vertex_errors_mm(outline: MeasuredOutline, truth: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Each measured vertex's distance to the nearest vertex of the nearest true outline, and that outline."""
    true = min(truth, key=lambda t: float(np.hypot(*(t.mean(axis=0) - outline.centroid_m))))
    distances = np.hypot(*(outline.outline_m[:, None, :] - true[None, :, :]).transpose(2, 0, 1))
    return 1000 * distances.min(axis=1), true


def check_all(outlines: list[MeasuredOutline], truth: list[np.ndarray], limit_mm: float) -> float:
    assert len(outlines) == len(truth)
    worst = 0.0
    for outline in outlines:
        errors, true = vertex_errors_mm(outline, truth)
        assert len(outline.outline_m) == len(true)  # every true side is 10 mm or more
        assert np.all(errors < limit_mm), errors
        # Counter-clockwise, and each vertex matched to a different true one.
        x, y = outline.outline_m.T
        assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
        nearest = np.argmin(np.hypot(*(outline.outline_m[:, None, :] - true[None]).transpose(2, 0, 1)), axis=1)
        assert len(set(nearest.tolist())) == len(true)
        assert outline.plane_z_m == TOP_Z_M
        assert len(outline.edge_colours) == len(true)
        worst = max(worst, float(errors.max()))
    return worst


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_vertex_of_every_piece_is_within_a_tenth_of_a_millimetre(seed: int) -> None:
    parts, truth = scattered(seed)
    outlines, problems = measure_unknown_outlines(PartDetector(), render_frame(parts), "red", TOP_Z_M)
    assert problems == []
    check_all(outlines, truth, 0.1)
    for outline in outlines:
        assert outline.residual_px < 0.1
        # The face's colour just inside each edge, sampled along all of it (a pixel apart).
        for k, colours in enumerate(outline.edge_colours):
            vertices = outline.outline_m
            length_mm = 1000 * float(np.hypot(*(vertices[(k + 1) % len(vertices)] - vertices[k])))
            assert colours.shape[1] == 3 and len(colours) > length_mm / 0.5 - 10
            assert np.allclose(colours.mean(axis=0), PAINT_RGB["red"], atol=0.02)


def test_a_blurred_noisy_camera_keeps_every_vertex_within_a_tenth() -> None:
    parts, truth = scattered(3)
    frame = render_frame(parts, blur_sigma_px=0.8, noise_sigma=2.0, seed=3)
    outlines, problems = measure_unknown_outlines(PartDetector(), frame, "red", TOP_Z_M)
    assert problems == []
    check_all(outlines, truth, 0.1)


def test_an_aliased_camera_leaves_a_side_of_simple_slope_to_a_fraction_of_a_pixel() -> None:
    # Pixel centres only, as pybullet's TinyRenderer: a side's staircase allows a range of lines, and a side
    # whose slope is a simple fraction p / q (a row or column, a diagonal) repeats it every q pixels, so it is
    # known to about 1 / (2 q) px however long (0.23 mm for a row). Most vertices stay within a tenth.
    parts, truth = scattered(4)
    outlines, problems = measure_unknown_outlines(PartDetector(), render_frame(parts, supersample=1), "red", TOP_Z_M)
    assert problems == []
    worst = check_all(outlines, truth, 0.25)
    errors = np.concatenate([vertex_errors_mm(o, truth)[0] for o in outlines])
    assert float(np.mean(errors)) < 0.05 and worst < 0.25


def moved_to_gap(first: SyntheticPrism, second: SyntheticPrism, gap_m: float) -> SyntheticPrism:
    """``first`` moved along the line to ``second``'s centre until their outlines are ``gap_m`` apart."""
    direction = np.array([second.x_m - first.x_m, second.y_m - first.y_m])
    direction /= np.linalg.norm(direction)
    fixed = footprint_m(second.prism, second.x_m, second.y_m, second.yaw_rad)
    start = polygon_gap_m(footprint_m(first.prism, first.x_m, first.y_m, first.yaw_rad), fixed)
    low, high = 0.0, start + 0.01
    for _ in range(40):
        middle = (low + high) / 2
        x, y = first.x_m + direction[0] * middle, first.y_m + direction[1] * middle
        gap = polygon_gap_m(footprint_m(first.prism, x, y, first.yaw_rad), fixed)
        low, high = (middle, high) if gap > gap_m else (low, middle)
    x, y = first.x_m + direction[0] * low, first.y_m + direction[1] * low
    return SyntheticPrism(first.colour, x, y, first.yaw_rad, first.prism)


def test_two_touching_pieces_are_reported_in_one_line() -> None:
    parts, truth = scattered(5)
    parts[1] = moved_to_gap(parts[1], parts[0], 0.0)
    outlines, problems = measure_unknown_outlines(PartDetector(), render_frame(parts), "red", TOP_Z_M)
    touching = [p for p in problems if "touch" in p]
    assert len(touching) == 1 and len(problems) == 1, problems
    assert "cannot tell their outlines apart" in touching[0]
    # The other four are measured as ever.
    assert len(outlines) == 4
    check_all(outlines, [t for k, t in enumerate(truth) if k > 1], 0.1)


@pytest.mark.parametrize("gap_mm", [0.6, 0.9])
def test_two_pieces_under_a_millimetre_apart_are_told_apart_or_reported(gap_mm: float) -> None:
    parts, truth = scattered(6)
    parts[4] = moved_to_gap(parts[4], parts[3], gap_mm / 1000)
    truth[4] = footprint_m(parts[4].prism, parts[4].x_m, parts[4].y_m, parts[4].yaw_rad)
    outlines, problems = measure_unknown_outlines(PartDetector(), render_frame(parts), "red", TOP_Z_M)
    if problems:
        assert len(problems) == 1 and "under 1 mm apart" in problems[0], problems
        assert len(outlines) == 4
    else:
        check_all(outlines, truth, 0.1)


def test_a_piece_cut_by_the_image_border_is_reported() -> None:
    parts, truth = scattered(7)
    cut = parts[2]
    parts[2] = SyntheticPrism(cut.colour, cut.x_m, 0.47, cut.yaw_rad, cut.prism)  # the image spans y -0.45..0.45 m
    outlines, problems = measure_unknown_outlines(PartDetector(), render_frame(parts), "red", TOP_Z_M)
    assert len(problems) == 1 and "cut by the image border" in problems[0], problems
    assert "red blob at (" in problems[0]
    check_all(outlines, [t for k, t in enumerate(truth) if k != 2], 0.1)


def test_painted_pieces_are_measured_in_a_foreground_mask() -> None:
    # A colour each: no one colour range holds them, the mask of "not the table" does.
    paints = [(0.8, 0.3, 0.2), (0.2, 0.6, 0.3), (0.2, 0.3, 0.8), (0.9, 0.8, 0.2), (0.7, 0.2, 0.7), (0.9, 0.5, 0.1)]
    parts, truth = scattered(8, paints)
    frame = render_frame(parts)
    table = np.asarray(SIM_TABLE_RGB) * 255
    mask = np.where(np.abs(frame.rgb.astype(float) - table).max(axis=2) > 40, 255, 0).astype(np.uint8)
    outlines, problems = in_mask(PartDetector(), frame, mask, TOP_Z_M)
    assert problems == []
    check_all(outlines, truth, 0.1)
    for outline in outlines:
        _, true = vertex_errors_mm(outline, truth)
        k = next(i for i, t in enumerate(truth) if t is true)
        assert np.allclose(outline.edge_colours[0].mean(axis=0), paints[k], atol=0.02)
