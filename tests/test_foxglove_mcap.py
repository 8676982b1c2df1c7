"""``--record DIR`` writes ``DIR/run.mcap``: read back with the ``mcap`` package, one real single-cube run."""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("mcap")
pytest.importorskip("mcap_protobuf")

from mcap.reader import make_reader  # noqa: E402

from bt_arrange import backends, treefile  # noqa: E402
from bt_arrange.foxglove.links import RobotLinks  # noqa: E402
from bt_arrange.geometry import quaternion_to_matrix  # noqa: E402
from bt_arrange.motion.urdf import default_urdf_path  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

#: Topic: the schema it must have.
TOPICS = {
    "/camera/image": "foxglove.CompressedImage",
    "/camera/calibration": "foxglove.CameraCalibration",
    "/tf": "foxglove.FrameTransforms",
    "/robot_description": "std_msgs/String",
    "/parts": "foxglove.SceneUpdate",
    "/tree": "bt_arrange.TreeStatus",
    "/log": "foxglove.Log",
    "/report": "bt_arrange.Report",
}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):  # noqa: ANN001, ANN201 - the folder, the report, the final truth
    folder = tmp_path_factory.mktemp("record")
    module = treefile.load(str(ROOT / "trees" / "single_cube.py"))
    root = treefile.build_root(module)
    backend = backends.load()
    starts = treefile.scene(module, 0, backend=backend)
    with backend.open_run(root, starts, record_dir=folder, title="single_cube.py") as run:
        report = run.run()
        truth = {name: run.truth.planar_pose(name) for name in run.truth.part_names()}
        full = {name: run.world.pose_truth(name) for name in run.truth.part_names()}
        tcp = run.world.robot.arm.tcp_pose()
    return folder, report, truth, full, tcp


def read(folder: Path):  # noqa: ANN201 - the summary; (schema, channel, message, decoded) per message, in file order
    """The file's messages decoded: protobuf by the schema the file carries (mcap_protobuf), JSON as JSON."""
    from mcap_protobuf.decoder import DecoderFactory

    decoders = DecoderFactory()
    decoded = []
    with open(folder / "run.mcap", "rb") as stream:
        reader = make_reader(stream)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.message_encoding == "json":
                value = json.loads(message.data)
            else:
                decode = decoders.decoder_for(channel.message_encoding, schema)
                assert decode is not None, channel.topic
                value = decode(message.data)
            decoded.append((schema, channel, message, value))
        return reader.get_summary(), decoded


@pytest.fixture(scope="module")
def messages(recorded):  # noqa: ANN001, ANN201
    summary, decoded = read(recorded[0])
    by_topic = defaultdict(list)
    for schema, channel, message, value in decoded:
        by_topic[channel.topic].append((schema, message, value))
    return summary, decoded, by_topic


def test_every_topic_is_there_with_its_schema(messages) -> None:  # noqa: ANN001
    summary, _, by_topic = messages
    schemas = {channel.topic: summary.schemas[channel.schema_id].name for channel in summary.channels.values()}
    for topic, schema in TOPICS.items():
        assert schemas.get(topic) == schema, topic
        assert by_topic[topic], f"no message on {topic}"
    assert len(by_topic["/report"]) == 1


def test_times_are_non_decreasing_and_world_time(messages, recorded) -> None:  # noqa: ANN001
    _, decoded, by_topic = messages
    times = [message.log_time for _, _, message, _ in decoded]
    assert times == sorted(times)
    report = recorded[1]
    # World time from the world's start: the settling (under 0.3 s) and the run's own world time.
    assert 0 <= times[0] and times[-1] / 1e9 == pytest.approx(report.sim_seconds, abs=0.35)
    for _, message, value in by_topic["/camera/image"] + by_topic["/log"]:
        assert value.timestamp.seconds * 10**9 + value.timestamp.nanos == message.log_time


def test_every_image_decodes_with_its_calibration(messages) -> None:  # noqa: ANN001
    _, _, by_topic = messages
    images, calibrations = by_topic["/camera/image"], by_topic["/camera/calibration"]
    assert len(images) == len(calibrations) >= 2  # the pick's look and the inspection at least
    for (_, _, image), (_, _, calibration) in zip(images, calibrations, strict=True):
        assert image.format == "png" and image.frame_id == "camera"
        pixels = cv2.imdecode(np.frombuffer(image.data, np.uint8), cv2.IMREAD_COLOR)
        assert pixels is not None and pixels.shape[:2] == (calibration.height, calibration.width)
        assert calibration.K[0] > 0 and calibration.K[8] == 1.0


def test_the_last_transform_of_each_part_is_its_final_ground_truth(messages, recorded) -> None:  # noqa: ANN001
    _, _, by_topic = messages
    truth, full = recorded[2], recorded[3]
    last = {}
    for _, _, value in by_topic["/tf"]:
        for transform in value.transforms:
            last[transform.child_frame_id] = transform
    for name, (x_m, y_m, _) in truth.items():
        transform = last[name]
        assert transform.parent_frame_id == "world"
        assert abs(transform.translation.x - x_m) < 1e-5 and abs(transform.translation.y - y_m) < 1e-5
        assert abs(transform.translation.z - full[name].position_m[2]) < 1e-5


def test_the_links_chain_to_the_measured_tcp(messages, recorded) -> None:  # noqa: ANN001
    _, _, by_topic = messages
    links = RobotLinks(default_urdf_path())
    transforms = {t.child_frame_id: t for t in by_topic["/tf"][-1][2].transforms}
    parents = {joint.child: joint.parent for joint in links.joints}
    frame, chain = "tcp", []
    while frame != "world":  # every frame of the robot hangs from the world through its links
        chain.append(frame)
        frame = transforms[frame].parent_frame_id
    assert chain[-1] == links.base_link and all(parents.get(f) == transforms[f].parent_frame_id for f in chain[:-1])
    assert {"camera", "red"} <= set(transforms)
    # The URDF's joints at the measured positions put the TCP where the arm measures it.
    pose = np.eye(4)
    for frame in chain:
        t = transforms[frame]
        step = np.eye(4)
        step[:3, :3] = quaternion_to_matrix([t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w])
        step[:3, 3] = (t.translation.x, t.translation.y, t.translation.z)
        pose = step @ pose
    tcp = recorded[4]
    assert np.allclose(pose[:3, 3], tcp.position_m, atol=1e-4)
    assert np.allclose(pose[:3, :3], quaternion_to_matrix(tcp.quaternion_xyzw), atol=1e-3)


def decoded(message):  # noqa: ANN001, ANN201 - a Foxglove SDK message (opaque) as its protobuf
    from mcap.records import Schema
    from mcap_protobuf.decoder import DecoderFactory

    schema = type(message).get_schema()
    record = Schema(id=1, name=schema.name, encoding=schema.encoding, data=schema.data)
    return DecoderFactory().decoder_for("protobuf", record)(message.encode())


def test_a_prism_is_a_closed_mesh_and_a_box_a_cube() -> None:
    from bt_arrange.foxglove import scene
    from bt_arrange.shapes import Prism

    triangle = Prism.from_outline([(0.0, 0.0), (0.05, 0.0), (0.0, 0.04)], 0.03)
    entity = decoded(scene.part_entity("tile", triangle, (1.0, 0.5, 0.0)))
    points = entity.triangles[0].points
    assert len(points) == 3 * (2 + 2 * 3)  # a top, a bottom and two triangles per wall
    assert {round(p.z, 6) for p in points} == {-0.015, 0.015}
    box = decoded(scene.part_entity("bar", Prism.box(0.08, 0.04, 0.04), (0.0, 0.0, 1.0)))
    assert box.cubes and box.cubes[0].size.x == pytest.approx(0.08) and box.frame_locked


def test_the_tree_statuses_agree_with_the_transitions(messages, recorded) -> None:  # noqa: ANN001
    _, _, by_topic = messages
    folder = recorded[0]
    transitions = [json.loads(line) for line in (folder / "transitions.jsonl").read_text().splitlines()]
    trees = [value for _, _, value in by_topic["/tree"]]
    assert trees and all({"uid", "type", "name", "status"} <= set(node) for node in trees[0]["nodes"])
    assert [node["uid"] for node in trees[0]["nodes"]] == list(range(1, len(trees[0]["nodes"]) + 1))
    counts = defaultdict(int)
    for node in trees[0]["nodes"]:
        counts[node["name"]] += 1
    names = {name for name, count in counts.items() if count == 1}  # a name two nodes share says nothing
    # The last /tree message at each moment shows every node with its last transition up to then.
    latest = {}
    for tree in trees:
        latest[tree["time_s"]] = tree
    assert len(latest) >= 3
    for time_s, tree in latest.items():
        seen = {}
        for transition in transitions:
            if transition["time_s"] <= time_s + 1e-9:
                seen[transition["behaviour"]] = transition["new"]
        shown = {node["name"]: node["status"] for node in tree["nodes"]}
        for name, status in seen.items():
            if name in names:
                assert shown[name] == status, (time_s, name)
    # The end: the last message agrees with every node's last transition.
    assert trees[-1] is latest[max(latest)]
    assert all(node["type"] for node in trees[0]["nodes"])


def test_the_log_has_the_feedback_by_node_and_the_report_is_the_report(messages, recorded) -> None:  # noqa: ANN001
    _, _, by_topic = messages
    logs = [value for _, _, value in by_topic["/log"]]
    assert logs and all(log.name and log.message for log in logs)
    report = by_topic["/report"][0][2]
    assert report == json.loads(json.dumps(recorded[1].to_dict()))
    urdf = by_topic["/robot_description"][0][2]["data"]
    assert urdf == default_urdf_path().read_text(encoding="utf-8")
    entities = by_topic["/parts"][0][2].entities
    assert {e.id for e in entities} == {"part/red", "target/red"}
    part = next(e for e in entities if e.id == "part/red")
    assert part.frame_id == "red" and part.frame_locked and part.cubes[0].size.x == pytest.approx(0.04, abs=0.03)
    assert math.isclose(part.cubes[0].color.r, 1.0, abs_tol=0.5)


def test_the_layout_shipped_is_the_one_built() -> None:
    from bt_arrange.foxglove.layout import layout_json

    shipped = (ROOT / "docs" / "foxglove-layout.json").read_text(encoding="utf-8")
    assert shipped == layout_json(), "python -m bt_arrange.foxglove.layout > docs/foxglove-layout.json"
    panels = {panel["panelType"] for panel in _panels(json.loads(shipped)["content"])}
    assert {"ThreeDee", "Image", "Plot", "Log"} <= panels


def _panels(content: dict):  # noqa: ANN202 - the panels of a layout's content, depth first
    if content["type"] == "panel":
        yield content
    for item in content.get("items", []):
        yield from _panels(item["content"])


def test_an_error_in_the_recording_stops_it_not_the_run(tmp_path, monkeypatch) -> None:  # noqa: ANN001
    from bt_arrange.errors import RecordError
    from bt_arrange.foxglove.observer import RunObserver

    calls = {"n": 0}
    publish = RunObserver._publish_tf

    def failing(self, time_ns):  # noqa: ANN001, ANN202
        calls["n"] += 1
        if calls["n"] == 20:
            raise ValueError("a world without joints")
        return publish(self, time_ns)

    monkeypatch.setattr(RunObserver, "_publish_tf", failing)
    module = treefile.load(str(ROOT / "trees" / "single_cube.py"))
    backend = backends.load()
    with backend.open_run(
        treefile.build_root(module), treefile.scene(module, 0, backend=backend), record_dir=tmp_path
    ) as run:
        with pytest.raises(RecordError) as caught:
            run.run()
    error = caught.value
    assert error.result.all_within_threshold, "the run went on"
    assert [fault.path.name for fault in error.faults] == ["run.mcap"]
    assert "the recording stopped (ValueError: a world without joints)" in str(error)
    assert not (tmp_path / "run.mcap").exists() and (tmp_path / "replay.html").is_file()


def test_tf_carries_the_calibrated_camera_pose_perception_used(tmp_path) -> None:  # noqa: ANN001
    """With a calibration, world -> camera on /tf is the calibrated pose, not the world's own camera's."""
    from fakeworld import FakeWorld, camera_view

    from bt_arrange.calibration import CameraCalibration
    from bt_arrange.foxglove import scene as foxglove_scene
    from bt_arrange.geometry import Pose
    from bt_arrange.objects import ObjectStart
    from bt_arrange.session import Session
    from bt_arrange.trees import Target, arrangement

    view = camera_view()
    shifted = Pose.from_rotation(
        view.camera_pose_world.position_m + np.array([0.004, -0.003, 0.0]), view.camera_pose_world.rotation
    )
    calibration = CameraCalibration(view.intrinsics, shifted, 0.1, 20, "real", "2026-12-07T10:00:00+00:00")
    root = arrangement([Target("red", 0.50, 0.05)])
    starts = [ObjectStart("red", 0.42, -0.22, 0.1)]
    with Session(
        root, starts, FakeWorld, view=view, calibration=calibration, record_dir=tmp_path, time_limit_s=1.0
    ) as run:
        run.run()
    _, decoded = read(tmp_path)
    cameras = [
        t
        for _, channel, _, value in decoded
        if channel.topic == "/tf"
        for t in value.transforms
        if t.child_frame_id == foxglove_scene.CAMERA_FRAME
    ]
    assert cameras, "the camera is on /tf"
    last = cameras[-1].translation
    np.testing.assert_allclose([last.x, last.y, last.z], shifted.position_m, atol=1e-9)
