"""What a run leaves behind in a long-lived process: nothing that grows run by run.

The resident memory itself is measured by ``benchmarks/memory.py`` (a figure, not a test: it
depends on the allocator and the machine). Here the per-run leftovers that were found are checked
one by one: placo models (placo never frees one, so each is lent out again), mesh files in the
temporary folder, the blackboard and the physics client of a closed run.
"""

from __future__ import annotations

import gc
import tempfile
import weakref

import numpy as np
import py_trees
from fakeworld import FakeWorld, camera_view

from bt_arrange.motion import DEFAULT_HOME_Q, ArmKinematics, gripper_down_pose
from bt_arrange.motion.urdf import default_urdf_path
from bt_arrange.objects import ObjectStart, ObjectType
from bt_arrange.session import Session
from bt_arrange.shapes import Prism
from bt_arrange.trees import Target, arrangement

TRIANGLE = ObjectType("triangle", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.015, 0.045]], 0.02))


def test_a_dropped_kinematics_lends_its_placo_model_to_the_next() -> None:
    from bt_arrange.motion import placo_models

    gc.collect()  # the kinematics other tests left as garbage go back first
    first = ArmKinematics()
    model = first._robot  # noqa: SLF001
    del first
    gc.collect()
    assert placo_models.free_models(str(default_urdf_path())) >= 1
    kinematics = [ArmKinematics() for _ in range(3)]
    robots = [k._robot for k in kinematics]  # noqa: SLF001
    # The dropped one's model is lent again rather than a new one built (placo would leak the old one)...
    assert any(robot is model for robot in robots)
    # ...and each live kinematics has a model of its own.
    assert len({id(robot) for robot in robots}) == 3


def test_a_lent_model_answers_as_a_new_one() -> None:
    used = ArmKinematics()
    used.inverse(gripper_down_pose(0.6, -0.2, 0.05, 0.7), DEFAULT_HOME_Q)
    used.forward(np.array([0.3, -1.0, 1.2, -0.5, -1.2, 0.4]))
    del used
    gc.collect()
    lent, fresh = ArmKinematics(), ArmKinematics()
    target = gripper_down_pose(0.45, 0.1, 0.03, -0.3)
    assert np.array_equal(lent.inverse(target, DEFAULT_HOME_Q), fresh.inverse(target, DEFAULT_HOME_Q))
    assert np.array_equal(lent.forward(DEFAULT_HOME_Q).matrix, fresh.forward(DEFAULT_HOME_Q).matrix)


def test_a_prism_part_leaves_no_mesh_file_in_the_temporary_folder(tmp_path, monkeypatch) -> None:
    from bt_arrange_sim.pybullet.cell import WorkCell

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    with WorkCell() as cell:
        cell.add_object(TRIANGLE, "red", 0.5, 0.0)
        cell.settle(0.05)
        assert cell.part_planar_truth("red")[0] > 0.45  # the part is there, loaded from its meshes
        assert list(tmp_path.iterdir()) == []
    assert cell.client is None  # the physics client is disconnected


def test_a_closed_session_leaves_no_key_on_the_blackboard_and_gives_its_placo_model_back() -> None:
    from bt_arrange.motion import placo_models

    root = arrangement([Target("red", 0.50, 0.05)])
    with Session(root, [ObjectStart("red", 0.42, -0.22, 0.1)], FakeWorld, view=camera_view()) as run:
        run.run()
        assert py_trees.blackboard.Blackboard.storage  # the run's keys, readable until it closes
        free = placo_models.free_models(str(default_urdf_path()))
    assert py_trees.blackboard.Blackboard.storage == {}
    # The tree holds its context in cycles: the model goes back at close, not when the collector comes.
    assert placo_models.free_models(str(default_urdf_path())) == free + 1


def test_closing_a_session_collects_what_runs_left_in_cycles() -> None:
    class Node:
        """A stand-in for a finished run's tree: garbage only the collector finds (it points at itself)."""

    root = arrangement([Target("red", 0.50, 0.05)])
    run = Session(root, [ObjectStart("red", 0.42, -0.22, 0.1)], FakeWorld, view=camera_view())
    run.run()
    left = Node()
    left.me = left  # type: ignore[attr-defined]
    gone = weakref.ref(left)
    del left
    gc.disable()  # the collector's own passes must not do the session's work here
    try:
        assert gone() is not None
        run.close()
        assert gone() is None
    finally:
        gc.enable()
