"""Every ```python block of README.md and docs/ runs as written (a contract), and so does every ```bash
block of our commands that is not marked to skip.

Each block runs alone in a fresh interpreter (``python -c``; ``bash -e`` for a shell block), headless, in a
folder that is the repository root as a user has it (every top-level entry linked, ``docs/`` copied, so
a block may write ``camera.toml``, ``runs/...`` or ``docs/images/...`` without touching the checkout),
within two minutes (of CPU time: other jobs on a shared machine stretch wall time, not that; a block
still running after 10 minutes is stopped). The output a page shows under a block (a ```text block)
must be what it prints; see ``docblocks`` for the markers (``skip:``, ``needs:``, ``output:``).

The blocks run in parallel subprocesses, longest first, started once for the whole module: the
module's wall time is about that of its longest block (README's list of commands), not the sum.
Blocks that serve on one fixed port (Groot2's 1667, Foxglove's 8765) take turns.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import docblocks
import pytest
from docblocks import ROOT, Block

#: The contract: a block runs in under two minutes. Checked as the CPU time the block's processes use
#: (its own and every child's it waited for), which other jobs on the machine do not stretch as they
#: stretch wall time; a block that waits (``--pace 1`` runs the world at real time) waits a bounded time.
BLOCK_LIMIT_CPU_S = 120.0
#: A block still running after this much wall time is stopped (a hang, or a machine far too busy).
BLOCK_STOP_S = 600.0
#: A shell block runs in the suite when every command in it is one of ours.
OUR_COMMANDS = re.compile(r"^(bt-arrange|python)(\s|$)")
#: Blocks that serve on a fixed port wait for each other (the pattern names the port's user).
PORTS = {"groot2": re.compile(r"--groot\b|Groot2Publisher"), "foxglove": re.compile(r"--foxglove\b|foxglove\.start")}
#: Top-level entries a sandbox leaves out (made by runs and builds, never read by a block).
LEFT_OUT = {".git", "runs", "site", "build", "dist", ".pytest_cache", ".hypothesis", ".mypy_cache", ".ruff_cache"}


def _blocks() -> list[Block]:
    return [
        block
        for path in docblocks.pages()
        for block in docblocks.read_page(path).blocks
        if block.language in ("python", "bash", "sh", "shell")
    ]


BLOCKS = _blocks()


def commands(block: Block) -> list[str]:
    """The commands of a shell block: split at newlines, ``&&``, ``||``, ``;`` and ``|`` outside quotes.

    A backslash-newline continues a command, and a ``#`` that starts a word outside quotes starts a comment.
    """
    text = block.code.replace("\\\n", " ")
    found, current, quote, index = [], "", "", 0
    while index < len(text):
        char = text[index]
        if quote:
            quote = "" if char == quote else quote
            current += char
        elif char in "'\"":
            quote = char
            current += char
        elif char == "#" and (not current or current[-1].isspace()):
            while index < len(text) and text[index] != "\n":
                index += 1
            continue
        elif char in "\n;|&":
            found.append(current.strip())
            current = ""
        else:
            current += char
        index += 1
    found.append(current.strip())
    return [command for command in found if command]


def _needs_missing(block: Block) -> str | None:
    """The reason to skip a block whose ``needs:`` tool is not installed, else None."""
    for tool in (block.needs or "").split(","):
        tool = tool.strip()
        if tool == "chromium":
            from bt_arrange import replay

            if replay.find_chromium() is None:
                return "no Chromium found (apt-get install chromium, or bash scripts/setup-system.sh)"
        elif tool and shutil.which(tool) is None:
            return f"{tool} is not installed"
    return None


def _runnable(block: Block) -> bool:
    if block.skip is not None or _needs_missing(block) is not None:
        return False
    return block.language == "python" or all(OUR_COMMANDS.match(command) for command in commands(block))


@dataclass
class Outcome:
    """What one block did."""

    returncode: int | None  # None: stopped after BLOCK_STOP_S
    stdout: str
    stderr: str
    seconds: float  # wall time
    cpu_s: float  # user and system time of the block's processes


def _sandbox(parent: Path) -> Path:
    """A folder that looks like the repository root: entries linked, docs/ copied (a block may write there)."""
    root = Path(tempfile.mkdtemp(dir=parent))
    for entry in ROOT.iterdir():
        if entry.name in LEFT_OUT or entry.name.endswith(".egg-info"):
            continue
        if entry.name == "docs":
            shutil.copytree(entry, root / "docs")
        else:
            (root / entry.name).symlink_to(entry)
    return root


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("DISPLAY", None)  # headless, as the contract says
    env.pop("WAYLAND_DISPLAY", None)
    env["MPLBACKEND"] = "Agg"
    # `python` and `bt-arrange` of the interpreter that runs the suite (a virtualenv's, when it is one).
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    return env


def _run(block: Block, parent: Path, locks: dict[str, threading.Lock]) -> Outcome:
    held = [locks[name] for name, pattern in PORTS.items() if pattern.search(block.code)]
    for lock in held:
        lock.acquire()
    try:
        cwd = _sandbox(parent)
        if block.language == "python":
            command = [sys.executable, "-c", block.code]
        else:
            command = ["bash", "-e", "-o", "pipefail", "-c", block.code]
        output = cwd / ".block-output"
        output.mkdir()
        with open(output / "stdout", "w+") as stdout, open(output / "stderr", "w+") as stderr:
            started = time.monotonic()
            process = subprocess.Popen(
                command,
                cwd=cwd,
                env=_environment(),
                stdin=subprocess.DEVNULL,  # a block never waits for a keyboard
                stdout=stdout,
                stderr=stderr,
                text=True,
                start_new_session=True,  # its own session: stopped whole, its processes found in /proc
            )
            code, cpu_s = _wait(process, started + BLOCK_STOP_S)
            stdout.seek(0)
            stderr.seek(0)
            return Outcome(code, stdout.read(), stderr.read(), time.monotonic() - started, cpu_s)
    finally:
        for lock in held:
            lock.release()


def _session_cpu_s(session: int) -> dict[int, float]:
    """CPU seconds (user and system) of every live process of ``session``, by pid, from /proc (Linux)."""
    found = {}
    tick_s = 1.0 / os.sysconf("SC_CLK_TCK")
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:
            continue  # gone meanwhile
        if int(fields[3]) == session:  # field 6 of proc(5): the session id
            found[int(stat.parent.name)] = (int(fields[11]) + int(fields[12])) * tick_s  # utime, stime
    return found


def _wait(process: subprocess.Popen[str], deadline: float) -> tuple[int | None, float]:
    """The exit code of ``process`` and the CPU time of everything it ran.

    The CPU time is the larger of ``os.wait4``'s (the process and the children it waited for) and the
    sum over every process of its session seen alive (``/proc``, polled): a pool's workers count even
    when nobody waits for them.
    """
    seen: dict[int, float] = {}
    polled_at = 0.0
    while time.monotonic() < deadline:
        pid, status, usage = os.wait4(process.pid, os.WNOHANG)
        if pid == process.pid:
            process.returncode = os.waitstatus_to_exitcode(status)
            return process.returncode, max(usage.ru_utime + usage.ru_stime, sum(seen.values()))
        if Path("/proc/self/stat").exists() and time.monotonic() - polled_at > 0.25:
            for child, cpu_s in _session_cpu_s(process.pid).items():
                seen[child] = max(cpu_s, seen.get(child, 0.0))
            polled_at = time.monotonic()
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)  # the block's own session: it and everything it started
    process.wait()
    return None, sum(seen.values())


def _cost(block: Block) -> int:
    """A rough order, longest first: shell blocks run several commands, and a run costs more than an import."""
    return (len(commands(block)) * 10 if block.language != "python" else 0) + block.code.count("run(")


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory: pytest.TempPathFactory):
    """Every runnable block started at once on a pool of workers; each test waits for its own."""
    parent = tmp_path_factory.mktemp("snippets")
    locks = {name: threading.Lock() for name in PORTS}
    # One more worker than cores: several blocks wait on world time (--pace 1) more than they compute.
    pool = ThreadPoolExecutor(max_workers=(os.cpu_count() or 2) + 1)
    futures: dict[str, Future[Outcome]] = {}
    for block in sorted((b for b in BLOCKS if _runnable(b)), key=_cost, reverse=True):
        futures[block.where] = pool.submit(_run, block, parent, locks)
    yield futures
    pool.shutdown(wait=True, cancel_futures=True)


def _report(block: Block, outcome: Outcome) -> str:
    """What the block printed last (the error first, where a reader looks), then the block itself."""
    tail = "\n".join((outcome.stdout + outcome.stderr).strip().split("\n")[-25:])
    took = f"{outcome.seconds:.0f} s, {outcome.cpu_s:.0f} s of CPU"
    return f"{block.where} ({took}):\n{tail}\n--- the block ---\n{block.code}"


@pytest.mark.parametrize("block", [b for b in BLOCKS if b.language == "python"], ids=lambda b: b.where)
def test_python_block_runs_as_written(block: Block, outcomes) -> None:
    _check(block, outcomes)


@pytest.mark.parametrize("block", [b for b in BLOCKS if b.language != "python"], ids=lambda b: b.where)
def test_shell_block_of_our_commands_runs(block: Block, outcomes) -> None:
    if block.skip is None:
        others = [command for command in commands(block) if not OUR_COMMANDS.match(command)]
        assert not others, (
            f"{block.where} runs {others[0]!r}, not one of our commands: mark the block <!-- skip: REASON --> "
            "(or make it one of bt-arrange ... / python ...)"
        )
    _check(block, outcomes)


def _check(block: Block, outcomes) -> None:
    if block.skip is not None:
        pytest.skip(f"{block.where}: {block.skip}")
    missing = _needs_missing(block)
    if missing:
        pytest.skip(f"{block.where}: {missing}")
    outcome = outcomes[block.where].result()
    assert outcome.returncode is not None, f"stopped after {BLOCK_STOP_S:.0f} s: " + _report(block, outcome)
    assert outcome.returncode == 0, f"exit {outcome.returncode}: " + _report(block, outcome)
    assert outcome.cpu_s < BLOCK_LIMIT_CPU_S, f"{outcome.cpu_s:.0f} s of CPU, over two minutes: " + _report(
        block, outcome
    )
    if block.output is not None and block.output_checked:
        assert docblocks.expected_output_matches(block.output.code, outcome.stdout, block.output_tolerance), (
            f"{block.where} printed\n{outcome.stdout}\nbut {block.output.where} shows\n{block.output.code}"
        )


def test_every_runnable_page_has_blocks() -> None:
    """The collector finds what a reader sees: the pages' Python blocks, and shell blocks that run."""
    python = [b for b in BLOCKS if b.language == "python"]
    assert len(python) >= 20
    assert any(b.page.name == "README.md" for b in python)
    assert sum(_runnable(b) and b.language == "bash" for b in BLOCKS) >= 3


def test_output_blocks_follow_the_block_that_prints_them() -> None:
    """A block that prints shows what it prints, and a shown output belongs to a block that prints."""
    for block in BLOCKS:
        if block.language != "python":
            continue
        if block.output is not None:
            assert "print(" in block.code, f"{block.output.where} shows output, but {block.where} prints nothing"
        elif "print(" in block.code and block.skip is None:
            raise AssertionError(f"{block.where} prints: show what it prints in a ```text block right under it")


def test_the_output_comparison_can_fail() -> None:
    shown = "PlanarPose(x_m=0.45, y_m=0.1, yaw_rad=0.3)\n"
    printed = "PlanarPose(x_m=0.45000100845810614, y_m=0.09999516615974068, yaw_rad=0.2999625959772352)\n"
    assert docblocks.expected_output_matches(shown, printed, 0.0005)
    assert not docblocks.expected_output_matches(shown, printed.replace("0.0999", "0.0989"), 0.0005)
    assert not docblocks.expected_output_matches(shown, printed, 0.0)  # as text, the digits differ
    assert docblocks.expected_output_matches("a\n...\ntook ... s\n", "a\nb\nc\ntook 1.6 s\n")
    assert not docblocks.expected_output_matches("a\n...\ntook ... s\n", "a\nb\nc\ntook 1.6 min\n")
    assert not docblocks.expected_output_matches("4 of 4 within 1 mm\n", "3 of 4 within 1 mm\n")


def test_a_block_that_fails_is_reported(tmp_path: Path) -> None:
    """The runner sees a NameError as a user would: a failing exit, the error in its output."""
    page = tmp_path / "page.md"
    page.write_text("# A page\n\n```python\nprint(root)\n```\n")
    (block,) = docblocks.read_page(page).blocks
    outcome = _run(block, tmp_path, {name: threading.Lock() for name in PORTS})
    assert outcome.returncode == 1
    assert "NameError: name 'root' is not defined" in outcome.stderr
