#!/usr/bin/env bash
# All set-up (all packages, every target) and the whole test suite. After
# run-demo.sh it reuses the demo's objects in build/.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bash "$here/scripts/install-deps.sh" all
bash "$here/scripts/build.sh" "$here/build" -DGAM_BUILD_TESTS=ON
cd "$here/build"
ctest --output-on-failure -j "${GAM_JOBS:-$(nproc)}" --timeout 600
