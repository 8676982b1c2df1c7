"""Outlines within limits: a point limit refused before any other work, and a self-crossing check in O(n log n).

The sweep line (``polygon.first_crossing``) is checked against testing every pair of edges on random
polygons (simple, self-crossing, touching, on a grid where points meet edges), and its work is
counted, not timed: at most 3n segment tests however large the outline (testing every pair took
n^2 / 2). The time of the whole check is measured in ``benchmarks/outline_limits.py``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_arrange import cli
from bt_arrange.filelimits import MAX_OBJECT_TYPES, MAX_OUTLINE_POINTS, MAX_PLAN_OUTLINE_POINTS
from bt_arrange.shapes import polygon
from bt_arrange.shapes.gripper import ROBOTIQ_2F85
from bt_arrange.shapes.polygon import first_crossing, outline_problem, segments_cross


def _every_pair(points: np.ndarray) -> bool:
    """The check as it was (n^2 / 2 tests): True when two edges that are not neighbours meet."""
    count = len(points)
    for i in range(count):
        for j in range(i + 1, count):
            if j == i + 1 or (i == 0 and j == count - 1):
                continue
            if segments_cross(points[i], points[(i + 1) % count], points[j], points[(j + 1) % count]):
                return True
    return False


def _no_short_edges(points: np.ndarray) -> bool:
    return bool(np.all(np.hypot(*(np.roll(points, -1, axis=0) - points).T) >= 1e-6))


def _star(count: int, seed: int, wobble: float = 0.4) -> np.ndarray:
    """A simple polygon: points at increasing angles, random radii."""
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0, 2 * math.pi, count))
    radii = 0.05 * (1 - wobble + wobble * rng.uniform(size=count))
    return np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])


@pytest.mark.parametrize("seed", range(60))
def test_the_sweep_finds_a_crossing_exactly_when_some_pair_of_edges_meets(seed: int) -> None:
    rng = np.random.default_rng(seed)
    count = int(rng.integers(3, 24))
    candidates = [
        rng.uniform(-0.05, 0.05, size=(count, 2)),  # random points: mostly crossing
        _star(count, seed),  # simple
        # On a coarse grid: points on other edges, collinear edges, vertical edges, touching corners.
        rng.integers(0, 4, size=(count, 2)).astype(float) * 0.01,
    ]
    # A simple polygon with one point moved onto (or across) another edge.
    moved = _star(max(count, 6), seed + 1000)
    moved[2] = (moved[4] + moved[5]) / 2 if seed % 2 else moved[4] * 1.5 + moved[5] * -0.5
    candidates.append(moved)
    for points in candidates:
        if not _no_short_edges(points) or len(points) < 3:
            continue
        expected = _every_pair(points)
        found = first_crossing(points)
        if found is None:
            assert not expected, (seed, points.tolist())
            continue
        i, j = found
        n = len(points)
        meet = segments_cross(points[i], points[(i + 1) % n], points[j], points[(j + 1) % n])
        assert meet and (expected or abs(i - j) in (1, n - 1)), (seed, found, points.tolist())


def test_a_point_written_twice_and_an_edge_folding_back_are_found() -> None:
    touching = np.array([[0, 0], [0.04, 0], [0.02, 0.02], [0.04, 0.04], [0, 0.04], [0.02, 0.02]])
    assert first_crossing(touching) is not None
    assert "crosses itself" in outline_problem(touching.tolist())
    folding = np.array([[0, 0], [0.04, 0], [0.04, 0.04], [0.04, 0.02], [0, 0.04]])  # back down its own edge
    assert first_crossing(folding) is not None


@pytest.mark.parametrize("count", [16, 256, 4096])
def test_the_sweep_makes_at_most_three_segment_tests_an_edge(count: int, monkeypatch: pytest.MonkeyPatch) -> None:
    tests = 0

    def counted(*args: object) -> bool:
        nonlocal tests
        tests += 1
        return segments_cross(*args)

    monkeypatch.setattr(polygon, "segments_cross", counted)
    gear = _star(count, count, wobble=0.2)
    assert first_crossing(gear) is None
    assert tests <= 3 * count, f"{tests} tests for {count} edges"
    middle = count // 2
    gear[[middle, middle + count // 4]] = gear[[middle + count // 4, middle]]  # two points swapped: edges cross
    tests = 0
    assert first_crossing(gear) is not None and tests <= 3 * count


def test_an_outline_over_the_limit_is_refused_before_any_other_work(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_work(*args: object) -> None:
        raise AssertionError("the outline was examined before its size was checked")

    monkeypatch.setattr(polygon, "first_crossing", no_work)
    monkeypatch.setattr(polygon.np, "asarray", no_work)
    points = _star(MAX_OUTLINE_POINTS + 1, 1).tolist()
    assert outline_problem(points) == (
        f"the outline has {MAX_OUTLINE_POINTS + 1} points, over the limit of {MAX_OUTLINE_POINTS} "
        "(bt_arrange.filelimits.MAX_OUTLINE_POINTS)"
    )


def _plan(tmp_path: Path, types: dict[str, list[list[float]]]) -> Path:
    lines = ["threshold_mm = 1.0"]
    for name, outline in types.items():
        lines += [f"[objects.{name}]", f"outline_mm = {outline}", "height_mm = 20"]
    first = next(iter(types))
    lines += ["[[targets]]", f'object = "{first}"', 'colour = "red"', "x_mm = 500", "y_mm = 0"]
    path = tmp_path / "plan.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_plan_with_an_outline_over_the_limit_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outline = (_star(MAX_OUTLINE_POINTS + 1, 2) * 1000).round(3).tolist()
    path = _plan(tmp_path, {"blob": outline})
    assert cli.main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[objects.blob]" in err, err
    assert f"the outline has {MAX_OUTLINE_POINTS + 1} points, over the limit of {MAX_OUTLINE_POINTS}" in err


def _round_part_mm(count: int, seed: int = 0) -> list[list[float]]:
    """A round part of ``count`` points the type check accepts: two flats joined by rippled arcs (millimetres)."""
    from benchmark_modules import load_benchmark

    bench = load_benchmark("outline_limits.py")
    return (bench.round_part(count, seed) * 1000).round(4).tolist()


def test_a_part_of_as_many_points_as_the_limit_loads(tmp_path: Path) -> None:
    from bt_arrange import plans

    assert MAX_OUTLINE_POINTS == 256
    path = _plan(tmp_path, {"round": _round_part_mm(MAX_OUTLINE_POINTS)})
    plan = plans.load(path)
    shape = plan.object_types["round"].shape
    assert len(shape.outline) == MAX_OUTLINE_POINTS and shape.grasps(ROBOTIQ_2F85)


def test_one_point_over_the_limit_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _plan(tmp_path, {"round": _round_part_mm(MAX_OUTLINE_POINTS + 1)})
    assert cli.main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[objects.round]" in err, err
    assert f"the outline has {MAX_OUTLINE_POINTS + 1} points, over the limit of {MAX_OUTLINE_POINTS}" in err


def test_outlines_over_the_plan_s_limit_in_all_are_refused_before_any_is_judged(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from bt_arrange import plans

    def no_work(*args: object, **kwargs: object) -> None:
        raise AssertionError("a type was judged before the outline points in all were counted")

    monkeypatch.setattr(plans.Prism, "from_outline", no_work)
    parts = MAX_PLAN_OUTLINE_POINTS // MAX_OUTLINE_POINTS + 1
    path = _plan(tmp_path, {f"round{k}": _round_part_mm(MAX_OUTLINE_POINTS, k) for k in range(parts)})
    assert cli.main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert (
        f"[objects]: {parts * MAX_OUTLINE_POINTS:,} outline points in all, over the limit of {MAX_PLAN_OUTLINE_POINTS}"
        in err
    )


def test_a_plan_with_more_types_than_the_limit_is_refused_before_any_is_judged(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from bt_arrange import plans

    def no_work(*args: object, **kwargs: object) -> None:
        raise AssertionError("a type was judged before the number of types was checked")

    monkeypatch.setattr(plans.Prism, "from_outline", no_work)
    triangle = [[0, 0], [60, 0], [15, 45]]
    path = _plan(tmp_path, {f"t{k}": triangle for k in range(MAX_OBJECT_TYPES + 1)})
    assert cli.main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"[objects]: {MAX_OBJECT_TYPES + 1} types, over the limit of {MAX_OBJECT_TYPES}" in err


def _exact_loop_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    from bt_arrange.shapes import antipodal

    monkeypatch.setattr(antipodal, "_clearly_refused", lambda points, closing, along, centres, *rest: np.zeros(
        len(centres), dtype=bool))  # fmt: skip


@pytest.mark.parametrize("seed", range(8))
def test_the_rough_judgement_of_every_place_finds_the_grasps_the_exact_loop_finds(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    from bt_arrange.shapes import Prism, antipodal
    from bt_arrange.shapes.gripper import ROBOTIQ_2F85

    rng = np.random.default_rng(seed)
    shapes = [
        [[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]],  # the shipped ell
        _star(int(rng.integers(5, 20)), seed, wobble=0.5),
        (np.round(_star(8, seed, wobble=0.3), 3)).tolist(),  # on a millimetre grid: exact ties
    ]
    for points in shapes:
        outline = np.array(Prism.from_outline(np.asarray(points).tolist(), 0.02).outline)
        rough = antipodal._search(outline, 0.02, ROBOTIQ_2F85)
        with monkeypatch.context() as patched:
            _exact_loop_alone(patched)
            exact = antipodal._search(outline, 0.02, ROBOTIQ_2F85)
        assert rough == exact, points


def _xml_of_picks(types: dict[str, list[list[float]]]) -> str:
    """An XML tree of one Pick a type, each type's outline written in its object_type port."""
    picks = "".join(
        f'<Pick name="pick {name}" obj="{name}" object_type="{name}=outline_mm '
        + " ".join(f"{x:g}:{y:g}" for x, y in outline)
        + ' height_mm 20"/>\n'
        for name, outline in types.items()
    )
    return (
        '<root BTCPP_format="4" main_tree_to_execute="M"><BehaviorTree ID="M">\n'
        f'<Sequence name="s">\n{picks}</Sequence></BehaviorTree></root>\n'
    )


@pytest.mark.parametrize("over", ["types", "points"])
def test_an_xml_tree_over_a_plan_s_type_limits_is_refused_before_any_type_is_judged(
    over: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from bt_arrange import ports

    def no_work(*args: object, **kwargs: object) -> None:
        raise AssertionError("a type was judged before the types in all were counted")

    if over == "types":
        triangle = [[0, 0], [60, 0], [15, 45]]
        types = {f"t{k}": [[x + k * 0.01, y] for x, y in triangle] for k in range(MAX_OBJECT_TYPES + 1)}
        expected = f"{MAX_OBJECT_TYPES + 1} object types, over the limit of {MAX_OBJECT_TYPES}"
    else:
        parts = MAX_PLAN_OUTLINE_POINTS // MAX_OUTLINE_POINTS + 1
        types = {f"round{k}": _round_part_mm(MAX_OUTLINE_POINTS, k) for k in range(parts)}
        expected = f"{parts * MAX_OUTLINE_POINTS:,} outline points in all, over the limit of {MAX_PLAN_OUTLINE_POINTS}"
    path = tmp_path / "tree.xml"
    path.write_text(_xml_of_picks(types))
    monkeypatch.setattr(ports.Prism, "from_outline", no_work)
    assert cli.main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and expected in err and str(path) in err, err


def test_an_xml_tree_s_types_repeated_in_many_ports_count_once(tmp_path: Path) -> None:
    from bt_arrange import xmltree

    outline = _round_part_mm(MAX_OUTLINE_POINTS)
    text = _xml_of_picks({"round": outline})
    many = text.replace(
        "</Sequence>", "".join(text.split("\n")[2] + "\n" for _ in range(MAX_OBJECT_TYPES)) + "</Sequence>"
    )
    assert many.count("outline_mm") == MAX_OBJECT_TYPES + 1
    root = xmltree.from_xml(many)
    assert len(list(root.children)) == MAX_OBJECT_TYPES + 1


def test_a_bad_outline_in_an_xml_port_is_quoted_short(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    crossing = [[0, 0], [60, 0], [0, 60], [60, 60]] + [[60 + k, 60 + 10 * k] for k in range(1, 40)]
    path = tmp_path / "tree.xml"
    path.write_text(_xml_of_picks({"bowtie": crossing}))
    assert cli.main(["show", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "object_type='bowtie=outline_mm 0:0 60:0" in err and "...'" in err, err
    assert len(err) < 500, err
