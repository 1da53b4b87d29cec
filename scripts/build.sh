#!/usr/bin/env bash
# Configures and builds (Release) into a persistent build folder.
# usage: scripts/build.sh [BUILD_DIR]   (default: build/ in the checkout)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
jobs=${GAM_JOBS:-$(nproc)}
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$jobs"
