"""A neighbour in the way of the one push that closes a part's offset: named, moved aside, put back.

The layout's plan (``bt_arrange.plan.move_aside``) on the example fresco; the branch it renders in
the part's correction (``bt_arrange.trees.steps``); Push naming the neighbour; PushAside's push.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import py_trees
import pytest
from behaviour_helpers import set_up, write
from py_trees.common import Status

from bt_arrange import treefile
from bt_arrange.behaviours import Context, Push, PushAside, PutBack
from bt_arrange.geometry import PlanarPose, Pose
from bt_arrange.objects import ObjectType
from bt_arrange.plan.layout import Pads
from bt_arrange.plan.move_aside import blocked_by, move_aside
from bt_arrange.shapes import ROBOTIQ_2F85, Prism
from bt_arrange.testing import fake_arm, tick_until_done
from bt_arrange.trees.arrangement import plan_of
from bt_arrange.trees.steps import correction

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import fresco  # noqa: E402

#: An L whose square pushes are named by heading: a fresco piece's are too.
ELL = ObjectType(
    "ell", shape=Prism.from_outline(np.array([[-30, -20], [30, -20], [30, 0], [0, 0], [0, 20], [-30, 20]]) / 1000, 0.02)
)


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    """The example fresco of five pieces, its fracture and scene from seed 0: tile 1 beside tile 2."""
    path = tmp_path_factory.mktemp("fresco") / "fresco.toml"
    path.write_text(fresco.plan_text(0, 5, 2.0))
    compiled = plan_of(treefile.build_root(treefile.load(path)))
    assert compiled is not None
    return compiled


def step_of(plan, obj):
    return next(step for step in plan.steps if step.target.obj == obj)


def test_the_layout_names_the_neighbour_in_a_pushs_way_and_how_it_is_moved_aside(plan) -> None:
    step = step_of(plan, "tile 2")
    assert step.blocked_by["@-28.7"] == "tile 1"
    (aside,) = [a for a in step.move_aside if a.move.towards == "@-28.7"]
    assert (aside.move.neighbour, aside.move.aside, aside.move.back) == ("tile 1", "@114.3", "@-61.3")
    assert 0.03 < aside.move.distance_m < 0.075
    # Once back, the neighbour is corrected among the parts then placed, tile 2 with them.
    assert aside.neighbour.target.obj == "tile 1" and not aside.neighbour.move_aside, "one level only"
    # Every blocked push names what blocks it; only a lone neighbour with a free way is moved.
    pads = Pads.from_settings(plan.settings)
    placed = [s.layout.part for s in plan.steps[:2]]
    assert set(blocked_by(placed[1], [(p.name, p.footprint) for p in placed], pads)) == set(step.blocked_by)
    assert move_aside(placed[1], placed, pads) == tuple(a.move for a in step.move_aside)


def test_a_part_placed_free_has_nothing_to_move_aside(plan) -> None:
    first = plan.steps[0]
    assert first.move_aside == () and not first.blocked_by


def test_the_correction_falls_back_on_moving_the_neighbour_aside_as_steps_of_their_own(plan) -> None:
    tree = correction(step_of(plan, "tile 2"), plan)
    names = [node.name for node in tree.iterate()]
    assert "move tile 1 aside to correct tile 2" in names
    branch = next(n for n in tree.iterate() if n.name == "move tile 1 aside to correct tile 2")
    assert [type(c).__name__ for c in branch.children] == [
        "CheckBlackboardVariableValue",
        "CheckBlackboardVariableValue",
        "PushAside",
        "Inspect",
        "FailureIsSuccess",
        "Sequence",
        "RepeatUntilWithin",
    ]
    assert [c.name for c in branch.children[5].children] == [
        "put tile 1 back",
        "inspect tile 1 put back",
        "correct tile 1 to 0.8 mm put back for tile 2",
    ]
    push_aside = branch.children[2]
    assert isinstance(push_aside, PushAside) and push_aside.for_obj == "tile 2"
    # The push that fails names its neighbour.
    (push,) = [n for n in tree.iterate() if n.name == "push tile 2"]
    assert isinstance(push, Push) and push.blockers["@-28.7"] == "tile 1"
    # With tile 1 aside, that push is free; the others still name what blocks them.
    (aside_push,) = [n for n in tree.iterate() if n.name == "push tile 2 with tile 1 aside"][:1]
    assert isinstance(aside_push, Push) and "@-28.7" in aside_push.towards
    assert "@-28.7" not in aside_push.blockers


@pytest.mark.parametrize(
    ("towards", "by", "runs"),
    [("@-28.7", "tile 1", True), ("@-28.7", "tile 3", False), ("@55.7", "tile 1", False), ("@-28.7", "", False)],
    ids=["blocked by it", "another neighbour", "another push", "nobody named"],
)
def test_the_neighbour_is_moved_only_when_the_key_says_it_blocks_that_push(plan, towards, by, runs) -> None:
    tree = correction(step_of(plan, "tile 2"), plan)
    (branch,) = [
        n for n in tree.iterate() if n.name == "move tile 1 aside to correct tile 2" and "@-28.7" in n.children[0].name
    ]
    py_trees.blackboard.Blackboard.set("/tile 2/blocked_towards", towards)
    py_trees.blackboard.Blackboard.set("/tile 2/blocked_by", by)
    passed = True
    for check in branch.children[:2]:
        check.tick_once()
        passed = passed and check.status == Status.SUCCESS
    assert passed is runs


def test_push_aside_pushes_the_neighbour_by_the_layouts_push_however_far_its_offset(context: Context) -> None:
    pushes = ELL.shape.named_pushes(ROBOTIQ_2F85)
    write({"/blue/pose": Pose.from_planar(0.5, 0.0, 0.0, 0.01), "/blue/target": PlanarPose(0.5, 0.0, 0.0)})
    write({"/blue/offset_xy_mm": (0.0, 0.0)})
    aside = next(iter(pushes))
    node = set_up(PushAside("push blue aside", "blue", aside, 0.02, ELL, for_obj="red"), context)
    run = tick_until_done(node, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback.startswith("pushed blue 20.0 mm aside, squarely onto its edge")
    assert run.feedback.endswith("so that red can be pushed from that side")
    assert fake_arm(context).commands, "it moved"


def test_push_aside_without_that_push_fails_without_moving(context: Context) -> None:
    write({"/blue/pose": Pose.from_planar(0.5, 0.0, 0.0, 0.01), "/blue/target": PlanarPose(0.5, 0.0, 0.0)})
    node = set_up(PushAside("push blue aside", "blue", "@12.3", 0.02, ELL), context)
    run = tick_until_done(node, context)
    assert run.status == Status.FAILURE and "blue has no square push @12.3" in run.feedback
    assert fake_arm(context).commands == []


def test_put_back_pushes_by_the_offset_along_its_push_less_the_reserve_and_across(context: Context) -> None:
    # 20 mm to go along +y (the push @90.0), 2 mm beside it along -x.
    write({"/blue/pose": Pose.from_planar(0.502, -0.02, 0.0, 0.01), "/blue/target": PlanarPose(0.5, 0.0, 0.0)})
    write({"/blue/offset_xy_mm": (-2.0, 20.0)})
    node = set_up(PutBack("put blue back", "blue", "@90.0", ELL), context)
    run = tick_until_done(node, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert run.feedback == "pushed +19.00 mm squarely onto its edge 1 (90.0 deg), +2.00 mm across"


def test_put_back_with_nothing_along_its_push_fails_without_moving(context: Context) -> None:
    write({"/blue/pose": Pose.from_planar(0.5, 0.0, 0.0, 0.01), "/blue/target": PlanarPose(0.5, 0.0, 0.0)})
    write({"/blue/offset_xy_mm": (3.0, 0.5)})
    node = set_up(PutBack("put blue back", "blue", "@90.0", ELL), context)
    run = tick_until_done(node, context)
    assert run.status == Status.FAILURE and "no push back to make" in run.feedback
    assert fake_arm(context).commands == []
