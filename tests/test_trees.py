"""Tree builders: plans checked before anything moves, the shapes of the trees, drawing them without a robot."""

from __future__ import annotations

import math

import py_trees
import pytest
from py_trees.common import Status

from bt_arrange.behaviours import Detect, GraspGuard, Inspect, MoveHome, Pick, Place, Push, Separate, StagedBehaviour
from bt_arrange.decorators import RetryUntilThreshold
from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import ObjectType
from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.shapes import ROBOTIQ_2F85
from bt_arrange.testing import fake_camera, make_context, part
from bt_arrange.trees import (
    Arrangement,
    Target,
    arrangement,
    kinds,
    parts_of,
    plan_steps,
    validate_targets,
)

RED = Target("red", 0.45, 0.10)
GREEN = Target("green", 0.45, -0.10, 0.3)


def outline(node: py_trees.behaviour.Behaviour, depth: int = 0) -> list[str]:
    """The tree as indented ``Type name`` lines, parents before children."""
    lines = [f"{'  ' * depth}{type(node).__name__} {node.name}"]
    for child in node.children:
        lines += outline(child, depth + 1)
    return lines


def find(root: py_trees.behaviour.Behaviour, name: str) -> py_trees.behaviour.Behaviour:
    matches = [node for node in root.iterate() if node.name == name]
    assert len(matches) == 1, f"{len(matches)} nodes named {name!r}"
    return matches[0]


# -- plans ---------------------------------------------------------------------------------------


def test_a_valid_plan_comes_back_as_a_list_in_order() -> None:
    assert validate_targets(t for t in (RED, GREEN)) == [RED, GREEN]


@pytest.mark.parametrize(
    ("targets", "message"),
    [
        ([], r"^no targets: an arrangement needs at least one Target\(colour, x_m, y_m, yaw_rad\)$"),
        ("red", r"^targets must be a list of Target\(colour, x_m, y_m, yaw_rad\), got 'red'$"),
        (None, r"^targets must be a list of Target.*, got None$"),
        ([RED, ("green", 0.45, -0.1)], r"^target 2 is \('green', 0.45, -0.1\), not a Target\(colour, x_m"),
        ([Target("red", math.nan, 0.1)], r"^target 1 \(red\): x_m=nan is not a finite number$"),
        ([Target("red", 0.45, math.inf)], r"^target 1 \(red\): y_m=inf is not a finite number$"),
        ([Target("red", 0.45, 0.1, "0")], r"^target 1 \(red\): yaw_rad='0' is not a finite number$"),
        ([Target("red", True, 0.1)], r"^target 1 \(red\): x_m=True is not a finite number$"),
        (
            [RED, Target("purple", 0.45, -0.1)],
            r"^target 2: unknown colour 'purple'; known colours: red, yellow, green, blue$",
        ),
        (
            [RED, Target("red", 0.55, -0.1)],
            r"^targets 1 and 2 are both named 'red' \(identical parts need a name each, e\.g\. name='red 1'",
        ),
        (
            [RED, Target("green", 1.2, 0.0)],
            r"^target green at x 1200 mm, y 0 mm is out of reach: it lies 1200 mm from the base axis; "
            r"in that direction the arm reaches 110 to 905 mm from its base axis: move it at least 295 mm closer$",
        ),
        (
            [RED, Target("green", 0.45, 0.08)],
            r"^targets red and green overlap: two parts cannot stand there; their centres are 20.0 mm apart and "
            r"must be at least 52.0 mm apart along that line \(their footprints and the 2 mm gap\): "
            r"move them 32.0 mm further apart$",
        ),
        (
            [RED, Target("green", 0.45, 0.049)],
            r"^targets red and green are 1.0 mm apart, under the 2 mm two parts need",
        ),
    ],
    ids=[
        "empty",
        "a string",
        "None",
        "a tuple",
        "nan",
        "inf",
        "text yaw",
        "bool",
        "unknown colour",
        "two for one colour",
        "out of reach",
        "overlapping",
        "too close",
    ],
)
def test_a_bad_plan_is_one_clear_plan_error(targets, message: str) -> None:
    with pytest.raises(PlanError, match=message):
        validate_targets(targets)
    with pytest.raises(PlanError, match=message):
        arrangement(targets)


def test_targets_2_mm_apart_are_accepted() -> None:
    other = Target("green", RED.x_m, RED.y_m - 0.052)
    assert validate_targets([RED, other]) == [RED, other]


def test_the_known_colours_can_be_given() -> None:
    with pytest.raises(PlanError, match=r"^target 2: unknown colour 'green'; known colours: red, blue$"):
        validate_targets([RED, GREEN], colours=["red", "blue"])


def test_two_names_for_one_colour_and_type_are_identical_parts() -> None:
    first, second = Target("red", 0.45, 0.1, name="first"), Target("red", 0.45, -0.1, name="second")
    assert validate_targets([first, second]) == [first, second]
    assert kinds([first, second]) == {"first": (first.planar, second.planar), "second": (first.planar, second.planar)}


def test_one_colour_on_two_types_is_a_plan_error_the_camera_cannot_tell_them_apart() -> None:
    bar = ObjectType("bar", (0.08, 0.04, 0.04))
    first, second = Target("red", 0.45, 0.1, name="first"), Target("red", 0.45, -0.1, name="bar", object_type=bar)
    with pytest.raises(PlanError, match=r"^targets 1 and 2 are both red but of types 'cube' and 'bar'"):
        validate_targets([first, second])


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"correct": "sometimes"}, r"^correct='sometimes': choose one of each, after_all$"),
        ({"threshold_mm": 0}, r"^threshold_mm=0 must be a positive number of millimetres$"),
        ({"threshold_mm": -1.0}, r"^threshold_mm=-1.0 must be a positive number"),
        ({"threshold_mm": math.nan}, r"^threshold_mm=nan must be a positive number"),
        ({"threshold_mm": "1"}, r"^threshold_mm='1' must be a positive number"),
        ({"threshold_mm": True}, r"^threshold_mm=True must be a positive number"),
        ({"max_pushes": -1}, r"^max_pushes=-1 must be a whole number, 0 or more$"),
        ({"max_pushes": 2.5}, r"^max_pushes=2.5 must be a whole number"),
    ],
    ids=["correct mode", "zero", "negative", "nan", "text", "bool", "negative pushes", "fractional pushes"],
)
def test_bad_options_are_one_clear_plan_error(options: dict, message: str) -> None:
    with pytest.raises(PlanError, match=message):
        arrangement([RED], **options)


# -- shapes --------------------------------------------------------------------------------------


def arrange_red(indent: int, threshold: str = "1") -> list[str]:
    pad = "  " * indent
    return [
        f"{pad}Sequence arrange red",
        f"{pad}  SetBlackboardVariable red target",
        f"{pad}  Retry pick and place red",
        f"{pad}    Sequence transfer red",
        *find_red(indent + 3),
        f"{pad}      Pick pick red",
        f"{pad}      GraspGuard while holding red",
        f"{pad}        Place place red",
        f"{pad}  Inspect inspect red after placing",
        *correct_red(indent + 1, threshold),
    ]


def find_red(indent: int, obj: str = "red") -> list[str]:
    """The look before the pick, and the push aside of a touching part when it fails."""
    pad = "  " * indent
    return [
        f"{pad}Selector find {obj}, else separate it from touching parts",
        f"{pad}  Detect detect {obj}",
        f"{pad}  Sequence separate {obj} from touching parts, then look again",
        f"{pad}    CheckBlackboardVariableValue {obj} touches parts of its colour",
        f"{pad}    Separate push a part touching {obj} aside",
        f"{pad}    Detect detect {obj} after separating",
    ]


def correct_red(indent: int, threshold: str = "1") -> list[str]:
    """Algorithm 1's inner loop, and the fallback that places the part again when its pushes stall."""
    pad = "  " * indent
    return [
        f"{pad}Selector correct red, else place it again",
        f"{pad}  RepeatUntilWithin correct red to {threshold} mm",
        f"{pad}    Sequence push and inspect red",
        f"{pad}      Push push red",
        f"{pad}      Inspect inspect red",
        f"{pad}  Sequence place red again when its pushes stall",
        f"{pad}    CheckBlackboardVariableValue red's pushes stalled",
        f"{pad}    Pick pick red to place it again",
        f"{pad}    GraspGuard while holding red to place it again",
        f"{pad}      Place place red again",
        f"{pad}    Inspect inspect red after placing it again",
        f"{pad}    RepeatUntilWithin correct red to {threshold} mm after placing it again",
        f"{pad}      Sequence push and inspect red after placing it again",
        f"{pad}        Push push red after placing it again",
        f"{pad}        Inspect inspect red after pushing it again",
    ]


def test_arrange_one_is_algorithm_1() -> None:
    assert outline(one_part(RED, threshold_mm=0.5)) == arrange_red(0, "0.5")


def test_correct_each_arranges_the_objects_one_after_the_other_then_parks() -> None:
    root = arrangement([RED, GREEN], threshold_mm=1.0, max_pushes=7, correct="each")
    assert isinstance(root, Arrangement)
    assert root.targets == [RED, GREEN] and root.threshold_mm == 1.0
    assert [f"{type(c).__name__} {c.name}" for c in root.children] == [
        "FailureIsSuccess then the next (red)",
        "FailureIsSuccess then the next (green)",
        "MoveHome park the arm",
    ]
    assert outline(root.children[0].decorated) == arrange_red(0)
    assert root.memory, "a sequence with memory: a finished object is not redone"


def test_without_keep_going_a_failed_object_stops_the_arrangement() -> None:
    root = arrangement([RED, GREEN], keep_going=False)
    assert [c.name for c in root.children] == ["arrange red", "arrange green", "park the arm"]


def test_correct_after_all_places_every_object_before_correcting_any() -> None:
    root = arrangement([RED, GREEN], correct="after_all")
    assert outline(root) == [
        "Arrangement arrangement",
        "  Sequence place all",
        "    FailureIsSuccess then the next (red)",
        "      Sequence place red first",
        "        SetBlackboardVariable red target",
        "        Retry pick and place red",
        "          Sequence transfer red",
        *find_red(6),
        "            Pick pick red",
        "            GraspGuard while holding red",
        "              Place place red",
        "        Inspect inspect red after placing",
        "    FailureIsSuccess then the next (green)",
        "      Sequence place green first",
        "        SetBlackboardVariable green target",
        "        Retry pick and place green",
        "          Sequence transfer green",
        *find_red(6, "green"),
        "            Pick pick green",
        "            GraspGuard while holding green",
        "              Place place green",
        "        Inspect inspect green after placing",
        "  Sequence correct all",
        "    FailureIsSuccess then the next (red)",
        "      Sequence correct red after all",
        "        CheckBlackboardVariableExists red was placed",
        "        Inspect inspect red before correcting",
        "        RepeatUntilWithin correct red to 1 mm",
        "          Sequence push and inspect red",
        "            Push push red",
        "            Inspect inspect red",
        "    FailureIsSuccess then the next (green)",
        "      Sequence correct green after all",
        "        CheckBlackboardVariableExists green was placed",
        "        Inspect inspect green before correcting",
        "        RepeatUntilWithin correct green to 1 mm",
        "          Sequence push and inspect green",
        "            Push push green",
        "            Inspect inspect green",
        "  MoveHome park the arm",
    ]


def test_the_options_reach_the_nodes_that_use_them() -> None:
    root = arrangement([RED, Target("blue", 0.5, -0.1, name="cube b")], threshold_mm=0.5, max_pushes=4)
    correct = find(root, "correct cube b to 0.5 mm")
    assert isinstance(correct, RetryUntilThreshold)
    assert (correct.threshold_mm, correct.max_attempts) == (0.5, 4)
    assert (correct.offset_key, correct.corrections_key) == ("/cube b/offset_mm", "/cube b/corrections")
    detect = find(root, "detect cube b")
    assert isinstance(detect, Detect) and (detect.obj, detect.colour) == ("cube b", "blue")
    placed = find(root, "inspect cube b after placing")
    assert isinstance(placed, Inspect) and placed.after_placing
    assert not find(root, "inspect cube b").after_placing


def test_the_target_node_writes_the_target_to_the_blackboard() -> None:
    node = find(one_part(GREEN), "green target")
    node.tick_once()
    assert node.status == Status.SUCCESS
    assert py_trees.blackboard.Blackboard.get("/green/target") == PlanarPose(0.45, -0.10, 0.3)


def test_a_tree_builds_and_renders_without_a_robot() -> None:
    root = arrangement([RED, GREEN, Target("blue", 0.60, 0.0)], correct="after_all")
    text = py_trees.display.unicode_tree(root)
    names = [node.name for node in root.iterate()]
    # 18 nodes per cube, and 5 more for the look that separates touching parts.
    assert len(names) == 2 + 3 * 23 + 2, "root and its two phases, 23 nodes per cube, park the arm"
    assert all(name in text for name in names)
    assert text.splitlines()[0].endswith("arrangement")
    assert all(node.context is None for node in root.iterate() if isinstance(node, StagedBehaviour))


def test_setting_up_a_tree_hands_the_context_to_every_behaviour(context) -> None:
    tree = py_trees.trees.BehaviourTree(arrangement([RED, GREEN]))
    tree.setup(context=context)
    users = [n for n in tree.root.iterate() if isinstance(n, (StagedBehaviour, GraspGuard))]
    assert {type(n) for n in users} == {Detect, Pick, GraspGuard, Place, Inspect, Push, Separate, MoveHome}
    assert all(n.context is context for n in users)


def test_setting_up_a_tree_without_a_context_is_a_clear_error() -> None:
    tree = py_trees.trees.BehaviourTree(arrangement([RED]))
    with pytest.raises(BtArrangeError, match=r"needs setup\(context=Context\(\.\.\.\)\)"):
        tree.setup()


# -- running, on fake devices --------------------------------------------------------------------


def run_tree(root: py_trees.behaviour.Behaviour, context, max_ticks: int = 20000, stop=None) -> Status:
    """Tick like the runner: tree, brake, one control period."""
    for node in root.iterate():
        node.setup(context=context)
    clock = context.robot.clock
    for _ in range(max_ticks):
        root.tick_once()
        context.brake.step()
        clock.advance(context.robot.arm.control_period_s)
        if root.status != Status.RUNNING or (stop is not None and stop()):
            return root.status
    raise AssertionError(f"{root.name} still RUNNING after {max_ticks} ticks")


def test_max_regrasps_allows_that_many_attempts_after_the_first(clock) -> None:
    context = make_context(clock=clock, parts=[])  # red is nowhere: every attempt fails at Detect
    root = arrangement([RED], max_regrasps=1, keep_going=False)
    assert run_tree(root, context) == Status.FAILURE
    assert find(root, "detect red").feedback_message.startswith("red not_found")
    assert len(fake_camera(context).captures) == 2, "one attempt, then one regrasp"


def test_an_object_that_cannot_be_found_does_not_stop_the_others(clock) -> None:
    context = make_context(clock=clock, parts=[])
    root = arrangement([RED, GREEN], max_regrasps=1)
    assert run_tree(root, context) == Status.SUCCESS
    assert find(root, "arrange red").status == Status.FAILURE
    assert find(root, "arrange green").status == Status.FAILURE
    assert find(root, "park the arm").status == Status.SUCCESS
    assert len(fake_camera(context).captures) == 4, "two attempts for each object"


def test_after_all_does_not_correct_an_object_that_was_not_placed(clock) -> None:
    # Red lies 25 cm from its target; the gripper closes on nothing, so every pick fails.
    context = make_context(clock=clock, parts=[part("red", 0.60, -0.12)], object_width_m=None)
    root = arrangement([RED], correct="after_all", max_regrasps=1)
    push = find(root, "push red")
    run_tree(root, context, stop=lambda: push.status != Status.INVALID)
    assert find(root, "place red first").status == Status.FAILURE
    assert push.status == Status.INVALID, f"push red ran: {push.feedback_message}"


def test_each_skips_the_correction_of_an_object_that_was_not_placed(clock) -> None:
    context = make_context(clock=clock, parts=[part("red", 0.60, -0.12)], object_width_m=None)
    root = arrangement([RED], correct="each", max_regrasps=1)
    assert run_tree(root, context) == Status.SUCCESS
    assert find(root, "pick red").feedback_message.startswith("no part between the pads")
    assert find(root, "arrange red").status == Status.FAILURE
    assert find(root, "push red").status == Status.INVALID
    assert isinstance(find(root, "park the arm"), MoveHome)


# -- the layout check on each type's real footprint ------------------

SMALL = ObjectType("small", (0.03, 0.03, 0.03))
BAR = ObjectType("bar", (0.08, 0.04, 0.04))


def test_the_layout_reads_each_type_s_footprint_so_small_parts_2_mm_apart_are_accepted() -> None:
    # 32 mm centre to centre: a 2 mm gap between 30 mm cubes (50 mm cubes there would overlap).
    first = Target("blue", 0.45, 0.0, name="small 1", object_type=SMALL)
    second = Target("blue", 0.45 + 0.032, 0.0, name="small 2", object_type=SMALL)
    assert validate_targets([first, second]) == [first, second]
    assert [p.size_x_m for p in parts_of([first, second])] == [0.03, 0.03]


def test_bars_whose_real_footprints_overlap_are_refused_naming_both() -> None:
    # 60 mm apart along their 80 mm side: they overlap (two 50 mm cubes there would not).
    first = Target("orange", 0.45, 0.0, name="bar 1", object_type=BAR)
    second = Target("orange", 0.51, 0.0, name="bar 2", object_type=BAR)
    with pytest.raises(PlanError, match=r"^targets bar 1 and bar 2 overlap"):
        validate_targets([first, second], colours=[*DEFAULT_COLOUR_TABLE.names, "orange"])


def test_bars_2_mm_apart_end_to_end_are_accepted_without_the_old_90_mm_spacing() -> None:
    # Held across their 40 mm side, whose faces stay free in a row along their 80 mm side.
    bars = [Target("orange", 0.40 + i * 0.082, 0.0, name=f"bar {i}", object_type=BAR) for i in range(3)]
    assert validate_targets(bars, colours=[*DEFAULT_COLOUR_TABLE.names, "orange"]) == bars


def test_a_bar_is_held_and_released_only_across_the_side_the_stroke_spans() -> None:
    bar = Target("orange", 0.45, 0.0, object_type=BAR)
    assert parts_of([bar])[0].grasp_axes == tuple(g.axis for g in BAR.shape.grasps(ROBOTIQ_2F85)) == ("y",)
    assert parts_of([RED])[0].grasp_axes == ("x", "y")
    steps = plan_steps([bar], order=None)
    assert steps[0].release.axis == "y"


@pytest.mark.parametrize("field", ["x_m", "y_m", "z_m"])
def test_a_python_target_in_millimetres_is_refused_in_one_line_that_says_so(field):
    values = {"x_m": 0.5, "y_m": 0.0, "z_m": 0.0, field: 500}
    with pytest.raises(
        PlanError, match=rf"^target 1 \(red\): {field}=500 looks like millimetres: a Target is in metres"
    ):
        arrangement([Target("red", **values)])


def one_part(target, threshold_mm=1.0, yaw_threshold_deg=1.0):  # noqa: ANN001, ANN201
    """Algorithm 1 for one part placed free, as a compiled plan renders it."""
    from bt_arrange.plan import ArrangementPlan, PartStep, Tolerance
    from bt_arrange.trees import render_part

    return render_part(PartStep.free(target), ArrangementPlan.of([target], Tolerance(threshold_mm, yaw_threshold_deg)))


@pytest.mark.parametrize("keep_going", [True, False])
def test_a_part_s_neighbours_are_looked_at_again_whatever_became_of_it_unless_the_plan_stops_there(
    keep_going: bool,
) -> None:
    """Going on past a failed part, its neighbours are rechecked anyway; a plan that stops at a failure stops."""
    from bt_arrange.plan import Target as PlanTarget
    from bt_arrange.plan import Tolerance, compile_plan
    from bt_arrange.trees import render

    targets = [PlanTarget("red", x_m=0.5, y_m=0.0), PlanTarget("blue", x_m=0.5, y_m=0.053)]
    root = render(compile_plan(targets, Tolerance(1.0), keep_going=keep_going))
    wrapped = [node.name for node in root.iterate() if node.name.startswith("then look again at")]
    assert wrapped == (["then look again at blue's neighbours"] if keep_going else [])
