"""Faults of the machine for tests: a disk that fills after N bytes, a real small tmpfs, checks of whole files.

- ``FullDisk`` swaps ``bt_arrange.files._write`` (the one write every file of a run or a campaign goes
  through) for one that writes up to ``budget`` bytes in all, then fails with ``ENOSPC`` as a full
  file system does (a write that crosses the limit writes its first part, then the next one fails).
  ``free()`` gives the room back.
- ``small_tmpfs(path, size)`` mounts a real tmpfs of that size there (root, and a kernel that lets
  this process mount); ``pytest.skip`` with the reason when it cannot.
- ``assert_whole(folder)``: every file in the folder is complete (PNGs to their end chunk, JSON and
  JSON lines parse, the replay page ends with ``</html>``) and no temporary file is left.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_arrange import files


class FullDisk:
    """Writes through ``bt_arrange.files`` fail with ENOSPC once ``budget`` bytes are written (all files)."""

    def __init__(self, budget: int) -> None:
        self.budget = budget
        self.written = 0
        self.failures = 0

    def __call__(self, fd: int, data: bytes | memoryview) -> int:
        room = self.budget - self.written
        if room <= 0:
            self.failures += 1
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        count = os.write(fd, bytes(data[:room]))
        self.written += count
        return count

    def free(self) -> None:
        """The disk has room again."""
        self.budget = 1 << 62


@pytest.fixture
def full_disk(monkeypatch: pytest.MonkeyPatch):  # noqa: ANN201 - a factory of FullDisk
    """``full_disk(n)``: from now on the disk fills after ``n`` more bytes (``FullDisk``)."""

    def fill_after(budget: int) -> FullDisk:
        disk = FullDisk(budget)
        monkeypatch.setattr(files, "_write", disk)
        return disk

    return fill_after


@contextlib.contextmanager
def small_tmpfs(path: Path, size: str) -> Iterator[Path]:
    """A real tmpfs of ``size`` (``64k``) mounted at ``path``, unmounted on leaving; skips when it cannot mount."""
    path.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root; the ENOSPC fixture covers the same paths")
    result = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)], capture_output=True, text=True
    )
    if result.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({result.stderr.strip() or result.returncode})")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], capture_output=True)


def make_read_only(folder: Path) -> None:
    """Make ``folder`` (inside a ``small_tmpfs``, which unmounts it too) read-only from now on, even for root.

    A read-only bind mount of the folder over itself: new files and renames fail with EROFS, as on a
    folder whose permissions were taken away; a file already open for writing stays writable.
    """
    subprocess.run(["mount", "--bind", str(folder), str(folder)], check=True, capture_output=True)
    subprocess.run(["mount", "-o", "remount,bind,ro", str(folder)], check=True, capture_output=True)


def assert_whole(folder: Path) -> list[str]:
    """Every file of ``folder`` is complete, and none is a temporary one; the names found."""
    names = sorted(p.name for p in folder.iterdir()) if folder.exists() else []
    for name in names:
        path = folder / name
        assert not name.endswith(".tmp"), f"a temporary file is left: {name}"
        data = path.read_bytes()
        if name.endswith(".png"):
            assert data.startswith(b"\x89PNG\r\n\x1a\n") and data.endswith(b"IEND\xaeB`\x82"), f"{name} is cut short"
        elif name.endswith(".json"):
            json.loads(data)
        elif name.endswith(".jsonl"):
            assert data.endswith(b"\n"), f"{name} ends in half a line"
            for line in data.splitlines():
                json.loads(line)
        elif name.endswith(".html"):
            assert data.rstrip().endswith(b"</html>"), f"{name} is cut short"
        elif name.endswith(".mcap"):
            magic = b"\x89MCAP0\r\n"
            assert data.startswith(magic) and data.endswith(magic), f"{name} is cut short"
        elif name.endswith((".csv", ".md")):
            assert data.endswith(b"\n"), f"{name} is cut short"
    return names
