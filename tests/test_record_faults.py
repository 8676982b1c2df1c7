"""A recorded run on a machine that fails it: the disk fills, the folder is removed or made read-only.

The run goes on, every file of ``--record`` is whole or absent, and the command prints the report,
then one line naming the file and the cause, and exits 3 ("the run finished, its record did not").
The world is ``tests/fakeworld.py``'s (no simulator); the disk is ``tests/diskfaults.py``'s: an
ENOSPC after N bytes, or a real small tmpfs where this machine lets the test mount one.
"""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from pathlib import Path

import pytest
from diskfaults import assert_whole, full_disk, make_read_only, small_tmpfs  # noqa: F401 - full_disk: a fixture
from fakeworld import FakeBackend, FakeWorld, camera_view

from bt_arrange import backends, cli
from bt_arrange.errors import RecordError
from bt_arrange.objects import ObjectStart
from bt_arrange.runner import Transition
from bt_arrange.session import Session
from bt_arrange.trees import Target, arrangement

RED, GREEN = Target("red", 0.50, 0.05), Target("green", 0.50, -0.05)
STARTS = [ObjectStart("red", 0.42, -0.22, 0.1), ObjectStart("green", 0.58, -0.22, 0.1)]
RECORD = ("after_placing_green.png", "after_placing_red.png", "after_pushing.png", "before_picking.png")
RECORD += ("replay.html", "report.json", "transitions.jsonl", "run.mcap")


def recorded_run(folder: Path, hook=None):  # noqa: ANN001, ANN201 - a transition hook; the report
    """Two cubes recorded into ``folder``; the report, or the ``RecordError`` carrying it."""
    with Session(arrangement([RED, GREEN]), STARTS, FakeWorld, view=camera_view(), record_dir=folder) as run:
        if hook is not None:
            run.transition_hooks.append(lambda transition: hook(run, transition))
        try:
            return run.run()
        except RecordError as error:
            return error


def test_a_full_record_is_written_whole_and_raises_nothing(tmp_path, full_disk):  # noqa: F811
    disk = full_disk(1 << 40)
    report = recorded_run(tmp_path)
    assert not isinstance(report, RecordError) and report.all_within_threshold
    assert assert_whole(tmp_path) == sorted(RECORD)
    assert disk.written == sum(p.stat().st_size for p in tmp_path.iterdir()), "every byte went through bt_arrange.files"


@pytest.fixture(scope="module")
def whole(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same run's record on a disk with room."""
    folder = tmp_path_factory.mktemp("whole")
    recorded_run(folder)
    return folder


@pytest.mark.parametrize("share", [0.0, 0.05, 0.3, 0.6, 0.9, 0.99])
def test_a_disk_that_fills_mid_run_leaves_every_file_whole_or_absent_and_the_report_intact(
    tmp_path,
    full_disk,  # noqa: F811
    whole,
    share,
):
    size = sum(p.stat().st_size for p in whole.iterdir())
    folder = tmp_path / "full"
    folder.mkdir()
    disk = full_disk(int(size * share))
    error = recorded_run(folder)
    assert isinstance(error, RecordError), "the record did not fit: the run says so"
    assert disk.failures >= 1
    report = error.result
    assert report.tree_status == "SUCCESS" and report.all_within_threshold, "the run itself went on to the end"
    message = str(error)
    assert "\n" not in message and message.startswith(f"cannot write {folder}/")
    assert "No space left on device" in message and message.endswith("the run finished, its record did not")
    names = assert_whole(folder)
    assert set(names) < set(RECORD), "what is there is whole; what did not fit is absent"
    for name in names:  # a file that is there is the same file as on a disk with room
        if name.endswith(".png"):
            assert (folder / name).read_bytes() == (whole / name).read_bytes()
    if "transitions.jsonl" in names:
        assert len((folder / "transitions.jsonl").read_text().splitlines()) == len(report.transitions)
    assert {str(fault.path.name) for fault in error.faults} == set(RECORD) - set(names)


def test_a_record_folder_removed_mid_run_is_one_fault_and_the_report_is_intact(tmp_path):
    folder = tmp_path / "record"

    def remove_after_the_first_place(run: Session, transition: Transition) -> None:
        if transition.kind == "Place" and transition.new == "SUCCESS" and folder.exists():
            shutil.rmtree(folder)

    error = recorded_run(folder, remove_after_the_first_place)
    assert isinstance(error, RecordError) and error.result.all_within_threshold
    assert "its folder no longer exists" in str(error) and str(error).startswith(f"cannot write {folder}/")
    assert not folder.exists(), "nothing is written back into a folder the user removed"


def test_a_record_folder_made_read_only_mid_run_on_a_real_tmpfs(tmp_path):
    with small_tmpfs(tmp_path / "mnt", "1m") as mount:
        folder = mount / "record"

        def read_only_after_the_first_place(run: Session, transition: Transition) -> None:
            if transition.kind == "Place" and transition.new == "SUCCESS" and not read_only:
                read_only.append(True)
                make_read_only(folder)

        read_only: list[bool] = []
        error = recorded_run(folder, read_only_after_the_first_place)
        assert isinstance(error, RecordError) and error.result.all_within_threshold
        assert "Read-only file system" in str(error)
        names = assert_whole(folder)
        assert "before_picking.png" in names and "replay.html" not in names


def cli_run(argv: list[str]) -> tuple[int, str, str]:
    backends.register("fake", FakeBackend)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main(argv)
    return code, out.getvalue(), err.getvalue()


def test_run_on_a_150_kb_tmpfs_prints_the_table_then_one_line_and_exits_3(tmp_path):
    """The issue's first try, on the fake backend: four cubes recorded onto a 150 KB file system."""
    with small_tmpfs(tmp_path / "mnt", "150k") as mount:
        folder = mount / "record"
        code, out, err = cli_run(["run", "four_cubes", "--backend", "fake", "--record", str(folder)])
        assert code == 3, err
        (line,) = err.splitlines()
        assert line.startswith(f"bt-arrange: error: cannot write {folder}/replay.html: No space left on device")
        assert "Traceback" not in err
        assert "four_cubes: 4 of 4 objects within 1 mm" in out.splitlines()[-1], "the verdict is printed"
        assert "red" in out and "the record in" in out and "is incomplete" in out
        assert "replay.html" not in assert_whole(folder)


def test_run_json_prints_the_report_and_exits_3_when_the_disk_fills(tmp_path, full_disk):  # noqa: F811
    full_disk(20_000)
    code, out, err = cli_run(["run", "four_cubes", "--backend", "fake", "--record", str(tmp_path), "--json"])
    assert code == 3
    assert json.loads(out)["objects_within"] == 4
    (line,) = err.splitlines()
    assert line.startswith(f"bt-arrange: error: cannot write {tmp_path}/") and "No space left on device" in line
    assert line.endswith("; the run finished, its record did not")
    assert_whole(tmp_path)


def test_exit_status_3_is_in_the_help():
    for command in ([], ["run"], ["experiment"]):
        out = io.StringIO()
        with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
            cli.main([*command, "--help"])
        assert "3" in out.getvalue() and "record did not" in out.getvalue(), command
