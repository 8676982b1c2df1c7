"""Draw a recorded run's 3-D scene at one moment from its ``run.mcap`` alone (no simulator, no Foxglove).

    python scripts/mcap_scene.py runs/four/run.mcap docs/images/foxglove_scene.png [--time-s 6.0]

What Foxglove's 3-D panel would show, from the file's own data: the ``/tf`` frames chained to the
world (the arm as lines from link origin to link origin, the camera's position), each part of
``/parts`` at its last transform up to ``--time-s`` (a box as its edges, a prism as its mesh's
edges) and each target's faint outline; beside it, the last ``/camera/image`` up to then.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mcap_protobuf.decoder import DecoderFactory  # noqa: E402

from bt_arrange.geometry import quaternion_to_matrix  # noqa: E402


def matrix(translation, rotation) -> np.ndarray:  # noqa: ANN001 - Foxglove Vector3, Quaternion
    """The 4x4 transform of a Foxglove translation and rotation."""
    out = np.eye(4)
    out[:3, :3] = quaternion_to_matrix([rotation.x, rotation.y, rotation.z, rotation.w])
    out[:3, 3] = (translation.x, translation.y, translation.z)
    return out


def read(path: Path, until_ns: int) -> tuple[dict, list, bytes | None]:
    """The last transform of each frame, the scene's entities and the last image, up to ``until_ns``."""
    decoders = DecoderFactory()
    transforms: dict[str, tuple[str, np.ndarray]] = {}
    entities, image = [], None
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            if message.log_time > until_ns:
                break
            if channel.message_encoding == "json":
                continue
            value = decoders.decoder_for(channel.message_encoding, schema)(message.data)
            if channel.topic == "/tf":
                for t in value.transforms:
                    transforms[t.child_frame_id] = (t.parent_frame_id, matrix(t.translation, t.rotation))
            elif channel.topic == "/parts" and not entities:
                entities = list(value.entities)
            elif channel.topic == "/camera/image":
                image = value.data
    return transforms, entities, image


def in_world(frame: str, transforms: dict) -> np.ndarray:
    """The pose of ``frame`` in the world: its transforms chained up to the root."""
    pose = np.eye(4)
    while frame in transforms:
        parent, step = transforms[frame]
        pose = step @ pose
        frame = parent
    return pose


def draw(path: Path, out: Path, time_s: float) -> None:
    """The scene at ``time_s`` of world time, and the last image up to then, as a PNG."""
    transforms, entities, image = read(path, round(time_s * 1e9))
    figure = plt.figure(figsize=(12, 5.5))
    axes = figure.add_subplot(1, 2, 1, projection="3d")
    for child, (parent, _) in transforms.items():  # the arm: a line from each link's origin to its child's
        if parent == "world":
            continue
        a, b = in_world(parent, transforms)[:3, 3], in_world(child, transforms)[:3, 3]
        axes.plot(*zip(a, b, strict=True), color="0.3", linewidth=2.5)
    camera = in_world("camera", transforms)[:3, 3]
    axes.scatter(*camera, color="black", marker="s")
    axes.text(*camera, "  camera", fontsize=8)
    for entity in entities:
        frame = in_world(entity.frame_id, transforms) if entity.frame_locked else np.eye(4)
        for cube in entity.cubes:
            half = np.array([cube.size.x, cube.size.y, cube.size.z]) / 2
            corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
            world = (frame[:3, :3] @ corners.T).T + frame[:3, 3]
            rgb = (cube.color.r, cube.color.g, cube.color.b)
            for i in range(8):
                for j in range(i + 1, 8):
                    if bin(i ^ j).count("1") == 1:
                        axes.plot(*zip(world[i], world[j], strict=True), color=rgb, linewidth=1.5)
        for mesh in entity.triangles:
            points = np.array([[p.x, p.y, p.z] for p in mesh.points])
            world = (frame[:3, :3] @ points.T).T + frame[:3, 3]
            rgb = (mesh.color.r, mesh.color.g, mesh.color.b)
            for k in range(0, len(world), 3):
                axes.plot(*zip(*world[[k, k + 1, k + 2, k]], strict=True), color=rgb, linewidth=0.5)
        for line in entity.lines:
            base = matrix(line.pose.position, line.pose.orientation)
            points = np.array(
                [[p.x, p.y, p.z] for p in line.points] + [[line.points[0].x, line.points[0].y, line.points[0].z]]
            )
            world = (base[:3, :3] @ points.T).T + base[:3, 3]
            axes.plot(*world.T, color=(line.color.r, line.color.g, line.color.b), alpha=0.5, linestyle="--")
    axes.set_xlim(-0.1, 0.8)
    axes.set_ylim(-0.45, 0.45)
    axes.set_zlim(0.0, 0.9)
    axes.set_box_aspect((0.9, 0.9, 0.9))
    axes.set_xlabel("x (m)")
    axes.set_ylabel("y (m)")
    moment = f"{time_s:g} s of world time" if time_s < 1e9 else "the end"
    axes.set_title(f"{path.name} at {moment}: /tf, /parts")
    if image is not None:
        pixels = cv2.cvtColor(cv2.imdecode(np.frombuffer(image, np.uint8), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
        side = figure.add_subplot(1, 2, 2)
        side.imshow(pixels)
        side.set_title("the last /camera/image up to then")
        side.axis("off")
    figure.tight_layout()
    figure.savefig(out, dpi=90)


def main() -> None:
    """The command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mcap", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--time-s", type=float, default=None, help="the moment (default: the end)")
    args = parser.parse_args()
    time_s = args.time_s if args.time_s is not None else 1e9
    draw(args.mcap, args.out, time_s)
    print(json.dumps({"out": str(args.out)}))


if __name__ == "__main__":
    main()
