"""A headless pick and place in the pybullet cell, steered by ground truth."""

import math
from pathlib import Path

import pytest

from bt_arrange.objects import CUBE
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.scripted import ScriptedPickPlace

CUBE_EDGE_M = CUBE.size_m[0]


@pytest.fixture
def cell_with_cube():
    with WorkCell() as cell:
        cell.add_cube("blue", 0.42, 0.12, 0.35)
        cell.settle(0.3)
        yield cell


def test_pick_and_place_lands_within_a_fraction_of_a_millimetre(cell_with_cube):
    cell = cell_with_cube
    script = ScriptedPickPlace(cell)
    pick = script.pick(*cell.part_planar_truth("blue"))
    assert pick.grasped
    assert pick.grip_width_m == pytest.approx(CUBE_EDGE_M, abs=5e-4)
    assert cell.part_pose_truth("blue").z_m > 0.08, "the cube was lifted with the gripper"
    script.place(0.55, -0.10, -0.2)
    x, y, _ = cell.part_planar_truth("blue")
    assert math.hypot(x - 0.55, y + 0.10) < 0.5e-3
    assert cell.part_pose_truth("blue").z_m == pytest.approx(CUBE_EDGE_M / 2, abs=1e-3)
    assert not cell.part_in_gripper_truth("blue")


def test_the_grasp_is_friction_opening_mid_air_drops_the_cube(cell_with_cube):
    cell = cell_with_cube
    script = ScriptedPickPlace(cell)
    assert script.pick(*cell.part_planar_truth("blue")).grasped
    assert cell.part_in_gripper_truth("blue")
    held_z = cell.part_pose_truth("blue").z_m
    cell.gripper.open(0.080)
    cell.settle(1.0)
    assert not cell.part_in_gripper_truth("blue")
    assert held_z > 0.08
    assert cell.part_pose_truth("blue").z_m < CUBE_EDGE_M  # on the table (it may have tipped over)


def test_closing_on_nothing_is_a_failed_grasp():
    with WorkCell() as cell:
        script = ScriptedPickPlace(cell)
        pick = script.pick(0.5, 0.0, 0.0)
        assert not pick.grasped
        assert pick.grip_width_m < 0.005


@pytest.mark.parametrize(("axis", "distance_m"), [("x", 0.010), ("y", -0.006)])
def test_a_cube_can_be_pushed_by_a_distance_along_an_axis(axis, distance_m):
    with WorkCell() as cell:
        cell.add_cube("red", 0.5, 0.05, 0.0)
        cell.settle(0.3)
        x0, y0, _ = cell.part_planar_truth("red")
        ScriptedPickPlace(cell).push(x0, y0, axis, distance_m)
        x1, y1, yaw = cell.part_planar_truth("red")
        along, across = (x1 - x0, y1 - y0) if axis == "x" else (y1 - y0, x1 - x0)
        assert along == pytest.approx(distance_m, abs=2e-4)
        assert abs(across) < 2e-4
        assert abs(yaw) < math.radians(0.5)
        assert cell.part_pose_truth("red").z_m == pytest.approx(CUBE_EDGE_M / 2, abs=1e-3)


def test_a_push_squares_up_a_turned_cube():
    """Two pads meeting one face (opening = width - pad thickness) turn the cube square to the push."""
    with WorkCell() as cell:
        cell.add_cube("red", 0.5, 0.0, math.radians(4.0))
        cell.settle(0.3)
        x0, y0, _ = cell.part_planar_truth("red")
        ScriptedPickPlace(cell).push(x0, y0, "x", 0.015)
        assert abs(cell.part_planar_truth("red")[2]) < math.radians(0.3)


def test_a_cube_turned_33_degrees_under_the_pads_is_squared_and_held_without_a_regrasp():
    """The first close pinches two vertical edges (~69 mm apart); Pick's squaring closes bring it into the band."""
    from bt_arrange.behaviours.moves import max_grip_width_m, min_held_width_m
    from bt_arrange.objects import CUBE
    from bt_arrange.settings import ManipulationSettings

    settings = ManipulationSettings(squaring="shift")
    with WorkCell() as cell:
        cell.add_cube("red", 0.45, 0.05, math.radians(33.0))
        cell.settle(0.3)
        x, y, _ = cell.part_planar_truth("red")
        # The gripper comes down square to the pose before the turn, as after PickRotation's injection.
        pick = ScriptedPickPlace(cell, settings=settings).pick(x, y, 0.0)
        assert pick.grasped, pick.feedback
        assert "squared from a" in pick.feedback, "the first close pinched it across its corners"
        assert min_held_width_m(settings, CUBE) < pick.grip_width_m <= max_grip_width_m(settings, CUBE)
        assert cell.part_pose_truth("red").z_m > 0.08, "lifted with the gripper"
        _, _, yaw = cell.part_planar_truth("red")
        assert abs(math.degrees(yaw)) < 15.0, "turned most of the way back to square"


@pytest.mark.parametrize("turn_deg", [33.0, -33.0])
def test_a_cube_turned_33_degrees_either_way_is_squared_by_a_wrist_turn_and_held_square(turn_deg):
    """``squaring = "turn"``: the wrist turns +22.5 deg (turned the other way, then -22.5), the close squares it."""
    from bt_arrange.behaviours.moves import max_grip_width_m, min_held_width_m
    from bt_arrange.geometry import fold_yaw
    from bt_arrange.objects import CUBE
    from bt_arrange.settings import ManipulationSettings

    settings = ManipulationSettings(squaring="turn")
    with WorkCell() as cell:
        cell.add_cube("red", 0.45, 0.05, math.radians(turn_deg))
        cell.settle(0.3)
        x, y, _ = cell.part_planar_truth("red")
        script = ScriptedPickPlace(cell, settings=settings)
        pick = script.pick(x, y, 0.0)
        assert pick.grasped, pick.feedback
        assert "squared from a" in pick.feedback, "the first close pinched it across its corners"
        wrist_turn = math.copysign(settings.squaring_turn_deg, turn_deg)
        assert f"the wrist turned {wrist_turn:+.1f} deg" in pick.feedback
        assert min_held_width_m(settings, CUBE) < pick.grip_width_m <= max_grip_width_m(settings, CUBE)
        assert cell.part_pose_truth("red").z_m > 0.08, "lifted with the gripper"
        tcp = script.context.planner.kinematics.forward(cell.robot.arm.joint_positions())
        held_x, held_y, yaw = cell.part_planar_truth("red")
        assert abs(math.degrees(fold_yaw(yaw - tcp.yaw_rad))) < 5.0, "held square to the pads at the turned wrist"
        # Squared about its centre, not pivoted about a corner ("shift" moves it 13-19 mm along the pads).
        assert math.hypot(held_x - tcp.position_m[0], held_y - tcp.position_m[1]) < 3e-3


def test_a_blended_pick_grasps_and_a_blended_place_lands_within_a_third_of_a_millimetre(monkeypatch):
    """Motions handed on at speed (lift into carry, retreat into the way home) keep the grasp and the place.

    The whole single-cube tree, steered by the camera; ground truth only measures the result.
    """
    from bt_arrange import treefile
    from bt_arrange.behaviours.context import ArmBrake
    from bt_arrange_sim.pybullet.runs import SimulatedRun

    handed_on = []
    carry_on = ArmBrake.carry_on

    def counting_carry_on(self, motion):  # noqa: ANN001, ANN202
        if not motion.done:
            handed_on.append(motion)
        carry_on(self, motion)

    monkeypatch.setattr(ArmBrake, "carry_on", counting_carry_on)
    module = treefile.load(Path(__file__).resolve().parents[2] / "trees" / "single_cube.py")
    with SimulatedRun(treefile.build_root(module), treefile.scene(module, seed=0)) as run:
        report = run.run()
    (red,) = report.objects
    picks = [t for t in report.transitions if t.kind == "Pick" and t.new == "SUCCESS"]
    assert picks and not [t for t in report.transitions if t.kind == "Pick" and t.new == "FAILURE"]
    assert len(handed_on) >= 2, "the lift and the retreat were handed on at speed"
    assert red.placed_offset_truth_mm is not None and red.placed_offset_truth_mm < 0.3
    assert red.status == "within"
