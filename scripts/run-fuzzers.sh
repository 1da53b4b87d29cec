#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz/, clang, ASan + UBSan) and runs each for
# SECONDS (default 60), starting from the seed corpus in tests/fuzz/corpus/<target>/.
# usage: scripts/run-fuzzers.sh [SECONDS] [BUILD_DIR]   (default build dir: build-fuzz/)
#
# Targets:
#   fuzz_rawlog  rawlog bytes -> the mapper's streaming reader -> every frame into
#                CElevation25DMap, CGroundAwareOccupancyGrid, CHeightBandOccupancyGrid,
#                COctoMapGrid2D
#   fuzz_ini     .ini text -> the mapper's validated map definitions -> CMultiMetricMap
#                -> one small depth frame into every map
# New inputs go to BUILD_DIR/corpus/<target>/ (the committed seeds are not modified);
# a crash, sanitizer report, leak or timeout (> 20 s per input) is written to
# BUILD_DIR/artifacts/ and fails the script; an input that runs out of memory
# (RSS > 3 GB or one allocation > 1.1 GB) is saved there too but only fails the
# script with GAM_FUZZ_STOP_ON_OOM=1. The mutation seed is fixed (GAM_FUZZ_SEED,
# default 1; 0 = random), so a short smoke run repeats the same inputs.
# Reproduce one with: BUILD_DIR/bin/<target> BUILD_DIR/artifacts/<file>
# GAM_FUZZ_TARGETS="fuzz_rawlog" runs a subset.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
secs=${1:-60}
build=${2:-$here/build-fuzz}
jobs=${GAM_JOBS:-$(nproc)}
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cxx=${GAM_FUZZ_CXX:-$(command -v clang++ || command -v clang++-14 || true)}
if [ -z "$cxx" ]; then
  echo "run-fuzzers: clang++ not found (Debian: apt-get install clang libclang-rt-14-dev)" >&2
  exit 2
fi

cmake -S "$here/tests/fuzz" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" >/dev/null
cmake --build "$build" -j "$jobs"

export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:allocator_may_return_null=1:quarantine_size_mb=64"
export LSAN_OPTIONS="suppressions=$here/tests/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
mkdir -p "$build/artifacts"
# MRPT 2.5's own deserializers still trust some counts in corrupt rawlogs (e.g. the
# measurement count of a CObservationRange): inputs that only run out of memory
# inside MRPT are logged and skipped (fork mode, -ignore_ooms) unless
# GAM_FUZZ_STOP_ON_OOM=1. Crashes, sanitizer reports, leaks and timeouts always stop.
oom_flags="-fork=1 -ignore_ooms=1"
[ "${GAM_FUZZ_STOP_ON_OOM:-0}" = 1 ] && oom_flags=""
# Smoke mode (CI): GAM_FUZZ_RUNS=N runs at most N inputs per target (and at most
# SECONDS), in one process, from the seeds alone (a fresh corpus folder), with the
# fixed seed. Not the same inputs on every run: coverage varies from run to run, and
# with it the mutations libFuzzer keeps (doc/robustness.md).
runs_flags=""
if [ -n "${GAM_FUZZ_RUNS:-}" ]; then
  runs_flags="-runs=$GAM_FUZZ_RUNS"
  oom_flags=""
fi
status=0
for t in ${GAM_FUZZ_TARGETS:-fuzz_rawlog fuzz_ini}; do
  seeds="$here/tests/fuzz/corpus/${t#fuzz_}"
  work="$build/corpus/$t"
  [ -n "$runs_flags" ] && { work="$build/corpus-smoke/$t"; rm -rf "$work"; }
  mkdir -p "$work"
  echo "== $t: ${secs} s, seeds $(ls "$seeds" | wc -l) files, corpus $work"
  log="$build/$t.log"
  # shellcheck disable=SC2086
  if "$build/bin/$t" -max_total_time="$secs" -timeout=20 -rss_limit_mb=3072 -malloc_limit_mb=1100 \
      -max_len=65536 -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" \
      -seed="${GAM_FUZZ_SEED:-1}" $oom_flags $runs_flags "$work" "$seeds" >"$log" 2>&1; then
    grep -E "^stat::number_of_executed_units|^stat::new_units_added|^#[0-9]+.*DONE|oom/timeout/crash" "$log" | tail -3 || true
    echo "== $t: no crash ($(ls "$work" | wc -l) corpus files)"
  elif [ "${GAM_FUZZ_STOP_ON_OOM:-0}" != 1 ] &&
       grep -qE "SUMMARY: (libFuzzer|AddressSanitizer): out-of-memory" "$log" &&
       ! grep -E "ERROR: (AddressSanitizer|LeakSanitizer)|runtime error|deadly signal|timeout" "$log" |
         grep -vq "ERROR: AddressSanitizer: allocator is out of memory"; then
    # Single-process (smoke) mode stops at the first out-of-memory input: the same
    # policy as fork mode, it is saved and does not fail the run. An operator new
    # that cannot be served is ASan's own out-of-memory report (e.g. a CRawlog
    # object's entry count: MRPT resizes a vector of pointers to it).
    grep -E "^stat::number_of_executed_units" "$log" || true
    echo "== $t: no crash; stopped by an out-of-memory input (saved in $build/artifacts)"
  else
    status=1
    echo "== $t: FAILED, see $log" >&2
    grep -E "ERROR|SUMMARY|Test unit written|==[0-9]+==" "$log" | head -20 >&2 || true
  fi
done
exit $status
