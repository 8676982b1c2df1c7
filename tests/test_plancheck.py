"""The plan check that knows the cell: camera view, objects in the scene, the threshold floor.

Each mistake a user can make is one ``PlanError`` naming it; generated plans (hypothesis) are either
accepted and valid or refused with a ``BtArrangeError`` that names the problem, never another exception.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.colours import PAINT_RGB
from bt_arrange.plan import ArrangementPlan, Tolerance
from bt_arrange.plan.check import CameraView, check_plan, check_scene
from bt_arrange.plan.layout import Part, gap_m
from bt_arrange.settings import ManipulationSettings
from bt_arrange.trees import Target, arrangement, check_threshold, correction
from bt_arrange_sim.config import CameraConfig
from bt_arrange_sim.scenes import PartStart, scatter

VIEW: CameraView = CameraConfig().view()
RED = Target("red", 0.50, 0.0)
BLUE = Target("blue", 0.50, 0.15)
RED_START = PartStart("red", 0.40, -0.25, 0.3)
BLUE_START = PartStart("blue", 0.62, -0.25, 0.0)


def test_a_good_plan_in_the_cell_is_accepted() -> None:
    plan = check_plan([RED, BLUE], threshold_mm=1.0, starts=[RED_START, BLUE_START], view=VIEW)
    assert plan == [RED, BLUE]


def test_a_target_without_its_cube_in_the_scene_is_refused() -> None:  # item 1
    with pytest.raises(PlanError, match=r"^target blue: no part 'blue' in the scene \(the scene has red\)$"):
        check_plan([RED, BLUE], starts=[RED_START], view=VIEW)


def test_a_target_named_otherwise_than_its_cube_is_refused() -> None:
    with pytest.raises(PlanError, match="no part 'cube a' in the scene"):
        check_plan([Target("red", 0.5, 0.0, name="cube a")], starts=[RED_START], view=VIEW)


def test_a_target_whose_cube_has_another_colour_is_refused() -> None:
    with pytest.raises(PlanError, match="target a is red but the scene's part a is blue"):
        check_plan([Target("red", 0.5, 0.0, name="a")], starts=[PartStart("blue", 0.4, -0.25, 0.0, name="a")])


@pytest.mark.parametrize(("x_m", "y_m"), [(0.30, 0.45), (-0.40, 0.0), (0.5, -0.47), (0.23, 0.0)])
def test_a_reachable_target_the_camera_cannot_see_is_refused(x_m: float, y_m: float) -> None:  # item 2
    target = Target("red", x_m, y_m)
    with pytest.raises(
        PlanError, match=r"outside the camera's view \(at the height of its top face it sees about x 221 to 779 mm"
    ):
        check_plan([target], view=VIEW)


def test_a_start_the_camera_cannot_see_is_refused() -> None:
    with pytest.raises(PlanError, match=r"^part red starts at x 300 mm, y 450 mm, outside the camera's view"):
        check_scene([PartStart("red", 0.30, 0.45, 0.0)], view=VIEW)


def test_the_view_margin_counts_the_cube_s_turn() -> None:
    # Near the long edge of the image a square cube fits, the same cube turned 45 degrees does not.
    x_m = 0.5
    y_m = next(y / 1000 for y in range(400, 480) if not VIEW.sees_face(x_m, y / 1000, 0.0, 0.05))
    inside = y_m - 0.003
    assert VIEW.sees_face(x_m, inside, 0.0, 0.05)
    assert not VIEW.sees_face(x_m, inside, math.pi / 4, 0.05)


def test_every_scattered_start_passes_the_check_at_its_own_yaw() -> None:
    for seed in range(40):
        check_scene(scatter(list(PAINT_RGB), seed), view=VIEW)


@pytest.mark.parametrize("threshold_mm", [0.01, 0.05, 0.065])
def test_a_threshold_below_what_a_push_corrects_is_refused_naming_the_floor(threshold_mm: float) -> None:  # item 3
    floor = ManipulationSettings().finest_threshold_mm
    assert floor == pytest.approx(math.sqrt(2) * 0.05)
    message = rf"threshold {threshold_mm:g} mm is below 0\.07 mm, the smallest offset a push can correct"
    for build in (
        lambda: arrangement([RED], threshold_mm=threshold_mm),
        lambda: correction(RED, ArrangementPlan.of([RED], Tolerance(threshold_mm))),
        lambda: check_threshold(threshold_mm),
        lambda: check_plan([RED], threshold_mm=threshold_mm),
    ):
        with pytest.raises(PlanError, match=message):
            build()
    check_threshold(floor)  # the floor itself is allowed


@pytest.mark.parametrize(
    ("threshold_mm", "min_push_mm"), [(1.0, 0.2), (0.3, 0.2), (0.25, 0.25 / math.sqrt(2)), (0.08, 0.08 / math.sqrt(2))]
)
def test_a_fine_threshold_lowers_the_shortest_push_to_fit(threshold_mm: float, min_push_mm: float) -> None:
    root = arrangement([RED], threshold_mm=threshold_mm)
    assert root.settings.min_push_m * 1000 == pytest.approx(min_push_mm)
    assert root.settings.min_threshold_mm <= max(threshold_mm, ManipulationSettings().finest_threshold_mm) + 1e-9


@pytest.mark.parametrize(("threshold_mm", "gap_mm"), [(3.0, 2.0), (1.0, 2.0), (0.6, 1.2), (0.25, 0.5), (0.1, 0.5)])
def test_the_least_gap_between_targets_is_twice_the_threshold(threshold_mm: float, gap_mm: float) -> None:
    root = arrangement([RED], threshold_mm=threshold_mm)
    assert root.settings.min_target_gap_m * 1000 == pytest.approx(gap_mm)
    assert ManipulationSettings().gap_for_threshold_m(threshold_mm) * 1000 == pytest.approx(gap_mm)


@pytest.mark.parametrize(
    ("starts", "message"),
    [
        ([RED_START, PartStart("purple", 0.6, 0.2, 0.0)], r"^part 2 of the scene: unknown colour 'purple'"),
        ([RED_START, PartStart("red", 0.6, 0.2, 0.0)], r"^parts 1 and 2 of the scene are both named 'red'$"),
        (
            [RED_START, PartStart("red", 0.6, 0.2, 0.0, "red bar", ObjectType("bar", (0.08, 0.04, 0.04)))],
            r"^parts 1 and 2 of the scene are both red but of types 'cube' and 'bar': the camera tells parts apart",
        ),
        ([PartStart("red", math.nan, 0.0, 0.0)], r"^part 1 of the scene \(red\): x_m=nan is not a finite number$"),
        ([("red", 0.5, 0.0, 0.0)], r"^part 1 of the scene is \('red', 0\.5, 0\.0, 0\.0\), not a part start"),
        ([RED_START, PartStart("blue", 0.42, -0.25, 0.0)], r"^parts red and blue start 20 mm apart: closer than"),
        ("red", r"^the scene must be a list of part starts"),
    ],
)
def test_a_bad_scene_is_one_plan_error(starts: object, message: str) -> None:
    with pytest.raises(PlanError, match=message):
        check_scene(starts, view=VIEW)  # type: ignore[arg-type]


def test_identical_parts_may_share_a_colour_in_the_scene() -> None:
    twins = [RED_START, PartStart("red", 0.6, 0.2, 0.0, name="other red")]
    assert check_scene(twins, view=VIEW) == twins


def test_a_cube_resting_on_another_object_s_target_is_refused() -> None:
    with pytest.raises(
        PlanError,
        match=r"^part blue starts 25 mm from red's target: the pads picking it or working at that target need 69 mm",
    ):
        check_plan([RED], starts=[RED_START, PartStart("blue", 0.55, 0.0, 0.0)], view=VIEW)


# -- property-based: every generated plan is accepted and valid, or refused with a named problem ---

colours = st.sampled_from([*PAINT_RGB, "purple", ""])
numbers = st.one_of(
    st.floats(min_value=-1.0, max_value=1.5, allow_nan=False),
    st.sampled_from([math.nan, math.inf, -math.inf, 0, True]),
    st.text(max_size=3),
    st.none(),
)
targets = st.builds(Target, colours, numbers, numbers, numbers, st.one_of(st.none(), st.sampled_from(["a", "b"])))
starts = st.builds(PartStart, colours, numbers, numbers, numbers, st.one_of(st.none(), st.sampled_from(["a", "b"])))
thresholds = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 3), st.none(), st.text(max_size=2)
)
FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def assert_valid(plan: list[Target], scene: list[PartStart] | None) -> None:
    """What an accepted plan guarantees, checked independently of how check_plan found it."""
    for target in plan:
        assert all(math.isfinite(v) for v in (target.x_m, target.y_m, target.yaw_rad))
        assert VIEW.sees_face(target.x_m, target.y_m, target.yaw_rad, 0.05)
        if scene is not None:
            assert any((s.name or s.colour) == target.obj and s.colour == target.colour for s in scene)
    for i, first in enumerate(plan):
        for second in plan[i + 1 :]:
            # Parts never overlap or come closer than the 2 mm the layout demands.
            a = Part("a", first.x_m, first.y_m, first.yaw_rad, CUBE.shape).footprint
            b = Part("b", second.x_m, second.y_m, second.yaw_rad, CUBE.shape).footprint
            assert gap_m(a, b) >= 0.002 - 1e-9


@FAST
@given(
    plan=st.lists(targets, max_size=4), scene=st.one_of(st.none(), st.lists(starts, max_size=4)), threshold=thresholds
)
def test_a_generated_plan_is_valid_or_one_named_bt_arrange_error(plan, scene, threshold) -> None:
    try:
        checked = check_plan(plan, threshold_mm=threshold, starts=scene, view=VIEW)
    except BtArrangeError as error:
        message = str(error)
        assert message and "\n" not in message
        assert any(word in message for word in ("target", "cube", "threshold", "scene")), message
        return
    assert_valid(checked, scene)


@FAST
@given(
    x_m=st.floats(0.2, 0.8),
    y_m=st.floats(-0.5, 0.5),
    yaw_rad=st.floats(-math.pi, math.pi),
    threshold=st.floats(0.28, 50),
)
def test_a_generated_single_cube_plan_builds_a_tree_or_is_refused(x_m, y_m, yaw_rad, threshold) -> None:
    target = Target("red", x_m, y_m, yaw_rad)
    try:
        check_plan([target], threshold_mm=threshold, view=VIEW)
        arrangement([target], threshold_mm=threshold)
    except PlanError as error:
        assert "target red" in str(error) or "threshold" in str(error)
        return
    assert VIEW.sees_face(x_m, y_m, yaw_rad, 0.05)
