#!/usr/bin/env bash
# Configures and builds (Release) into a persistent build folder.
# usage: scripts/build.sh [BUILD_DIR [-DVAR=VALUE ...] [TARGET ...]]
#   BUILD_DIR  default: build/ in the checkout
#   -D...      passed to cmake when configuring (kept in the cache, as usual)
#   TARGET     build only these targets and what they need (default: all)
# e.g. scripts/build.sh build -DGAM_BUILD_TESTS=OFF ground-aware-mapper gam-simulate
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
[ $# -gt 0 ] && shift
jobs=${GAM_JOBS:-$(nproc)}
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
defs=()
targets=()
for a in "$@"; do
  case "$a" in
    -D*) defs+=("$a") ;;
    *) targets+=(--target "$a") ;;
  esac
done
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release "${defs[@]}" >/dev/null
cmake --build "$build" -j "$jobs" "${targets[@]}"
