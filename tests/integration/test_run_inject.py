"""``bt-arrange run trees/four_cubes.py --inject translation --seed 1 --json``: the errors go in, pushes take them out.

One headless run (a few seconds): Table 1's translation error into each of the four cubes, at the
magnitude the experiment's row uses, and every cube ends within its threshold.
"""

from __future__ import annotations

import json
from pathlib import Path

from bt_arrange import cli
from bt_arrange_sim.experiment.rows import row_injectors

FOUR_CUBES = Path(__file__).resolve().parents[2] / "trees" / "four_cubes.py"


def test_the_translation_error_is_injected_into_every_cube_and_pushed_out(capsys) -> None:
    code = cli.main(["run", str(FOUR_CUBES), "--inject", "translation", "--seed", "1", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0
    assert [o["status"] for o in report["objects"]] == ["within"] * 4
    assert report["objects_within"] == 4
    assert sum(o["pushes"] for o in report["objects"]) > 0
    # What went into which part: the row's injector, at the row's magnitude, fired once in each cube.
    (row_injector,) = row_injectors("translation")
    injected = report["injected"]
    assert [(i["error"], i["part"]) for i in injected] == [("translation", o["name"]) for o in report["objects"]]
    for record in injected:
        assert record["injector"] == row_injector.name and record["fired"] is True
        assert record["max_m"] == row_injector.params["max_m"] == 0.025
        assert 0 <= record["distance_mm"] <= 25.0
    # The parts moved furthest were the ones pushed: placed outside the threshold, pushed within.
    pushed = [o for o in report["objects"] if o["pushes"]]
    assert pushed and all(o["placed_offset_mm"] > 1.0 > o["final_offset_mm"] for o in pushed)
