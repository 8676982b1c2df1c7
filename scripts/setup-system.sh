#!/usr/bin/env bash
# System packages the test suite and the pictures use, installed when missing:
#   graphviz  `dot` draws trees as PNG/SVG (bt-arrange show --format png|svg)
#   chromium  a headless browser, for the replay page's test
# Both are optional: when one cannot be installed this script says so on stderr and still exits 0,
# so the test command goes on (the tests that need the tool skip, saying why).
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
set -uo pipefail

packages="${SETUP_PACKAGES:-graphviz:dot chromium:chromium}"
tries="${SETUP_APT_TRIES:-10}"
wait_s="${SETUP_APT_WAIT_S:-15}"
lock_timeout_s="${SETUP_LOCK_TIMEOUT_S:-120}"
lists="${SETUP_APT_LISTS:-/var/lib/apt/lists}"

# Messages go to the caller's stderr (fd 3) even where apt-get's own output is silenced.
exec 3>&2
say() { echo "setup-system: $*" >&3; }

missing=()
for entry in $packages; do
    package="${entry%%:*}"
    command="${entry#*:}"
    command -v "$command" >/dev/null 2>&1 || missing+=("$package")
done
[ "${#missing[@]}" -eq 0 ] && exit 0

if ! command -v apt-get >/dev/null 2>&1; then
    if command -v brew >/dev/null 2>&1; then
        for package in "${missing[@]}"; do
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
