"""The coarse search joins the fragments of one face the opening cut apart, and nothing else."""

from __future__ import annotations

import numpy as np

from bt_arrange.objects import ObjectType
from bt_arrange.perception import PartDetector
from bt_arrange.perception.segmentation import Blob
from bt_arrange.shapes import Prism

ELL = ObjectType(
    "ell", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)
)
FACE_PX = 200.0


def _candidate(area_px: float, x_m: float, y_m: float, bbox: tuple[int, int, int, int]) -> tuple:
    return (Blob(area_px, (bbox[0] + bbox[2] / 2, bbox[1] + bbox[3] / 2), bbox), np.array([x_m, y_m]), FACE_PX)


def _join(candidates: list[tuple]) -> list[tuple]:
    return PartDetector().for_object(ELL)._join_fragments(candidates)  # noqa: SLF001 - the rule itself


def test_two_pieces_of_a_face_close_together_become_one_blob() -> None:
    joined = _join([_candidate(84, 0.330, -0.344, (272, 137, 14, 7)), _candidate(60, 0.297, -0.335, (273, 147, 7, 10))])
    assert len(joined) == 1
    blob, xy, _ = joined[0]
    assert blob.area_px == 144 and blob.bbox_px == (272, 137, 14, 20)
    np.testing.assert_allclose(xy, [(84 * 0.330 + 60 * 0.297) / 144, (84 * -0.344 + 60 * -0.335) / 144])


def test_a_whole_face_pieces_far_apart_or_more_than_a_face_together_stay_apart() -> None:
    whole_and_piece = [_candidate(190, 0.33, -0.34, (270, 130, 20, 20)), _candidate(60, 0.30, -0.33, (273, 147, 7, 10))]
    assert len(_join(whole_and_piece)) == 2
    far = [_candidate(84, 0.33, -0.34, (272, 137, 14, 7)), _candidate(60, 0.53, -0.34, (372, 147, 7, 10))]
    assert len(_join(far)) == 2
    too_much = [_candidate(150, 0.33, -0.34, (272, 137, 14, 7)), _candidate(150, 0.31, -0.34, (273, 147, 7, 10))]
    assert len(_join(too_much)) == 2
