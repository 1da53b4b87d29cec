#!/usr/bin/env bash
# All set-up (packages, build) and the whole test suite.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bash "$here/scripts/install-deps.sh"
bash "$here/scripts/build.sh" "$here/build"
cd "$here/build"
ctest --output-on-failure -j "${GAM_JOBS:-$(nproc)}" --timeout 600
