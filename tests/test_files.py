"""``bt_arrange.files``: every file whole or absent, logs of whole lines, and the faults named, on a disk that fills."""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys

import pytest
from diskfaults import full_disk  # noqa: F401 - a fixture

from bt_arrange import files


def test_a_file_that_does_not_fit_is_absent_or_the_old_one_and_no_temporary_file_is_left(tmp_path, full_disk):  # noqa: F811
    page = tmp_path / "replay.html"
    full_disk(100)
    with pytest.raises(OSError) as raised:
        files.write_text(page, "x" * 1000)
    assert raised.value.errno == errno.ENOSPC
    assert not page.exists() and list(tmp_path.iterdir()) == [], "absent, and no temporary file"
    full_disk(10_000).free()
    files.write_text(page, "old page\n")
    full_disk(5)
    with pytest.raises(OSError):
        files.write_text(page, "a new page, longer than the room left\n")
    assert page.read_text() == "old page\n", "the old file stays whole"
    assert [p.name for p in tmp_path.iterdir()] == ["replay.html"]


def test_a_written_file_has_the_usual_permissions_and_json_ends_with_a_newline(tmp_path):
    path = files.write_json(tmp_path / "report.json", {"a": 1})
    assert json.loads(path.read_text()) == {"a": 1} and path.read_text().endswith("\n")
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_an_append_the_disk_cuts_short_is_taken_back_to_the_last_whole_line(tmp_path, full_disk):  # noqa: F811
    log = tmp_path / "trials.jsonl"
    files.append_lines(log, ['{"trial": 0}', '{"trial": 1}'])
    before = log.read_bytes()
    disk = full_disk(7)  # room for half of the next line
    with pytest.raises(OSError):
        files.append_lines(log, ['{"trial": 2, "status": "within"}'])
    assert disk.written == 7 and log.read_bytes() == before, "the half line is taken back"
    # A log that this append created and could not write into is absent, not empty.
    with pytest.raises(OSError):
        files.append_lines(tmp_path / "new.jsonl", ['{"trial": 0}'])
    assert not (tmp_path / "new.jsonl").exists()


def test_an_append_into_a_removed_folder_fails_rather_than_writing_into_a_deleted_file(tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    files.append_lines(folder / "trials.jsonl", ["{}"])
    (folder / "trials.jsonl").unlink()
    folder.rmdir()
    with pytest.raises(FileNotFoundError):
        files.append_lines(folder / "trials.jsonl", ["{}"])


def test_a_line_log_stops_at_its_first_fault_with_whole_lines_only(tmp_path, full_disk):  # noqa: F811
    log = files.LineLog(tmp_path / "transitions.jsonl")
    assert log.write(["one", "two"])
    disk = full_disk(5)
    assert not log.write(["three", "four"]) and log.fault is not None and log.fault.errno == errno.ENOSPC
    disk.free()
    assert not log.write(["five"]), "no line after the fault: the file is a prefix, never a log with a gap"
    assert (tmp_path / "transitions.jsonl").read_text() == "one\ntwo\n"
    # Closed and written again (no fault), it goes on where it was rather than emptying itself.
    again = files.LineLog(tmp_path / "again.jsonl")
    again.write(["a"])
    again.close()
    again.write(["b"])
    assert (tmp_path / "again.jsonl").read_text() == "a\nb\n"


def test_a_torn_last_line_is_cut_off_and_stale_temporary_files_of_dead_processes_removed(tmp_path):
    log = tmp_path / "trials.jsonl"
    log.write_bytes(b'{"trial": 0}\n{"trial": 1}\n{"tri')
    assert files.repair_lines(log) == len('{"tri') and log.read_bytes() == b'{"trial": 0}\n{"trial": 1}\n'
    assert files.repair_lines(log) == 0
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = tmp_path / f".fig4.png.{int(dead.stdout)}.0123abcd.tmp"
    live = tmp_path / f".fig4.png.{os.getpid()}.0123abcd.tmp"
    stale.write_bytes(b"half")
    live.write_bytes(b"being written")
    assert files.remove_stale_temps(tmp_path) == [stale]
    assert live.exists() and not stale.exists()


def test_faults_are_one_line_naming_the_first_file_its_cause_and_how_many_more():
    faults = files.Faults()
    with faults.guard("/r/replay.html"):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    with faults.guard("/r/report.json"):
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT))
    with faults.guard("/r/fig4.png"):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))
    assert faults.message() == "cannot write /r/replay.html: No space left on device (and 2 more files)"
    assert [f.cause for f in faults.faults[1:]] == [
        "its folder no longer exists",
        "Read-only file system (the folder is read-only)",
    ]
    assert "\n" not in faults.message()
