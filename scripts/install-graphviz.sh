#!/usr/bin/env bash
# Graphviz's `dot` draws trees as PNG/SVG (bt-arrange show --format png|svg). It is a system
# package, not a Python one: install it when missing; say clearly how when this script cannot.
set -euo pipefail
if command -v dot >/dev/null 2>&1; then
    exit 0
fi
if command -v apt-get >/dev/null 2>&1; then
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
            echo "install-graphviz: not root and no sudo: run 'apt-get install graphviz' as root" >&2; exit 0
        fi
    fi
    $sudo apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq graphviz >/dev/null
    echo "install-graphviz: installed $(dot -V 2>&1)"
elif command -v brew >/dev/null 2>&1; then
    brew install graphviz
else
    echo "install-graphviz: install Graphviz with your system's package manager for PNG/SVG tree pictures;" \
         "everything else works without it" >&2
fi
