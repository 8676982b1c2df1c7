"""A small fresco reassembled headless by the camera: 3 pieces of one colour, 2 mm gaps, within 1 mm and 1 degree."""

from __future__ import annotations

from pathlib import Path

from bt_arrange import treefile
from bt_arrange.plan.layout import Outline, gap_m
from bt_arrange_sim.pybullet.runs import SimulatedRun

FRESCO = """
threshold_mm = 1.0
yaw_threshold_deg = 1.0

[colours.ochre]
rgb = [0.8, 0.55, 0.2]

[fresco.tile]
size_mm = [120, 80, 20]
pieces = 3
gap_mm = 2
seed = 0
colour = "ochre"
x_mm = 500
y_mm = 0
yaw_deg = 0
"""


def test_a_three_piece_fresco_is_reassembled_with_its_gaps(tmp_path: Path) -> None:
    path = tmp_path / "fresco.toml"
    path.write_text(FRESCO)
    module = treefile.load(path)
    root = treefile.build_root(module)
    with SimulatedRun(root, treefile.scene(module, 0)) as run:
        report = run.run()
        outlines = {}
        for target in root.targets:
            x, y, yaw = run.cell.part_planar_truth(target.obj)
            pieces = tuple(tuple(map(tuple, p)) for p in target.object_type.shape.convex_pieces())
            outlines[target.obj] = Outline(x, y, yaw, pieces)
    assert [o.name for o in report.objects] == ["tile 1", "tile 2", "tile 3"]
    for outcome in report.objects:
        assert outcome.status == "within", outcome
        assert outcome.final_offset_truth_mm < 1.0, outcome
        assert abs(outcome.final_yaw_error_truth_deg) < 1.0, outcome
        # No piece was shoved by a later one before its last look.
        assert outcome.moved_by_later_truth_mm is None or outcome.moved_by_later_truth_mm < 0.3, outcome
    # At least one piece went down beside another: released off its target and pushed home.
    assert any(outcome.pushes >= 1 for outcome in report.objects)
    names = list(outlines)
    gaps = [gap_m(outlines[a], outlines[b]) for i, a in enumerate(names) for b in names[i + 1 :]]
    assert min(gaps) > 0.0005  # none touching
