"""A puzzle's ground truth for the report: pieces matched where seen, homes under the whole's symmetry."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pytest

from bt_arrange.behaviours.puzzle import SurveyedPiece
from bt_arrange.puzzle import PuzzleSpec
from bt_arrange.puzzle.evaluation import PuzzleTruth
from bt_arrange.trees import Target

SPEC = PuzzleSpec("slab", (0.16, 0.12, 0.02), 2, 0.002, "red", 0.5, 0.0, 0.0)


@dataclass
class FakeTruth:
    poses: dict[str, tuple[float, float, float]]
    homes: dict[str, tuple[str, tuple[float, float, float]]]

    def part_names(self) -> list[str]:
        return list(self.poses)

    def planar_pose(self, name: str) -> tuple[float, float, float]:
        return self.poses[name]

    def home_pose(self, name: str):
        return self.homes.get(name)


def truth() -> FakeTruth:
    return FakeTruth(
        {"slab fragment 1": (0.40, 0.25, 0.3), "slab fragment 2": (0.60, -0.25, 1.0), "red": (0.3, 0.0, 0.0)},
        {"slab fragment 1": ("slab", (0.46, 0.0, 0.1)), "slab fragment 2": ("slab", (0.54, 0.0, -0.2))},
    )


def surveyed(world: FakeTruth) -> PuzzleTruth:
    evaluation = PuzzleTruth([SPEC], world)
    # The camera numbered them its own way: "slab 1" is the world's fragment 2.
    evaluation.surveyed(
        SPEC, [SurveyedPiece("slab 1", None, (0.601, -0.249)), SurveyedPiece("slab 2", None, (0.399, 0.25))]
    )
    return evaluation


def test_each_named_piece_is_the_world_s_part_nearest_where_the_camera_saw_it() -> None:
    assert surveyed(truth()).parts == {"slab 1": "slab fragment 2", "slab 2": "slab fragment 1"}


@pytest.mark.parametrize("half_turned", [False, True])
def test_the_true_home_is_taken_under_the_whole_s_symmetry_the_solve_chose(half_turned: bool) -> None:
    evaluation = surveyed(truth())
    homes = {"slab 1": (0.54, 0.0, -0.2), "slab 2": (0.46, 0.0, 0.1)}
    if half_turned:  # the solve put the whole together turned half a turn: the same slab
        homes = {k: (1.0 - x, -y, yaw + math.pi) for k, (x, y, yaw) in homes.items()}
    targets = [Target("red", x + 0.0002, y, yaw, name=k) for k, (x, y, yaw) in homes.items()]
    for target in targets:
        home = evaluation.home(target, targets)
        assert home is not None
        assert home[:2] == pytest.approx(homes[target.obj][:2], abs=1e-9)
        assert math.cos(home[2] - homes[target.obj][2]) == pytest.approx(1.0)


def test_other_targets_and_a_world_without_homes_have_none() -> None:
    evaluation = surveyed(truth())
    assert evaluation.home(Target("red", 0.3, 0.0), []) is None
    plain = PuzzleTruth([SPEC], None)
    plain.surveyed(SPEC, [SurveyedPiece("slab 1", None, (0.6, -0.25))])
    assert plain.parts == {}
