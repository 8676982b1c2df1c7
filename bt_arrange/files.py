"""Every file a run or a campaign writes goes through here: complete or absent, never cut short.

- ``write_bytes`` / ``write_text`` / ``write_json``: the whole content to a temporary name in the
  same folder (``.NAME.PID.XXXX.tmp``), flushed to the disk, then renamed over ``NAME``. A full
  disk, a folder removed or made read-only, a process killed mid-write: ``NAME`` is the old file
  or the new one, never half of one, and the temporary file is removed (``remove_stale_temps``
  removes those a killed process left).
- ``append_lines``: whole lines onto a log (``trials.jsonl``), the folder looked up again each
  time (a removed folder is an error, not writes into a deleted file); a write the disk cuts short
  is taken back, so the log never ends in half a line by our doing. ``LineLog`` keeps its file
  open for a log written many times a second (``transitions.jsonl``) and stops at its first fault.
- ``Faults``: what could not be written, one ``WriteFault`` (the file, the cause) each, for the
  "the run finished, its record did not" ending (``bt_arrange.errors.RecordError``, exit 3).

All writes go through ``_write`` (``os.write``), the one seam the tests' full-disk fixture takes.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import secrets
import tempfile
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: The low-level write every helper uses (a test swaps it for one that fills the disk).
_write: Callable[[int, bytes | memoryview], int] = os.write

#: A temporary file of ours: ``.NAME.PID.HEX.tmp``.
_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[0-9a-f]{8}\.tmp$")


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        written = _write(fd, view)
        if written <= 0:  # pragma: no cover - os.write raises rather than writing nothing
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        view = view[written:]


def temp_name(path: Path) -> Path:
    """A temporary name beside ``path`` for this process (hidden, unique)."""
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")


def write_bytes(path: Path | str, data: bytes) -> Path:
    """Write ``data`` to ``path`` whole or not at all (temporary name in the same folder, then rename)."""
    path = Path(path)
    temp = temp_name(path)
    fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, as for open()
    try:
        try:
            _write_all(fd, data)
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(temp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        raise
    _sync_folder(path.parent)
    return path


def write_text(path: Path | str, text: str) -> Path:
    """``write_bytes`` of ``text`` in UTF-8."""
    return write_bytes(path, text.encode("utf-8"))


def shared_temp_file(prefix: str, suffix: str, text: str) -> Path:
    """A file of ``text`` in the temporary directory, named by its content, written once (whole or absent).

    For files other processes may write at the same time with the same content (a URDF, a mesh):
    each writes under its own temporary name and renames, so every reader finds a whole file.
    """
    digest = hashlib.sha1(text.encode()).hexdigest()[:16]
    path = Path(tempfile.gettempdir()) / f"{prefix}{digest}{suffix}"
    if not path.exists():
        write_text(path, text)
    return path


def write_json(path: Path | str, value: Any, *, indent: int | None = 2) -> Path:
    """``value`` as JSON (indented, a newline at the end), whole or not at all."""
    return write_text(path, json.dumps(value, indent=indent) + "\n")


def save_figure(figure: Any, path: Path | str, **options: Any) -> Path:
    """A matplotlib figure as PNG (``figure.savefig`` into memory, then ``write_bytes``)."""
    import io

    buffer = io.BytesIO()
    figure.savefig(buffer, format=Path(path).suffix.lstrip(".") or "png", **options)
    return write_bytes(path, buffer.getvalue())


def _sync_folder(folder: Path) -> None:
    """The rename reaches the disk too (best effort: not every file system lets a folder be synced)."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def append_lines(path: Path | str, lines: Iterable[str]) -> None:
    """Append whole lines (each gets its newline) to ``path``; a write cut short is taken back.

    The file is opened for each call, so a removed folder raises ``FileNotFoundError`` here rather
    than letting the lines go into a deleted file. A log this call created and could not write
    anything into is removed again (absent, not empty).
    """
    data = "".join(line + "\n" for line in lines).encode("utf-8")
    if not data:
        return
    path = Path(path)
    existed = path.exists()
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
    try:
        _append(fd, data, path, created=not existed)
    finally:
        os.close(fd)


def _append(fd: int, data: bytes, path: Path, *, created: bool) -> None:
    size = os.fstat(fd).st_size
    try:
        _write_all(fd, data)
    except OSError:
        # Take back the part that was written: the log ends at its last whole line, as before the call.
        with contextlib.suppress(OSError):
            os.ftruncate(fd, size)
            if created and size == 0:
                os.unlink(path)
        raise


def repair_lines(path: Path | str) -> int:
    """Cut a log back to its last whole line (a process killed mid-write); the bytes dropped.

    Needs no free space (it only shortens the file). Nothing to do for a missing or whole file.
    """
    path = Path(path)
    if not path.exists():
        return 0
    with path.open("rb+") as file:
        data = file.read()
        if not data or data.endswith(b"\n"):
            return 0
        keep = data.rfind(b"\n") + 1
        file.truncate(keep)
    return len(data) - keep


class LineLog:
    """A log of lines kept open (``transitions.jsonl``): whole lines only; it stops at its first fault.

    ``write(lines)`` appends them; an ``OSError`` (a full disk) takes the partial write back, closes
    the file and keeps the error in ``fault``: later lines are not written, so the file holds every
    line up to the fault and none after (``rewrite`` can complete it at the end).
    """

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        self.fault: OSError | None = None
        self._fd: int | None = None
        self._created = False
        self._opened = False

    def write(self, lines: Iterable[str]) -> bool:
        """Append ``lines``; False once a fault stopped the log."""
        if self.fault is not None:
            return False
        data = "".join(line + "\n" for line in lines).encode("utf-8")
        if not data:
            return True
        try:
            if self._fd is None:
                # Emptied when first opened; opened again after a ``close``, it goes on where it was.
                first = not self._opened
                self._created = first and not self.path.exists()
                flags = os.O_WRONLY | os.O_CREAT | (os.O_TRUNC if first else os.O_APPEND)
                self._fd = os.open(self.path, flags, 0o666)
                self._opened = True
            _append(self._fd, data, self.path, created=self._created)
        except OSError as error:
            self.fault = error
            self.close()
            return False
        return True

    def close(self) -> None:
        """Close the file (it stays as written)."""
        if self._fd is not None:
            with contextlib.suppress(OSError):
                os.close(self._fd)
            self._fd = None


def remove_stale_temps(folder: Path | str) -> list[Path]:
    """Remove the temporary files a killed process of ours left in ``folder``; the ones removed.

    Only names of our pattern whose process is gone: a live writer's temporary file stays.
    """
    folder = Path(folder)
    removed: list[Path] = []
    if not folder.is_dir():
        return removed
    for entry in folder.iterdir():
        match = _TEMP.match(entry.name)
        if match is None or _alive(int(match["pid"])):
            continue
        with contextlib.suppress(OSError):
            entry.unlink()
            removed.append(entry)
    return removed


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def cause(error: OSError) -> str:
    """The cause of a failed write in a few words (``No space left on device``; a removed folder said as such)."""
    if error.errno == errno.ENOENT:
        return "its folder no longer exists"
    if error.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        return f"{error.strerror or 'not writable'} (the folder is read-only)"
    return error.strerror or str(error)


@dataclass(frozen=True)
class WriteFault:
    """A file that could not be written, and why."""

    path: Path
    cause: str
    errno: int | None = None

    def __str__(self) -> str:
        return f"cannot write {self.path}: {self.cause}"


@dataclass
class Faults:
    """The files a run or a campaign could not write; each write is tried once, the work goes on.

    ``with faults.guard(path): write_bytes(path, ...)`` keeps an ``OSError`` as a ``WriteFault``
    instead of raising it. ``message()`` is the one line the command prints.
    """

    faults: list[WriteFault] = field(default_factory=list)

    def __bool__(self) -> bool:
        return bool(self.faults)

    def add(self, path: Path | str, error: OSError) -> WriteFault:
        """Note that ``path`` could not be written because of ``error``."""
        fault = WriteFault(Path(path), cause(error), error.errno)
        self.faults.append(fault)
        return fault

    @contextlib.contextmanager
    def guard(self, path: Path | str) -> Iterator[None]:
        """Run the block; an ``OSError`` in it becomes a fault of ``path`` (and the block ends)."""
        try:
            yield
        except OSError as error:
            self.add(path, error)

    def message(self) -> str:
        """One line: the first file and its cause, and how many more could not be written."""
        if not self.faults:
            return ""
        first = self.faults[0]
        more = len({fault.path for fault in self.faults} - {first.path})
        return str(first) + (f" (and {more} more file{'s' if more > 1 else ''})" if more else "")
