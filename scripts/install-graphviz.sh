#!/usr/bin/env bash
# Kept for old instructions: the set-up script installs Graphviz and the other system packages.
exec bash "$(dirname "$0")/setup-system.sh" "$@"
