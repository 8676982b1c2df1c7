"""Where a part's set-down error comes from, stage by stage.

    python benchmarks/setdown.py [--seeds 0 1 2] [--fresco-seeds 3] [--isolated] [--json]

Runs the five outlines of ``benchmarks/plans/irregular_parts.toml`` and a fresco (the example
plan's slab, its fracture from each ``--fresco-seeds``) in the headless pybullet cell, and at
every stage of each part's Pick and Place reads, by ground truth (the simulator's, evaluation
only), where the held part sits in the gripper against where the grasp expects it: the part's
offset from its grasp's planned place along the closing axis (``closing_mm``) and along the pads
(``along_mm``), its tilt, and at the end the set-down error against the target. A stage is read
at its first tick, so each row says what the stages before it did:

- ``close``: the pads are about to close (the offset is the camera's and the approach's);
- ``lift``: closed (what the close did);
- ``carry``: lifted (what the lift did);
- ``lower``: above the target (what the carry did);
- ``release``: down, the pads still closed (what the lowering did);
- ``retreat``: the pads open (what the release did);
- ``down``: the part at rest after the retreat: the set-down error by truth.

With ``--isolated`` it also picks each outline at its true pose (``ScriptedPickPlace``, no camera)
at two turns and sets it down, for the grip's and the carry's share alone. One JSON line a part
as it ends; the last line sums the stages up (mean and largest of each stage's change).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import statistics
import tempfile
from pathlib import Path

from bt_arrange import treefile
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.moves import grasp_of
from bt_arrange.geometry import Pose
from bt_arrange.settings import ManipulationSettings
from bt_arrange_sim.pybullet.runs import SimulatedRun

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "benchmarks" / "plans" / "irregular_parts.toml"
FRESCO = ROOT / "bt_arrange" / "examples" / "fresco.toml"
#: The stages read, by the stage names the behaviours report.
STAGES = {
    stage.CLOSE_ON_PART: "close",
    stage.LIFT_PART: "lift",
    stage.CARRY_ABOVE_TARGET: "carry",
    stage.LOWER_PART: "lower",
    stage.RELEASE_PART: "release",
    stage.RETREAT: "retreat",
}


def _in_gripper(tcp: Pose, part: Pose, ideal_m: tuple[float, float]) -> dict:
    """The part's offset from its grasp's planned place in the gripper's frame (mm), and its tilt (deg)."""
    relative = tcp.inverse() @ part
    # The TCP's z points down: its y axis is the planar gripper frame's -y.
    closing_mm = (relative.position_m[0] - ideal_m[0]) * 1000
    along_mm = (-relative.position_m[1] - ideal_m[1]) * 1000
    tilt_deg = math.degrees(math.acos(max(-1.0, min(1.0, float(part.rotation[2, 2])))))
    return {"closing_mm": round(closing_mm, 3), "along_mm": round(along_mm, 3), "tilt_deg": round(tilt_deg, 3)}


def _ideal_m(settings: ManipulationSettings, object_type) -> tuple[float, float]:  # noqa: ANN001
    """Where the grasp expects the part's origin in the gripper's planar frame (m)."""
    grasp = grasp_of(settings, object_type)
    c, s = math.cos(grasp.yaw_offset_rad), math.sin(grasp.yaw_offset_rad)
    cx, cy = grasp.centre_m
    # The TCP stands at the grasp's centre, turned by its yaw offset: the origin is at -centre, turned back.
    return (-(c * cx + s * cy), -(-s * cx + c * cy))


def run_tree(plan: Path, seed: int, label: str) -> list[dict]:
    """One run of ``plan``; each part's stage rows."""
    module = treefile.load(plan)
    root = treefile.build_root(module)
    settings = ManipulationSettings()
    rows: dict[str, dict] = {}
    last_stage: dict[int, str] = {}
    with SimulatedRun(root, treefile.scene(module, seed=seed)) as session:
        cell = session.cell

        def read(tree_root) -> None:  # noqa: ANN001
            for node in tree_root.iterate():
                name = STAGES.get(getattr(node, "stage", None) or "")
                obj = getattr(node, "obj", None)
                if name is None or obj is None or last_stage.get(id(node)) == name:
                    continue
                last_stage[id(node)] = name
                row = rows.setdefault(obj, {"run": label, "seed": seed, "part": cell.object_types[obj].name})
                # A regrasp or a second pick reads the stages again: the last reading stands.
                ideal = _ideal_m(settings, cell.object_types[obj])
                row[name] = _in_gripper(cell.arm.tcp_pose(), cell.part_pose_truth(obj), ideal)

        session.tick_hooks.append(read)
        report = session.run()
    for outcome in report.objects:
        row = rows.get(outcome.name)
        if row is None:
            continue
        row["placed_truth_mm"] = outcome.placed_offset_truth_mm
        row["placed_camera_mm"] = outcome.placed_offset_mm
        row["final_truth_mm"] = outcome.final_offset_truth_mm
        row["status"] = outcome.status
    return list(rows.values())


def fresco_plan(seed: int, folder: Path) -> Path:
    """The example fresco with its fracture from ``seed`` and its pieces scattered from it."""
    text = re.sub(r"(?m)^seed = \d+", f"seed = {seed}", FRESCO.read_text()) + f"\n[scene]\nseed = {seed}\n"
    path = folder / f"fresco_{seed}.toml"
    path.write_text(text)
    return path


def run_isolated(yaws_deg: tuple[float, ...] = (30.0, -70.0)) -> list[dict]:
    """Each outline picked at its true pose and set down at a target: the grip's and the carry's share alone."""
    from bt_arrange_sim.config import CellConfig
    from bt_arrange_sim.pybullet.cell import WorkCell
    from bt_arrange_sim.pybullet.scripted import OBJ, ScriptedPickPlace

    module = treefile.load(PLAN)
    root = treefile.build_root(module)
    settings = ManipulationSettings()
    rows = []
    for target in root.targets:
        kind = target.object_type
        for yaw_deg in yaws_deg:
            cell = WorkCell(CellConfig())
            try:
                x0, y0, yaw0 = 0.45, 0.15, math.radians(yaw_deg)
                cell.add_object(kind, "red", x0, y0, yaw0, name=OBJ)  # one part alone: any colour of the cell's table
                cell.step(50)
                script = ScriptedPickPlace(cell, settings=settings, object_type=kind)
                held = script.pick(x0, y0, yaw0)
                lifted = _in_gripper(cell.arm.tcp_pose(), cell.part_pose_truth(OBJ), _ideal_m(settings, kind))
                goal = (0.50, 0.0, math.radians(35.0))
                script.place(*goal)
                cell.step(100)
                rest = cell.part_pose_truth(OBJ)
                error_mm = math.hypot(rest.x_m - goal[0], rest.y_m - goal[1]) * 1000
                rows.append(
                    {
                        "run": "isolated",
                        "part": kind.name,
                        "picked_at_deg": yaw_deg,
                        "grip_width_mm": round(held.grip_width_m * 1000, 2),
                        "grasp_width_mm": round(grasp_of(settings, kind).width_m * 1000, 2),
                        "lift": lifted,
                        "set_down_truth_mm": round(error_mm, 3),
                    }
                )
            finally:
                cell.close()
    return rows


def summary(rows: list[dict]) -> dict:
    """Each stage's change of the in-gripper offset (mm): mean and largest over the parts."""
    order = ["close", "lift", "carry", "lower", "release", "retreat"]
    out: dict[str, dict] = {}
    for before, after in zip(order, order[1:], strict=False):
        moves = [
            math.hypot(r[after]["closing_mm"] - r[before]["closing_mm"], r[after]["along_mm"] - r[before]["along_mm"])
            for r in rows
            if before in r and after in r
        ]
        if moves:
            out[f"{before}->{after}"] = {"mean_mm": round(statistics.fmean(moves), 3), "max_mm": round(max(moves), 3)}
    tilts = [r["release"]["tilt_deg"] for r in rows if "release" in r]
    if tilts:
        out["tilt_at_release_deg"] = {"mean": round(statistics.fmean(tilts), 2), "max": round(max(tilts), 2)}
    placed = [r["placed_truth_mm"] for r in rows if r.get("placed_truth_mm") is not None]
    if placed:
        out["placed_truth_mm"] = {"mean": round(statistics.fmean(placed), 3), "max": round(max(placed), 3)}
    finals = [r["final_truth_mm"] for r in rows if r.get("final_truth_mm") is not None]
    if finals:
        out["final_truth_mm"] = {"mean": round(statistics.fmean(finals), 3), "max": round(max(finals), 3)}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2], help="scene seeds of the irregular plan")
    parser.add_argument("--fresco-seeds", type=int, nargs="*", default=[3], help="fracture and scene seeds")
    parser.add_argument("--isolated", action="store_true", help="also pick each outline at its true pose")
    parser.add_argument("--json", action="store_true", help="JSON lines only")
    args = parser.parse_args()
    rows: list[dict] = []

    def emit(new: list[dict]) -> None:
        for row in new:
            print(json.dumps(row), flush=True)
        rows.extend(new)

    for seed in args.seeds:
        emit(run_tree(PLAN, seed, "irregular"))
    with tempfile.TemporaryDirectory() as folder:
        for seed in args.fresco_seeds:
            emit(run_tree(fresco_plan(seed, Path(folder)), seed, "fresco"))
    if args.isolated:
        emit(run_isolated())
    tree_rows = [r for r in rows if r["run"] != "isolated"]
    print(json.dumps({"summary": summary(tree_rows), "parts": len(tree_rows)}))


if __name__ == "__main__":
    main()
