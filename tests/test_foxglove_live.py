"""``bt-arrange run TREE --foxglove [PORT]``: a real WebSocket client on 127.0.0.1 watches a paced run.

The SDK speaks Foxglove's WebSocket protocol under the subprotocol ``foxglove.sdk.v1`` (the same
protocol as ``foxglove.websocket.v1``, renamed by Foxglove); the client offers both names.
"""

from __future__ import annotations

import asyncio
import base64
import json
import os
import re
import socket
import struct
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("foxglove")
websockets = pytest.importorskip("websockets")
pytest.importorskip("mcap_protobuf")

from mcap.records import Schema  # noqa: E402
from mcap_protobuf.decoder import DecoderFactory  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
SERVING = re.compile(r"serving the run to Foxglove on ws://127\.0\.0\.1:(\d+)")
#: Wall time the whole test may take, seconds (a paced single-cube run is about 4 s).
TIMEOUT_S = 120


def free_port_pair() -> int:
    """A port whose next one is free too (Groot2 uses both)."""
    for _ in range(50):
        with socket.socket() as first:
            first.bind(("127.0.0.1", 0))
            port = first.getsockname()[1]
            if port >= 65535:
                continue
            with socket.socket() as second:
                try:
                    second.bind(("127.0.0.1", port + 1))
                except OSError:
                    continue
            return port
    raise AssertionError("no free pair of ports")


def start_run(*options: str) -> tuple[subprocess.Popen[str], int, str]:
    """The single-cube run with ``options`` (``--json``): the process, its Foxglove port, its stderr so far."""
    command = [sys.executable, "-m", "bt_arrange.cli", "run", str(ROOT / "trees" / "single_cube.py"), "--json"]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        [*command, *options], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env
    )
    assert process.stderr is not None
    said = ""
    for line in process.stderr:
        said += line
        match = SERVING.search(line)
        if match:
            return process, int(match.group(1)), said
    process.wait(timeout=TIMEOUT_S)
    raise AssertionError(f"the run never served (exit {process.returncode})")


def finish(process: subprocess.Popen[str]) -> tuple[int, dict, str]:
    out, err = process.communicate(timeout=TIMEOUT_S)
    return process.returncode, json.loads(out.splitlines()[-1]), err


async def watch(port: int, topics: tuple[str, ...]) -> dict[str, list]:
    """Subscribe to ``topics``; the messages decoded (by the schemas advertised) until each topic had one."""
    decoders = DecoderFactory()
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS) as client:
        channels: dict[str, dict] = {}
        while not set(topics) <= set(channels):
            message = json.loads(await asyncio.wait_for(client.recv(), 10))
            if message["op"] == "advertise":
                channels.update({channel["topic"]: channel for channel in message["channels"]})
        subscriptions = [{"id": i, "channelId": channels[topic]["id"]} for i, topic in enumerate(topics)]
        await client.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
        decode = {}
        for i, topic in enumerate(topics):
            channel = channels[topic]
            schema = Schema(
                id=i + 1, name=channel["schemaName"], encoding="protobuf", data=base64.b64decode(channel["schema"])
            )
            decode[i] = decoders.decoder_for("protobuf", schema)
        received: dict[str, list] = {topic: [] for topic in topics}
        while not all(received.values()):
            data = await asyncio.wait_for(client.recv(), 20)
            if isinstance(data, bytes) and data[0] == 1:  # message data: opcode, subscription, log time, payload
                subscription, log_time_ns = struct.unpack_from("<IQ", data, 1)
                received[topics[subscription]].append((log_time_ns, decode[subscription](data[13:])))
        return received


async def misbehave(port: int) -> list[dict]:
    """A client that advertises a topic to publish into the run, then sends garbage: the statuses it got back."""
    statuses = []
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=SUBPROTOCOLS) as client:
        advertise = {"id": 1, "topic": "/cmd", "encoding": "json", "schemaName": "cmd"}
        await client.send(json.dumps({"op": "advertise", "channels": [advertise]}))
        await client.send(json.dumps({"op": "callService", "serviceId": 1, "callId": 1, "encoding": "json"}))
        await client.send("{ not json")
        await client.send(b"\x01\x00\x00\x00\x01garbage")  # a data message on a channel never granted
        try:
            while len(statuses) < 3:
                message = await asyncio.wait_for(client.recv(), 5)
                if isinstance(message, str) and json.loads(message)["op"] == "status":
                    statuses.append(json.loads(message))
        except (TimeoutError, websockets.ConnectionClosed):
            pass
    return statuses


@pytest.fixture(scope="module")
def unwatched() -> dict:
    """The same run with no server: what a watched run must end as."""
    result = subprocess.run(
        [sys.executable, "-m", "bt_arrange.cli", "run", str(ROOT / "trees" / "single_cube.py"), "--json"],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.splitlines()[-1])


def same_outcome(report: dict, other: dict) -> None:
    keep = ("name", "status", "final_offset_mm", "final_offset_truth_mm", "pushes")
    assert [{k: o[k] for k in keep} for o in report["objects"]] == [{k: o[k] for k in keep} for o in other["objects"]]
    assert report["sim_seconds"] == other["sim_seconds"] and report["tree_status"] == other["tree_status"]


def test_a_client_watches_a_paced_run_and_a_client_that_publishes_is_refused(unwatched) -> None:  # noqa: ANN001
    process, port, _ = start_run("--pace", "1", "--foxglove", "0")
    try:
        received = asyncio.run(watch(port, ("/tf", "/camera/image")))
        statuses = asyncio.run(misbehave(port))
    finally:
        code, report, err = finish(process)
    assert code == 0, err
    frames = {t.child_frame_id for _, message in received["/tf"] for t in message.transforms}
    assert {"base_link", "tcp", "camera", "red"} <= frames
    image = received["/camera/image"][0][1]
    assert image.format == "png" and image.data.startswith(b"\x89PNG")
    assert all(status["level"] == 2 for status in statuses) and statuses, statuses
    assert any("clientPublish" in status["message"] for status in statuses)
    same_outcome(report, unwatched)


def test_groot2_and_foxglove_at_once(unwatched) -> None:  # noqa: ANN001
    groot = free_port_pair()
    process, port, said = start_run("--pace", "2", "--groot", str(groot), "--foxglove", "0")
    try:
        received = asyncio.run(watch(port, ("/tf",)))
    finally:
        code, report, err = finish(process)
    assert code == 0, err
    assert f"serving the tree to Groot2 on tcp://127.0.0.1:{groot}" in said, said
    assert received["/tf"]
    same_outcome(report, unwatched)


def test_foxglove_options_are_one_line_errors(tmp_path) -> None:  # noqa: ANN001
    run = [sys.executable, "-m", "bt_arrange.cli", "run", str(ROOT / "trees" / "single_cube.py")]
    for options, said in (
        (["--foxglove-bind", "0.0.0.0"], "--foxglove-bind serves a run to Foxglove only with --foxglove"),
        (["--foxglove", "70000"], "out of range"),
        (["--foxglove", "x"], "is not a port number"),
    ):
        result = subprocess.run([*run, *options], capture_output=True, text=True, timeout=TIMEOUT_S, cwd=ROOT)
        assert result.returncode == 2 and said in result.stderr, result.stderr
        assert "Traceback" not in result.stderr
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run(
            [*run, "--foxglove", str(port), "--record", str(tmp_path / "r")],
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            cwd=ROOT,
        )
    assert result.returncode == 2 and f"cannot serve Foxglove on 127.0.0.1:{port}" in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and not (tmp_path / "r" / "replay.html").exists()
