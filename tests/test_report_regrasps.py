"""A regrasp in the report ("Reports"): the first placing's figures kept, the regrasps counted.

A part picked up again after it was placed (turned too far, its pushes stalled, a push needing a
blocked side) used to overwrite the "after placing" figures with those of its placing again, and
the report did not say it happened. Here a fake world whose pushes move nothing makes the
correction stall, so its fallback picks the part up and places it again (``trees.steps.correction``).
"""

from __future__ import annotations

import json

import py_trees
from fakeworld import FakeWorld, camera_view

from bt_arrange.behaviours import Detect, Inspect, Pick, Place
from bt_arrange.objects import ObjectStart
from bt_arrange.report import Placement, PlacementLog
from bt_arrange.session import Session
from bt_arrange.trees import Arrangement, Target, arrangement, set_target, transfer

RED = Target("red", 0.50, 0.05)
RED_START = ObjectStart("red", 0.42, -0.22, 0.1)


class StuckWorld(FakeWorld):
    """A fake world whose pads push nothing: every correction stalls."""

    def _push(self) -> None:
        return None


def _stalled_run(**options: object):  # noqa: ANN202
    world = StuckWorld(release_errors_m={"red": (0.004, 0.0)}, truth=True)
    with Session(arrangement([RED]), [RED_START], lambda: world, view=camera_view(), **options) as run:
        return run.run()


def test_a_part_placed_again_keeps_its_first_placing_figures_and_counts_the_regrasp() -> None:
    report = _stalled_run()
    (red,) = report.objects
    assert red.regrasps_after_placing == 1
    # The first placing landed 4 mm off; its figures are kept, not those of the placing again.
    assert red.placed_offset_mm is not None and 3.5 < red.placed_offset_mm < 4.5
    assert red.placed_offset_truth_mm is not None and 3.5 < red.placed_offset_truth_mm < 4.5
    assert red.placed_again_offset_mm is not None and red.placed_again_offset_mm < 1.0
    assert red.placed_again_offset_truth_mm is not None and red.placed_again_offset_truth_mm < 1.0
    assert red.status == "within"
    objects = report.to_dict()["objects"]
    assert objects[0]["regrasps_after_placing"] == 1
    assert objects[0]["placed_offset_mm"] == red.placed_offset_mm


def test_a_second_look_after_placing_does_not_overwrite_the_first_placing_figures() -> None:
    # As a turned part's regrasp does (trees.steps.regrasp_while_turned): pick, place, inspect after placing again.
    again = py_trees.composites.Sequence(
        "pick and place red again",
        memory=True,
        children=[
            Pick("pick red again", "red"),
            Place("place red again", "red"),
            Inspect("inspect red after placing again", "red", after_placing=True),
        ],
    )
    children = [set_target(RED), transfer(RED), Inspect("inspect red after placing", "red", after_placing=True), again]
    root = Arrangement("regrasped", children, [RED], 1.0)
    world = FakeWorld(release_errors_m={"red": (0.004, 0.0)}, truth=True)
    with Session(root, [RED_START], lambda: world, view=camera_view()) as run:
        (red,) = run.run().objects
    assert red.regrasps_after_placing == 1
    assert red.placed_offset_mm is not None and 3.5 < red.placed_offset_mm < 4.5, "the first placing's, kept"
    assert red.placed_offset_truth_mm is not None and 3.5 < red.placed_offset_truth_mm < 4.5
    assert red.placed_again_offset_mm is not None and red.placed_again_offset_mm < 1.0


def test_a_recorded_regrasp_keeps_the_first_after_placing_image(tmp_path) -> None:
    _stalled_run(record_dir=tmp_path)
    assert (tmp_path / "after_placing_red.png").exists()
    assert (tmp_path / "after_placing_red_again_1.png").exists()
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["objects"][0]["regrasps_after_placing"] == 1


def test_a_part_never_picked_again_has_no_regrasp_and_no_placing_again() -> None:
    world = FakeWorld(release_errors_m={"red": (0.003, 0.0)}, truth=True)
    with Session(arrangement([RED]), [RED_START], lambda: world, view=camera_view()) as run:
        (red,) = run.run().objects
    assert red.pushes >= 1 and red.regrasps_after_placing == 0
    assert red.placed_again_offset_mm is None and red.placed_again_offset_truth_mm is None


def test_the_placement_log_counts_picks_after_the_first_placing_only() -> None:
    log = PlacementLog()
    figures = iter([Placement(4.0, 1.0, 4.1), Placement(0.3, 0.1, 0.2), Placement(0.2, 0.0, 0.1)])
    log.pick_started("red")  # the first pick: before any placing
    assert log.inspected("red", True, lambda first: next(figures)) == "after_placing_red"
    assert log.inspected("red", False, lambda first: next(figures)) is None  # a look after a push
    log.pick_started("red")
    assert log.inspected("red", True, lambda first: next(figures)) == "after_placing_red_again_1"
    assert log.regrasps == {"red": 1}
    assert log.first["red"].offset_mm == 4.0 and log.again["red"].offset_mm == 0.3


def test_the_report_counts_set_downs_and_placings_again() -> None:
    report = _stalled_run()
    (red,) = report.objects
    assert red.placed_again == 1 and red.set_downs == 0  # the stalled correction's fallback placed it again
    # A part set down where it was picked, looked at and picked again centred (as among neighbours).
    children = [
        set_target(RED),
        Detect("detect red", "red"),
        Pick("pick red", "red"),
        Place("set red down to look again", "red", where="pick"),
        Detect("detect red again", "red"),
        Pick("pick red centred", "red"),
        Place("place red", "red"),
        Inspect("inspect red after placing", "red", after_placing=True),
    ]
    root = Arrangement("set down", children, [RED], 1.0)
    world = FakeWorld(truth=True)
    with Session(root, [RED_START], lambda: world, view=camera_view()) as run:
        report = run.run()
    (red,) = report.objects
    assert (red.set_downs, red.placed_again) == (1, 0)
    assert report.to_dict()["objects"][0]["set_downs"] == 1
    assert red.held_look == "set down"  # no look in the fingers in this tree: the set-down says so


def test_the_report_says_how_a_part_among_neighbours_was_known_in_the_pads() -> None:
    # LookAtHeld writes /<obj>/held_look; here a hand-set value stands for it.
    children = [
        set_target(RED),
        Detect("detect red", "red"),
        Pick("pick red", "red"),
        py_trees.behaviours.SetBlackboardVariable(
            name="red looked at in the fingers",
            variable_name="/red/held_look",
            variable_value="held look",
            overwrite=True,
        ),
        Place("place red", "red"),
        Inspect("inspect red after placing", "red", after_placing=True),
    ]
    root = Arrangement("held look", children, [RED], 1.0)
    world = FakeWorld(truth=True)
    with Session(root, [RED_START], lambda: world, view=camera_view()) as run:
        report = run.run()
    (red,) = report.objects
    assert red.held_look == "held look"
    assert report.to_dict()["objects"][0]["held_look"] == "held look"
    with Session(arrangement([RED]), [RED_START], lambda: FakeWorld(truth=True), view=camera_view()) as run:
        (free,) = run.run().objects
    assert free.held_look == ""  # placed free: no look in the fingers, no set-down
