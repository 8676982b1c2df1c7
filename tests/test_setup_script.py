"""scripts/setup-system.sh: waits for a held apt lock, updates only when needed, never fails the tests.

A fake ``apt-get`` on PATH plays the package manager (the real dpkg lock is never touched): it
logs its arguments, answers as a busy or a working apt would, and "installs" a fake command.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "setup-system.sh"
LOCKED = "E: Could not get lock /var/lib/dpkg/lock-frontend. It is held by process 4242 (apt-get)"

FAKE_APT = """#!/usr/bin/env bash
echo "$*" >> "$FAKE_LOG"
count=$(( $(cat "$FAKE_COUNT" 2>/dev/null || echo 0) + 1 )); echo "$count" > "$FAKE_COUNT"
case " $* " in *" update "*) exit 0 ;; esac
if [ "$count" -le "$FAKE_LOCKED_CALLS" ]; then echo "$FAKE_LOCK_MESSAGE" >&2; exit 100; fi
if [ -n "$FAKE_UNKNOWN" ] && [ ! -e "$FAKE_LISTS/updated" ]; then
    echo "E: Unable to locate package bt-fake-tool" >&2; exit 100
fi
case " $* " in *" bt-fake-lib "*) touch "$FAKE_LIBS/libbtfake.so.1"; exit 0 ;; esac
printf '#!/bin/sh\\n' > "$FAKE_BIN/bt-fake-tool"; chmod +x "$FAKE_BIN/bt-fake-tool"
exit 0
"""

pytestmark = pytest.mark.skipif(shutil.which("bash") is None, reason="the set-up script is a bash script")


def run_script(
    tmp_path: Path,
    *,
    locked_calls: int,
    lists: bool = True,
    unknown: bool = False,
    tries: int = 3,
    packages: str = "bt-fake-tool:bt-fake-tool",
):
    fake_bin = tmp_path / "bin"
    fake_bin.mkdir(exist_ok=True)
    apt = fake_bin / "apt-get"
    apt.write_text(FAKE_APT)
    apt.chmod(0o755)
    (fake_bin / "sudo").write_text('#!/bin/sh\nexec "$@"\n')
    (fake_bin / "sudo").chmod(0o755)
    lists_dir = tmp_path / "lists"
    lists_dir.mkdir(exist_ok=True)
    libs_dir = tmp_path / "libs"
    libs_dir.mkdir(exist_ok=True)
    if lists:
        (lists_dir / "deb.debian.org_debian_dists_bookworm_main_binary-amd64_Packages").write_text("")
    env = {
        "PATH": f"{fake_bin}:/usr/bin:/bin",
        "HOME": str(tmp_path),
        "SETUP_PACKAGES": packages,
        # A library check looks in this folder only, and asks no real ldconfig.
        "SETUP_LIB_DIRS": str(libs_dir),
        "SETUP_LDCONFIG": str(tmp_path / "no-ldconfig"),
        "FAKE_LIBS": str(libs_dir),
        "SETUP_APT_TRIES": str(tries),
        "SETUP_APT_WAIT_S": "0",
        "SETUP_APT_LISTS": str(lists_dir),
        "FAKE_LOG": str(tmp_path / "log"),
        "FAKE_COUNT": str(tmp_path / "count"),
        "FAKE_LOCKED_CALLS": str(locked_calls),
        "FAKE_LOCK_MESSAGE": LOCKED,
        "FAKE_BIN": str(fake_bin),
        "FAKE_LISTS": str(lists_dir),
        "FAKE_UNKNOWN": "1" if unknown else "",
    }
    if unknown:  # the fake's update marks the lists as fresh
        apt.write_text(FAKE_APT.replace('*" update "*) exit 0', '*" update "*) touch "$FAKE_LISTS/updated"; exit 0'))
    result = subprocess.run(["bash", str(SCRIPT)], env=env, capture_output=True, text=True, timeout=60, check=False)
    log = (tmp_path / "log").read_text().splitlines() if (tmp_path / "log").exists() else []
    return result, log, (fake_bin / "bt-fake-tool").exists()


def test_a_held_lock_is_waited_for_and_the_install_retried(tmp_path: Path) -> None:
    result, log, installed = run_script(tmp_path, locked_calls=1)
    assert result.returncode == 0, result.stderr
    assert installed
    assert [line.split()[-1] for line in log] == ["bt-fake-tool", "bt-fake-tool"]  # the same install, twice
    assert all("DPkg::Lock::Timeout=120" in line for line in log)
    assert "holds the lock; waiting 0 s (attempt 1 of 3)" in result.stderr
    assert "installed bt-fake-tool" in result.stderr
    assert not any(" update" in line for line in log)  # the lists were there: no update


def test_a_lock_held_for_ever_gives_up_without_failing_the_test_command(tmp_path: Path) -> None:
    result, log, installed = run_script(tmp_path, locked_calls=99, tries=2)
    assert result.returncode == 0
    assert not installed
    assert "could not install bt-fake-tool; the tests that need it will skip" in result.stderr
    assert 2 <= len(log) <= 6  # bounded: tries per apt-get command, no endless loop


def test_empty_package_lists_are_fetched_first(tmp_path: Path) -> None:
    result, log, installed = run_script(tmp_path, locked_calls=0, lists=False)
    assert result.returncode == 0 and installed
    assert "update" in log[0].split() and "install" in log[1].split()


def test_a_package_missing_from_stale_lists_updates_once_then_installs(tmp_path: Path) -> None:
    result, log, installed = run_script(tmp_path, locked_calls=0, unknown=True)
    assert result.returncode == 0 and installed, result.stderr
    assert [next(w for w in ("update", "install") if w in line.split()) for line in log] == [
        "install",
        "update",
        "install",
    ]


def test_a_missing_library_is_installed_by_its_package(tmp_path: Path) -> None:
    # libosmesa6 has no command: its check is a library file (lib:NAME), found in ldconfig's cache or a folder.
    result, log, _ = run_script(tmp_path, locked_calls=0, packages="bt-fake-lib:lib:libbtfake.so")
    assert result.returncode == 0, result.stderr
    assert [line.split()[-1] for line in log] == ["bt-fake-lib"]
    assert (tmp_path / "libs" / "libbtfake.so.1").exists()
    assert "installed bt-fake-lib" in result.stderr


def test_a_library_already_there_is_not_installed_again(tmp_path: Path) -> None:
    (tmp_path / "libs").mkdir()
    (tmp_path / "libs" / "libbtfake.so.1").write_text("")
    result, log, _ = run_script(tmp_path, locked_calls=0, packages="bt-fake-lib:lib:libbtfake.so")
    assert result.returncode == 0 and result.stderr == ""
    assert log == []


def test_a_library_in_ldconfigs_cache_counts_as_there(tmp_path: Path) -> None:
    fake = tmp_path / "ldconfig"
    fake.write_text("#!/bin/sh\necho '\tlibbtfake.so.2 (libc6,x86-64) => /opt/libbtfake.so.2'\n")
    fake.chmod(0o755)
    env = {**os.environ, "SETUP_PACKAGES": "bt-fake-lib:lib:libbtfake.so", "SETUP_LDCONFIG": str(fake),
           "SETUP_LIB_DIRS": str(tmp_path / "nowhere")}  # fmt: skip
    result = subprocess.run(["bash", str(SCRIPT)], env=env, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0 and result.stderr == ""


def test_the_default_list_installs_osmesa_for_mujoco() -> None:
    assert "libosmesa6:lib:libOSMesa.so" in SCRIPT.read_text()


def test_nothing_is_run_when_every_command_is_there(tmp_path: Path) -> None:
    env = {**os.environ, "SETUP_PACKAGES": "bash:bash"}
    result = subprocess.run(["bash", str(SCRIPT)], env=env, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0 and result.stderr == ""


def test_ci_and_the_readme_call_the_set_up_script() -> None:
    readme_command = "bash scripts/setup-system.sh && pip install -e '.[test]' && python -m pytest -q"
    assert readme_command in (ROOT / "README.md").read_text()
    assert (ROOT / ".ci" / "run").read_text().strip().splitlines()[-1] == readme_command
