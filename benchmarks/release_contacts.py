"""What holds the pads at a release: each pad's contacts with the part, by ground truth.

    python benchmarks/release_contacts.py [--plan trees/irregular_parts.toml] [--seeds 0] [--json]

Runs a plan in the headless pybullet cell and, through every tick of each part's release (the
pads opening on the set-down part), reads from the simulator (evaluation only, nothing of it
steers the robot) the contact points between each finger link and the part: their normal
forces, how far they are into each other and the normal's direction in the gripper's frame. A
contact whose force pushes its pad *shut* (the normal's component along the pad's opening
direction is negative) is one the pads cannot open away from: the release stalls. One row a
release: the opening reached against the one commanded, the largest shutting force on each pad
(N) with its normal's angle off the closing axis (deg), the deepest contact (mm), the part's tilt
(deg) when the release began, and whether the fingers stalled (stopped 2 mm or more short, then
were sent all the way open: with a pad pushed shut, held by the part; with none, only slow to start).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from bt_arrange import treefile
from bt_arrange.behaviours import stages as stage
from bt_arrange.behaviours.base import GripperStage
from bt_arrange_sim.pybullet.runs import SimulatedRun

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "trees" / "irregular_parts.toml"
#: Each finger's opening direction along the tool's x axis (the URDF's joint axes: left +x, right -x).
OPENING_SIGN = (1.0, -1.0)
#: A pad pushed shut by more than this (N) is held by the part, not merely slow to leave it.
HELD_SHUT_N = 5.0


def _pad_contacts(cell, obj: str) -> list[dict]:  # noqa: ANN001
    """Each finger link's contacts with the part in the tool frame: shutting force, angle, depth."""
    client, robot = cell.client, cell.robot_id
    tool = next(i for i in range(client.getNumJoints(robot)) if client.getJointInfo(robot, i)[12] == b"tool0")
    rotation = np.array(client.getMatrixFromQuaternion(client.getLinkState(robot, tool)[5])).reshape(3, 3)
    pads = []
    for finger, sign in zip(cell.finger_joint_indices, OPENING_SIGN, strict=True):
        shut_n, angle_deg, depth_mm = 0.0, 0.0, 0.0
        for point in client.getContactPoints(robot, cell.parts[obj], linkIndexA=finger):
            normal = rotation.T @ np.array(point[7])  # on the part, towards the pad: the push on the pad
            along = sign * float(normal[0])
            depth_mm = max(depth_mm, -point[8] * 1000)
            if along < 0 and -along * point[9] > shut_n:
                shut_n = -along * point[9]
                angle_deg = math.degrees(math.acos(min(1.0, abs(float(normal[0])))))
        pads.append({"shut_n": round(shut_n, 1), "off_axis_deg": round(angle_deg, 1), "depth_mm": round(depth_mm, 2)})
    return pads


def run(plan: Path, seed: int) -> list[dict]:
    """One run of ``plan``; a row per release of a part."""
    module = treefile.load(plan)
    root = treefile.build_root(module)
    rows: list[dict] = []
    open_releases: dict[int, dict] = {}
    with SimulatedRun(root, treefile.scene(module, seed=seed)) as session:
        cell = session.cell

        def read(tree_root) -> None:  # noqa: ANN001
            for node in tree_root.iterate():
                obj = getattr(node, "obj", None)
                key = id(node)
                releasing = obj is not None and getattr(node, "stage", None) == stage.RELEASE_PART
                row = open_releases.get(key)
                if releasing and row is None:
                    part = cell.part_pose_truth(obj)
                    tilt = math.degrees(math.acos(max(-1.0, min(1.0, float(part.rotation[2, 2])))))
                    row = {"seed": seed, "part": cell.object_types[obj].name, "tilt_deg": round(tilt, 2)}
                    row["pads"] = [{"shut_n": 0.0, "off_axis_deg": 0.0, "depth_mm": 0.0} for _ in range(2)]
                    open_releases[key] = row
                if row is None:
                    continue
                if releasing:
                    for worst, now in zip(row["pads"], _pad_contacts(cell, obj), strict=True):
                        depth_mm = max(worst["depth_mm"], now["depth_mm"])
                        if now["shut_n"] > worst["shut_n"]:
                            worst.update(now)
                        worst["depth_mm"] = depth_mm
                    continue
                # The release is over (the retreat's first tick, or the behaviour ended).
                del open_releases[key]
                width_m = sum(cell.client.getJointState(cell.robot_id, f)[0] for f in cell.finger_joint_indices)
                row["opening_mm"] = round(width_m * 1000, 1)
                # The release stage's own count of fingers stopping short (a benchmark may read it).
                releases = [s for s in getattr(node, "_stages", []) if isinstance(s, GripperStage)]
                row["stalled"] = any(s.stalled for s in releases if s.name == stage.RELEASE_PART)
                rows.append(row)

        session.tick_hooks.append(read)
        session.run()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plan", type=Path, default=PLAN, help="a tree file (default: the irregular parts)")
    parser.add_argument("--seeds", type=int, nargs="*", default=[0], help="scene seeds")
    parser.add_argument("--json", action="store_true", help="JSON lines only")
    args = parser.parse_args()
    rows = [row for seed in args.seeds for row in run(args.plan, seed)]
    for row in rows:
        if args.json:
            print(json.dumps(row))
            continue
        pads = "  ".join(
            f"{p['shut_n']:5.1f} N {p['off_axis_deg']:4.1f} deg {p['depth_mm']:.2f} mm" for p in row["pads"]
        )
        print(
            f"{row['seed']:>4}  {row['part']:<10} {row['opening_mm']:6.1f} mm  tilt {row['tilt_deg']:5.2f}  {pads}"
            f"  {'STALLED' if row['stalled'] else ''}"
        )
    if not args.json:
        stalled = [r for r in rows if r["stalled"]]
        held = [r for r in stalled if max(p["shut_n"] for p in r["pads"]) > HELD_SHUT_N]
        print(
            f"{len(stalled)} of {len(rows)} releases stopped short at least once, {len(held)} of them with a pad "
            f"pushed shut by more than {HELD_SHUT_N:.0f} N; per pad (left, right): the largest force pushing it "
            "shut, its normal's angle off the closing axis, the deepest contact; by ground truth (evaluation only)"
        )


if __name__ == "__main__":
    main()
