"""Every file in trees/ runs headless and ends with every cube within the threshold by ground truth."""

import math
from pathlib import Path

import numpy as np
import pytest

from bt_arrange import treefile
from bt_arrange.behaviours import holding, stages
from bt_arrange_sim.pybullet.objects import apply_contact
from bt_arrange_sim.pybullet.runs import SimulatedRun

TREES = sorted((Path(__file__).resolve().parents[2] / "trees").glob("*.py"))


@pytest.mark.parametrize("path", TREES, ids=[p.stem for p in TREES])
def test_tree_file_ends_with_every_cube_within_the_threshold(path):
    module = treefile.load(path)
    root = treefile.build_root(module)
    with SimulatedRun(root, treefile.scene(module, seed=0)) as run:
        report = run.run()
    assert report.tree_status == "SUCCESS"
    assert report.objects, "an arrangement reports its objects"
    for outcome in report.objects:
        assert outcome.status == "within", outcome
        assert outcome.final_offset_mm < report.threshold_mm
        assert outcome.final_offset_truth_mm < report.threshold_mm, f"{outcome.name}: ground truth disagrees"


def test_a_two_centimetre_picking_error_is_pushed_back_within_the_threshold():
    """The cube is moved 2 cm after it was detected and before the grasp (the paper's picking error)."""
    module = treefile.load(TREES[0].parent / "single_cube.py")
    root = treefile.build_root(module)
    with SimulatedRun(root, treefile.scene(module, seed=0)) as run:

        def bump_after_detection(transition):
            if transition.behaviour == "detect red" and transition.new == "SUCCESS":
                # 45 degrees to the faces: 14 mm along each, so the pads still come down beside it.
                direction = run.cell.part_planar_truth("red")[2] + math.pi / 4
                run.cell.displace_part("red", 0.02 * np.cos(direction), 0.02 * np.sin(direction))

        run.transition_hooks.append(bump_after_detection)
        report = run.run()
    (red,) = report.objects
    assert red.placed_offset_mm > 5.0, "the injected error bit"
    assert red.pushes >= 1
    assert red.status == "within"
    assert red.final_offset_truth_mm < 1.0


def test_a_cube_that_slips_out_on_the_way_is_picked_again():
    """Mid-carry the pads lose their grip (friction gone): the guard notices within a tick, the tree re-picks."""
    module = treefile.load(TREES[0].parent / "single_cube.py")
    root = treefile.build_root(module)
    with SimulatedRun(root, treefile.scene(module, seed=1)) as run:
        cell, context = run.cell, run.context
        period_s = cell.config.physics.control_period_s
        state = {"slippery": False, "dropped_at": None}

        def slip_during_carry(tree_root):
            place = next(node for node in tree_root.iterate() if node.name == "place red")
            guard = next(node for node in tree_root.iterate() if node.name == "while holding red")
            if (
                not state["slippery"]
                and state["dropped_at"] is None
                and place.feedback_message == stages.CARRY_ABOVE_TARGET
            ):
                state["slippery"] = True
                for finger in cell.finger_joint_indices:
                    cell.client.changeDynamics(cell.robot_id, finger, lateralFriction=0.0)
            if state["slippery"] and state["dropped_at"] is None and not holding(context):
                state["dropped_at"] = cell.clock.now()
            if state["slippery"] and guard.status.value == "FAILURE":
                state["slippery"] = False  # grip restored for the second attempt
                for finger in cell.finger_joint_indices:
                    apply_contact(cell.config.physics.pad_contact, cell.client, cell.robot_id, finger)

        run.tick_hooks.append(slip_during_carry)
        report = run.run()
    assert state["dropped_at"] is not None, "the cube slipped out"
    guard_failures = [t for t in report.transitions if t.behaviour == "while holding red" and t.new == "FAILURE"]
    assert len(guard_failures) == 1
    assert "left the gripper" in guard_failures[0].feedback
    assert guard_failures[0].time_s - state["dropped_at"] <= period_s + 1e-9, "noticed within a tick"
    place_ends = [t for t in report.transitions if t.behaviour == "place red" and t.old == "RUNNING"]
    assert place_ends[0].new == "INVALID", "the carry was interrupted, not finished over air"
    detections = [t for t in report.transitions if t.behaviour == "detect red" and t.new == "SUCCESS"]
    assert len(detections) == 2, "detected again after the slip"
    (red,) = report.objects
    assert red.status == "within", red
