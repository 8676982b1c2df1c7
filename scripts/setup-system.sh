#!/usr/bin/env bash
# System packages the test suite and the pictures use, installed when missing:
#   graphviz  `dot` draws trees as PNG/SVG (bt-arrange show --format png|svg)
#   chromium  a headless browser, for the replay page's test
#   libosmesa6  OSMesa, MuJoCo's headless OpenGL (--backend mujoco renders through MUJOCO_GL=osmesa)
# All are optional: when one cannot be installed this script says so on stderr and still exits 0,
# so the test command goes on (the tests that need the tool skip, saying why).
#
# Each entry is "package:check": the check is a command found with `command -v`, or, for a
# package of libraries only, "lib:NAME": a shared library whose file name starts with NAME, found
# in `ldconfig -p` or in the library folders.
#
# It survives a busy package manager: apt-get waits for the dpkg lock itself
# (-o DPkg::Lock::Timeout), and a run that still finds a lock held (exit 100 and a lock message;
# `apt-get update` takes the lists lock, which that option may not cover) is retried a bounded
# number of times. `apt-get update` runs only when the package lists are empty or a package is not
# found in them.
#
# Environment (for tests and unusual machines):
#   SETUP_PACKAGES       "package:command ..." to install instead of the default list
#   SETUP_APT_TRIES      attempts per apt-get command while a lock is held (default 10)
#   SETUP_APT_WAIT_S     seconds between attempts (default 15)
#   SETUP_LOCK_TIMEOUT_S seconds apt-get itself waits for the dpkg lock (default 120)
#   SETUP_APT_LISTS      the package lists folder (default /var/lib/apt/lists)
#   SETUP_LIB_DIRS       folders searched for a "lib:NAME" check besides ldconfig's cache
#   SETUP_LDCONFIG       the ldconfig to ask (default: the one on PATH, else /sbin/ldconfig)
set -uo pipefail

packages="${SETUP_PACKAGES:-graphviz:dot chromium:chromium libosmesa6:lib:libOSMesa.so}"
tries="${SETUP_APT_TRIES:-10}"
wait_s="${SETUP_APT_WAIT_S:-15}"
lock_timeout_s="${SETUP_LOCK_TIMEOUT_S:-120}"
lists="${SETUP_APT_LISTS:-/var/lib/apt/lists}"
lib_dirs="${SETUP_LIB_DIRS:-/usr/lib /usr/lib64 /usr/local/lib /lib /usr/lib/x86_64-linux-gnu /usr/lib/aarch64-linux-gnu}"
ldconfig="${SETUP_LDCONFIG:-$(command -v ldconfig 2>/dev/null || echo /sbin/ldconfig)}"

# Messages go to the caller's stderr (fd 3) even where apt-get's own output is silenced.
exec 3>&2
say() { echo "setup-system: $*" >&3; }

# A "lib:NAME" check: a library file whose name starts with NAME, in ldconfig's cache or a library folder.
library_present() {
    local name="$1" dir
    if [ -x "$ldconfig" ] && "$ldconfig" -p 2>/dev/null | grep -q "^[[:space:]]*$name"; then
        return 0
    fi
    for dir in $lib_dirs; do
        compgen -G "$dir/$name*" >/dev/null && return 0
    done
    return 1
}

present() {
    case "$1" in
        lib:*) library_present "${1#lib:}" ;;
        *) command -v "$1" >/dev/null 2>&1 ;;
    esac
}

missing=()
for entry in $packages; do
    package="${entry%%:*}"
    check="${entry#*:}"
    present "$check" || missing+=("$package")
done
[ "${#missing[@]}" -eq 0 ] && exit 0

if ! command -v apt-get >/dev/null 2>&1; then
    if command -v brew >/dev/null 2>&1; then
        for package in "${missing[@]}"; do
            # OSMesa is Debian's way to render headless; macOS renders MuJoCo through CGL.
            [ "$package" = libosmesa6 ] && continue
            [ "$package" = chromium ] && package="--cask chromium"
            # shellcheck disable=SC2086
            brew install $package || say "could not install $package with brew; the tests that need it will skip"
        done
    else
        say "install ${missing[*]} with your system's package manager; everything else works without them"
    fi
    exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        sudo="sudo"
    else
        say "not root and no sudo: run 'apt-get install ${missing[*]}' as root; the tests that need them will skip"
        exit 0
    fi
fi

# apt-get with the lock timeout, retried while another apt/dpkg process holds a lock.
# Prints apt-get's output on failure; returns its exit status.
apt() {
    local attempt=1 output status
    while true; do
        output="$(DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout="$lock_timeout_s" -qq "$@" 2>&1)"
        status=$?
        [ "$status" -eq 0 ] && return 0
        if [ "$status" -eq 100 ] && grep -qiE "could not get lock|unable to acquire|unable to lock|is another process using it" <<<"$output"; then
            if [ "$attempt" -lt "$tries" ]; then
                say "another apt or dpkg process holds the lock; waiting ${wait_s} s (attempt $attempt of $tries)"
                sleep "$wait_s"
                attempt=$((attempt + 1))
                continue
            fi
            say "the apt lock was still held after $tries attempts"
        fi
        printf '%s\n' "$output" >&2
        return "$status"
    done
}

updated=0
update() {
    [ "$updated" -eq 1 ] && return 0
    updated=1
    apt update >/dev/null || say "apt-get update failed; trying with the package lists there are"
}

# Fresh images ship without package lists: nothing can be found until they are fetched.
if ! compgen -G "$lists/*Packages*" >/dev/null; then
    update
fi
installed=()
for package in "${missing[@]}"; do
    if apt install -y --no-install-recommends "$package" >/dev/null 2>&1; then
        installed+=("$package")
        continue
    fi
    # Not found (or stale lists): fetch the lists once, then try again.
    update
    if apt install -y --no-install-recommends "$package" >/dev/null; then
        installed+=("$package")
    else
        say "could not install $package; the tests that need it will skip"
    fi
done
[ "${#installed[@]}" -gt 0 ] && say "installed ${installed[*]}"
exit 0
