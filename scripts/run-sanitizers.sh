#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer.
# usage: scripts/run-sanitizers.sh [--quick] [BUILD_DIR]   (default: build-asan/ in the checkout)
#
# --quick (what CI runs): builds only the libraries (ground_core, ground_maps, baseline_maps, ground_mapper),
# ground-aware-mapper, gam-simulate and the suites test_core, test_maps, test_baseline_maps, test_robustness
# and test_mapper, and runs those five executables (not the simulator, evaluator,
# navigation and viewer suites).
#
# Configures BUILD_DIR with -fsanitize=address,undefined -fno-sanitize-recover=all
# -fno-omit-frame-pointer (RelWithDebInfo; compiler: $CXX, default g++), builds it and
# runs ctest there. Any ASan report (overflow, use-after-free, leak) or UBSan report
# fails the test that triggered it.
#
# Leaks: LeakSanitizer is on (detect_leaks=1). tests/sanitizers/lsan.supp suppresses
# leaks whose stack is entirely inside MRPT or other third-party libraries (never this
# project's code); see the comments in that file.
#
# Not run under sanitizers (documented in README "Robustness"):
#  - StockApps.*: they load the instrumented plugin into the stock, uninstrumented MRPT
#    executables (rawlog-edit -p, LD_PRELOAD observations2map), which the ASan runtime
#    refuses ("ASan runtime does not come first").
# Extra ctest arguments can be passed in GAM_SANITIZER_CTEST_ARGS (e.g. "-R Robustness").
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
quick=0
if [ "${1:-}" = "--quick" ]; then quick=1; shift; fi
build=${1:-$here/build-asan}
jobs=${GAM_JOBS:-$(nproc)}
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
san="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"

cmake -S "$here" -B "$build" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER="${CXX:-g++}" \
  -DCMAKE_CXX_FLAGS="$san" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
if [ $quick = 1 ]; then
  cmake --build "$build" -j "$jobs" --target test_core test_maps test_baseline_maps test_robustness test_mapper ground-aware-mapper gam-simulate
else
  cmake --build "$build" -j "$jobs"
fi

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=0:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$here/tests/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
cd "$build"
if [ $quick = 1 ]; then
  status=0
  for t in tests/test_core tests/test_maps tests/test_baseline_maps tests/test_robustness tests/mapper/test_mapper; do
    echo "== $t (ASan + UBSan)"
    "$build/$t" --gtest_filter='-StockApps.*' --gtest_brief=1 || status=1
  done
  exit $status
fi
# shellcheck disable=SC2086
ctest --output-on-failure -j "$jobs" --timeout 1200 -E '^StockApps\.' ${GAM_SANITIZER_CTEST_ARGS:-}
