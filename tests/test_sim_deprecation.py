"""The simulated cells' names that said cube for any part: deprecated aliases that warn once."""

from __future__ import annotations

import warnings

import pytest

from bt_arrange import deprecation
from bt_arrange.geometry import Pose
from bt_arrange_sim import scenes
from bt_arrange_sim.cell_base import RENAMED_METHODS, CellBase


class _Cell(CellBase):
    def __init__(self) -> None:
        self.parts = {"red": 3}
        self.object_types = {}

    def part_pose_truth(self, name: str) -> Pose:
        return Pose.from_planar(0.5, 0.1, 0.0, 0.025)


@pytest.fixture(autouse=True)
def fresh_warnings(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(deprecation, "_warned", set())


def test_the_old_names_give_the_new_and_warn_once_naming_them() -> None:
    cell = _Cell()
    with pytest.warns(DeprecationWarning, match=r"_Cell\.cubes.*_Cell\.parts"):
        assert cell.cubes is cell.parts
    with pytest.warns(DeprecationWarning, match=r"cube_pose_truth.*part_pose_truth"):
        assert cell.cube_pose_truth("red").position_m.tolist() == cell.part_pose_truth("red").position_m.tolist()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cell.cubes == {"red": 3}  # once per process
        assert cell.part_planar_truth("red")[:2] == pytest.approx((0.5, 0.1))  # the new names never warn
    with pytest.raises(AttributeError, match="no attribute 'cubez'"):
        cell.cubez  # noqa: B018


def test_every_renamed_method_exists_under_its_new_name_on_both_engines() -> None:
    from bt_arrange_sim.mujoco.cell import MujocoCell
    from bt_arrange_sim.pybullet.cell import WorkCell

    for new in RENAMED_METHODS.values():
        assert callable(getattr(WorkCell, new)) and callable(getattr(MujocoCell, new)), new


def test_cube_start_is_part_start() -> None:
    with pytest.warns(DeprecationWarning, match="PartStart"):
        assert scenes.CubeStart is scenes.PartStart
