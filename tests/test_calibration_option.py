"""``--calibration``: every bad file is one line and exit 2 before anything moves; a campaign keeps one calibration.

Each bad file is tried through the command line (``run`` and ``experiment``), and through
``read_calibration`` where the reader alone decides. ``experiment --resume`` (and any rerun) refuses
a folder begun with another calibration file, or with this one before it was changed in place.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bt_arrange import cli
from bt_arrange.calibration import CameraCalibration, read_calibration, rpy_matrix, write_calibration
from bt_arrange.errors import PlanError
from bt_arrange.filelimits import MAX_FILE_BYTES
from bt_arrange.geometry import Pose
from bt_arrange.robot import CameraIntrinsics


def _calibration(width_px: int = 1920, height_px: int = 1080) -> CameraCalibration:
    rotation = rpy_matrix(math.radians(180.0), 0.0, math.radians(-93.0))
    return CameraCalibration(
        intrinsics=CameraIntrinsics(width_px, height_px, 1371.0, 1371.0, (width_px - 1) / 2, (height_px - 1) / 2),
        camera_to_base=Pose.from_rotation([0.5, 0.0, 0.7], rotation),
        reprojection_error_px=0.1,
        views=20,
        cell="real",
        date="2026-12-01T10:00:00+00:00",
    )


def _good(tmp_path: Path, name: str = "camera.toml") -> Path:
    return write_calibration(_calibration(), tmp_path / name)


def _bad_files(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    """Each kind of bad file, with what its one line must say."""
    good = _good(tmp_path, "good.toml").read_text()
    files = {}

    def add(name: str, content: bytes | str, says: str) -> None:
        path = tmp_path / f"{name}.toml"
        (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
        files[name] = (path, says)

    add("not_utf8", b'cell = "\xff\xfe"\n', "is not UTF-8 text")
    add("too_large", good + "#" * (MAX_FILE_BYTES + 1) + "\n", "over the limit of 1,048,576 bytes")
    add("missing_key", good.replace("views = 20\n", ""), "views is missing")
    add("nan_focal", good.replace("fx_px = 1371.000000", "fx_px = nan"), "fx_px = nan must be a finite number")
    add("negative_focal", good.replace("fy_px = 1371.000000", "fy_px = -1371"), "fy_px = -1371 must be positive")
    other = write_calibration(_calibration(1280, 720), tmp_path / "other_size.toml")
    files["other_size"] = (other, "the calibration is for 1280x720 px images, the camera takes 1920x1080 px")
    return files


def test_the_reader_words_every_bad_file_in_one_line(tmp_path: Path) -> None:
    for name, (path, says) in _bad_files(tmp_path).items():
        if name == "other_size":
            continue  # a valid file: only the camera it is used with can refuse it
        with pytest.raises(PlanError) as raised:
            read_calibration(path)
        assert says in str(raised.value) and "\n" not in str(raised.value), (name, str(raised.value))


@pytest.mark.parametrize("command", ["run", "experiment"])
def test_every_bad_calibration_file_is_one_line_and_exit_2_before_anything_moves(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, command: str
) -> None:
    # Nothing may move: a world built, or a trial begun, fails the test.
    from bt_arrange_sim.experiment import campaign
    from bt_arrange_sim.pybullet.runs import SimulatedRun

    def moved(*args: object, **kwargs: object) -> None:
        raise AssertionError("the world was built or a trial ran before the calibration was checked")

    monkeypatch.setattr(SimulatedRun, "open_world", staticmethod(moved))
    monkeypatch.setattr(campaign, "run_trial", moved)
    for name, (path, says) in _bad_files(tmp_path).items():
        if command == "run":
            argv = ["run", "four_cubes", "--calibration", str(path)]
        else:
            argv = ["experiment", "--trials", "1", "--calibration", str(path), "--out", str(tmp_path / f"out-{name}")]
        code = cli.main(argv)
        captured = capsys.readouterr()
        assert code == 2, (name, captured.err)
        assert captured.err.count("\n") == 1 and "Traceback" not in captured.err, (name, captured.err)
        assert captured.err.startswith(f"bt-arrange: error: --calibration {path}: "), (name, captured.err)
        assert says in captured.err, (name, captured.err)
        assert captured.out == "", (name, "nothing is printed before the error")


def _quick_trial(spec):  # noqa: ANN001, ANN202 - a TrialSpec, a record
    """A trial's record without a world (what the campaign's files need)."""
    return {
        **spec.record_fields(),
        "target": [0.5, 0.0, 0.0],
        "placed_mm": 2.0,
        "pushed_mm": 0.5,
        "placed_truth_mm": 2.0,
        "pushed_truth_mm": 0.5,
        "pushes": 1,
        "regrasps": 0,
        "status": "within",
    }


def test_a_resume_refuses_a_calibration_changed_in_place_or_another_path_naming_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from bt_arrange_sim.experiment import campaign, run_experiment

    monkeypatch.setattr(campaign, "run_trial", _quick_trial)
    camera = _good(tmp_path)
    out = tmp_path / "campaign"
    run_experiment(["system"], 1, 1, 1.0, out, calibration=str(camera))
    # The same file, unchanged: resumed (and grown by a plain rerun).
    run_experiment(["system"], 1, 1, 1.0, out, calibration=str(camera), resume=True)
    run_experiment(["system"], 2, 1, 1.0, out, calibration=str(camera))
    # Another path, the same content: named.
    other = _good(tmp_path, "other.toml")
    with pytest.raises(PlanError, match=rf"^--resume: {out} holds another campaign: --calibration {camera} there, "
                       rf"{other} asked"):  # fmt: skip
        run_experiment(["system"], 2, 1, 1.0, out, calibration=str(other), resume=True)
    # The same path, changed in place (a new calibration written over it): its content is named.
    write_calibration(_calibration().__class__(**{**_calibration().__dict__, "views": 19}), camera)
    for resume in (True, False):
        with pytest.raises(PlanError, match=r"the calibration file's content \(sha256\) [0-9a-f]{12} there, "):
            run_experiment(["system"], 2, 1, 1.0, out, calibration=str(camera), resume=resume)
    # Without a calibration now: named too.
    with pytest.raises(PlanError, match=rf"--calibration {camera} there, none asked"):
        run_experiment(["system"], 2, 1, 1.0, out, resume=True)


# ----------------------------------------------------------------------------------------------
# write_calibration: the project's atomic writer
# ----------------------------------------------------------------------------------------------


def test_a_calibration_is_written_through_the_atomic_writer_fsynced_under_its_own_temporary_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import os

    synced: list[int] = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (synced.append(fd), real_fsync(fd))[1])
    # Another writer's calibration half-written under the name a fixed temporary name would take.
    other = tmp_path / ".camera.toml.tmp"
    other.write_text("another writer's half")
    path = write_calibration(_calibration(), tmp_path / "camera.toml")
    assert synced, "the content reaches the disk before the rename"
    assert other.read_text() == "another writer's half", "another writer's temporary file is not taken"
    assert read_calibration(path).intrinsics == _calibration().intrinsics
    assert sorted(p.name for p in tmp_path.iterdir()) == [".camera.toml.tmp", "camera.toml"], "no temporary left"


def test_two_calibrations_written_at_once_do_not_collide(tmp_path: Path) -> None:
    import threading

    from bt_arrange import files

    path = tmp_path / "camera.toml"
    names: list[str] = []
    real_temp_name = files.temp_name
    both_named = threading.Barrier(2)

    def temp_name(target: Path) -> Path:
        name = real_temp_name(target)
        names.append(name.name)
        both_named.wait(timeout=30)  # both writers hold their temporary names at the same moment
        return name

    errors: list[BaseException] = []

    def write(views: int) -> None:
        try:
            write_calibration(CameraCalibration(**{**_calibration().__dict__, "views": views}), path)
        except BaseException as error:  # noqa: BLE001 - kept for the assertion below
            errors.append(error)

    files.temp_name, saved = temp_name, files.temp_name
    try:
        writers = [threading.Thread(target=write, args=(views,)) for views in (20, 21)]
        for writer in writers:
            writer.start()
        for writer in writers:
            writer.join(timeout=60)
    finally:
        files.temp_name = saved
    assert errors == [] and len(set(names)) == 2, (errors, names)
    assert read_calibration(path).views in (20, 21), "one of the two, whole"
    assert [p.name for p in tmp_path.iterdir()] == ["camera.toml"]


def test_a_full_disk_while_writing_the_calibration_exits_3_naming_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import contextlib
    from types import SimpleNamespace

    from diskfaults import FullDisk

    from bt_arrange import cli_calibrate, files
    from bt_arrange.errors import RecordError

    out = tmp_path / "camera.toml"
    out.write_text("the old calibration\n")
    monkeypatch.setattr(files, "_write", FullDisk(100))
    with pytest.raises(RecordError, match=rf"^cannot write the calibration file {out}: No space left on device$"):
        write_calibration(_calibration(), out)
    assert out.read_text() == "the old calibration\n" and len(list(tmp_path.iterdir())) == 1, "old file, no temp"

    outcome = SimpleNamespace(calibration=_calibration(), reason="", poses=20, unreachable=0, not_seen=0)
    run = SimpleNamespace(tick_hooks=[], run=lambda: outcome, elapsed_s=lambda: 0.0)
    backend = SimpleNamespace(name="fake", open_calibration=lambda **options: contextlib.nullcontext(run))
    monkeypatch.setattr(cli_calibrate, "backends", SimpleNamespace(load=lambda name=None: backend))
    code = cli.main(["calibrate", "--out", str(out)])
    captured = capsys.readouterr()
    assert code == 3
    assert captured.err == f"bt-arrange: error: cannot write the calibration file {out}: No space left on device\n"
    assert "intrinsics: fx 1371.00" in captured.out, "what was found is printed"
    assert out.read_text() == "the old calibration\n"
