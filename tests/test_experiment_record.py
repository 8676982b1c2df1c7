"""``experiment --record DIR``: one MCAP file per trial, read back with the ``mcap`` package; tiny campaigns.

The recording changes no trial's outcome (the records with and without it are the same but for the
wall time and the ``mcap`` key), works on a process pool, on ``--resume`` (finished trials' files
are not rewritten) and with a disk that fills (the trial's measurement kept, the file named, exit 3).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("mcap")
pytest.importorskip("mcap_protobuf")

from mcap.reader import make_reader  # noqa: E402

from bt_arrange import cli, files  # noqa: E402
from bt_arrange.errors import RecordError  # noqa: E402
from bt_arrange_sim.experiment import read_trials, run_experiment  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
ROWS = ["system", "translation"]
TRIALS = 2
SEED = 3
#: What differs between two runs of one trial: the wall time; and with --record, the pointer to its file.
VARYING = ("wall_seconds", "mcap")
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


def by_trial(path: Path) -> dict:
    records = read_trials(path)
    keys = [(r["row"], r["trial"]) for r in records]
    assert len(keys) == len(set(keys)), "a trial recorded twice"
    return {(r["row"], r["trial"]): r for r in records}


def outcome(record: dict) -> dict:
    return {k: v for k, v in record.items() if k not in VARYING}


def read_mcap(path: Path) -> dict[str, list]:
    """Each topic's (schema name, log time, decoded message), in file order."""
    from mcap_protobuf.decoder import DecoderFactory

    decoders = DecoderFactory()
    by_topic: dict[str, list] = defaultdict(list)
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            if channel.message_encoding == "json":
                value = json.loads(message.data)
            else:
                value = decoders.decoder_for(channel.message_encoding, schema)(message.data)
            by_topic[channel.topic].append((schema.name, message.log_time, value))
    return by_topic


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The same campaign recorded on a pool of two workers, and not recorded in this process."""
    base = tmp_path_factory.mktemp("campaigns")
    recorded, plain, record_dir = base / "recorded", base / "plain", base / "mcap"
    run_experiment(ROWS, TRIALS, SEED, 1.0, recorded, workers=2, record=record_dir)
    run_experiment(ROWS, TRIALS, SEED, 1.0, plain)
    return {
        "recorded": by_trial(recorded / "trials.jsonl"),
        "plain": by_trial(plain / "trials.jsonl"),
        "out": recorded,
        "record_dir": record_dir,
    }


def test_the_recording_changes_no_trials_outcome(campaigns: dict) -> None:
    recorded, plain = campaigns["recorded"], campaigns["plain"]
    assert sorted(recorded) == sorted((row, i) for row in ROWS for i in range(TRIALS))
    assert {key: outcome(r) for key, r in recorded.items()} == {key: outcome(r) for key, r in plain.items()}
    assert all("mcap" not in r for r in plain.values()), "no key without --record"
    assert any(r["pushes"] for r in recorded.values()), "a trial that pushes is among them"


def test_one_file_per_trial_by_row_and_number_and_each_record_points_at_its_own(campaigns: dict) -> None:
    record_dir, out = campaigns["record_dir"], campaigns["out"]
    found = sorted(p.relative_to(record_dir).as_posix() for p in record_dir.rglob("*") if p.is_file())
    assert found == [f"{row}/trial-{i:04d}.mcap" for row in ROWS for i in range(TRIALS)]
    for (row, index), record in campaigns["recorded"].items():
        assert not Path(record["mcap"]).is_absolute()
        assert (out / record["mcap"]).resolve() == (record_dir / row / f"trial-{index:04d}.mcap").resolve()


def test_each_file_has_every_topic_and_its_trials_final_transforms_and_report(campaigns: dict) -> None:
    for record in campaigns["recorded"].values():
        topics = read_mcap(campaigns["out"] / record["mcap"])
        assert {topic: topics[topic][0][0] for topic in TOPICS if topic in topics} == TOPICS
        times = [t for messages in topics.values() for _, t, _ in messages]
        assert max(times) / 1e9 == pytest.approx(record["sim_seconds"], abs=0.5), "world time, from the world's start"
        last = {}
        for _, _, value in topics["/tf"]:
            for transform in value.transforms:
                last[transform.child_frame_id] = transform
        part = last["red"]
        x_m, y_m, _ = record["target"]
        offset_mm = math.hypot(part.translation.x - x_m, part.translation.y - y_m) * 1000
        # The record rounds to 0.1 µm, its target to 1 µm.
        assert offset_mm == pytest.approx(record["pushed_truth_mm"], abs=0.01)
        ((_, _, report),) = topics["/report"]
        (reported,) = report["objects"]
        assert reported["final_offset_mm"] == pytest.approx(record["pushed_mm"], abs=1e-4)
        assert reported["pushes"] == record["pushes"]


def test_a_resumed_campaign_rewrites_no_finished_trials_file(tmp_path: Path) -> None:
    out, record_dir = tmp_path / "out", tmp_path / "mcap"
    run_experiment(["system"], 2, SEED, 1.0, out, record=record_dir)
    lines = (out / "trials.jsonl").read_text().splitlines()
    first = record_dir / "system" / "trial-0000.mcap"
    before = first.stat()
    # Killed after trial 0's line: trial 1's line and file are not there.
    (out / "trials.jsonl").write_text(lines[0] + "\n")
    (record_dir / "system" / "trial-0001.mcap").unlink()
    ran = []
    run_experiment(
        ["system"], 2, SEED, 1.0, out, record=record_dir, resume=True, on_trial=lambda r, d, t: ran.append(r["trial"])
    )
    assert ran == [1]
    after = first.stat()
    assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns), "trial 0's file not rewritten"
    records = by_trial(out / "trials.jsonl")
    assert [outcome(records[("system", i)]) for i in (0, 1)] == [outcome(json.loads(line)) for line in lines]
    assert (out / records[("system", 1)]["mcap"]).is_file()


def test_a_disk_that_fills_loses_the_trials_file_not_its_measurement(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    """Full after trial 0, room after trial 1: trial 1's file named, its record kept; --resume redoes it."""
    from diskfaults import FullDisk

    disk = FullDisk(1 << 62)
    monkeypatch.setattr(files, "_write", disk)

    def fill_then_free(record: dict, done: int, total: int) -> None:
        if done == 1:
            disk.budget = disk.written  # full from now on
        elif done == 2:
            disk.free()

    out, record_dir = tmp_path / "out", tmp_path / "mcap"
    with pytest.raises(RecordError) as caught:
        run_experiment(["system"], 3, SEED, 1.0, out, record=record_dir, on_trial=fill_then_free)
    lost = record_dir / "system" / "trial-0001.mcap"
    assert str(caught.value).startswith(f"cannot write {lost}: No space left on device")
    assert str(caught.value).endswith("the campaign finished, its record did not")
    assert [fault.path for fault in caught.value.faults] == [lost]
    records = by_trial(out / "trials.jsonl")
    assert sorted(records) == [("system", 0), ("system", 1), ("system", 2)], "every measurement kept"
    assert records[("system", 1)]["mcap"] is None and records[("system", 1)]["mcap_fault"] == "No space left on device"
    assert records[("system", 1)]["status"] == "within"
    assert [(out / records[("system", i)]["mcap"]).is_file() for i in (0, 2)] == [True, True]
    assert sorted(p.name for p in (record_dir / "system").iterdir()) == ["trial-0000.mcap", "trial-0002.mcap"]

    # Once there is room, --resume with --record runs the trial whose file is missing, and only it.
    ran = []
    run_experiment(
        ["system"], 3, SEED, 1.0, out, record=record_dir, resume=True, on_trial=lambda r, d, t: ran.append(r["trial"])
    )
    assert ran == [1]
    again = by_trial(out / "trials.jsonl")
    assert {key: outcome(r) for key, r in again.items()} == {
        key: {k: v for k, v in outcome(r).items() if k != "mcap_fault"} for key, r in records.items()
    }
    assert all((out / r["mcap"]).is_file() for r in again.values())


#: The command line with the disk full for MCAP files alone (their temporary files), every other file written.
FULL_FOR_MCAP = """
import errno, os, sys
from bt_arrange import cli, files
def write(fd, data):
    name = os.path.basename(os.readlink(f"/proc/self/fd/{fd}"))
    if ".mcap." in name and name.endswith(".tmp"):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return os.write(fd, data)
files._write = write
sys.exit(cli.main(sys.argv[1:]))
"""


def test_the_command_names_the_file_in_one_line_and_exits_3_with_the_table_printed(tmp_path: Path) -> None:
    out, record_dir = tmp_path / "out", tmp_path / "mcap"
    command = [sys.executable, "-c", FULL_FOR_MCAP, "experiment", "--rows", "system", "--trials", "1"]
    command += ["--seed", str(SEED), "--out", str(out), "--record", str(record_dir)]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert result.returncode == 3, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.startswith("bt-arrange")]
    assert lines == [
        f"bt-arrange: error: cannot write {record_dir / 'system' / 'trial-0000.mcap'}: No space left on device; "
        "the campaign finished, its record did not"
    ]
    assert "Traceback" not in result.stderr
    assert "| 1) System accuracy | 1 |" in result.stdout
    (record,) = read_trials(out / "trials.jsonl")
    assert record["mcap"] is None and record["status"] == "within"
    assert list((record_dir / "system").iterdir()) == [], "no file cut short, no temporary file left"


def test_record_without_the_extra_is_one_line_naming_it(tmp_path: Path) -> None:
    without = "import sys\nsys.modules['foxglove'] = None\nfrom bt_arrange import cli\nsys.exit(cli.main(sys.argv[1:]))"
    command = [sys.executable, "-c", without, "experiment", "--rows", "system", "--trials", "1"]
    command += ["--out", str(tmp_path / "out"), "--record", str(tmp_path / "mcap")]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip().splitlines()[-1:] == [
        "bt-arrange: error: --record needs the Foxglove SDK: pip install 'bt-arrange[foxglove]'"
    ]
    assert not (tmp_path / "out" / "trials.jsonl").exists() and not (tmp_path / "mcap").exists()


def test_record_into_a_file_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "taken").write_text("")
    code = cli.main(["experiment", "--rows", "system", "--trials", "1", "--out", str(tmp_path / "out"),
                     "--record", str(tmp_path / "taken")])  # fmt: skip
    assert code == 2
    assert (
        capsys.readouterr().err.strip()
        == f"bt-arrange: error: --record {tmp_path / 'taken'}: it is a file, not a folder"
    )


def test_a_dask_cluster_records_into_the_shared_folder(tmp_path: Path) -> None:
    pytest.importorskip("dask.distributed", reason="the [cluster] extra (dask[distributed]) is not installed")
    out, record_dir = tmp_path / "out", tmp_path / "mcap"
    run_experiment(["system"], 2, SEED, 1.0, out, executor="dask", workers=2, record=record_dir)
    records = by_trial(out / "trials.jsonl")
    for index in (0, 1):
        path = out / records[("system", index)]["mcap"]
        assert path.resolve() == (record_dir / "system" / f"trial-{index:04d}.mcap").resolve()
        assert path.read_bytes().startswith(b"\x89MCAP0\r\n")


def test_a_campaign_of_several_combinations_records_into_their_folders(tmp_path: Path) -> None:
    out, record_dir = tmp_path / "out", tmp_path / "mcap"
    run_experiment(["system"], 1, SEED, 1.0, out, thresholds="0.5,1", record=record_dir)
    found = sorted(p.relative_to(record_dir).as_posix() for p in record_dir.rglob("*.mcap"))
    assert found == ["threshold-0.5mm/system/trial-0000.mcap", "threshold-1mm/system/trial-0000.mcap"]
    for folder in ("threshold-0.5mm", "threshold-1mm"):
        (record,) = read_trials(out / folder / "trials.jsonl")
        assert record["mcap"] == f"../../mcap/{folder}/system/trial-0000.mcap"
        assert (out / folder / record["mcap"]).is_file()
