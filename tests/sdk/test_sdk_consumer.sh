#!/usr/bin/env bash
# The SDK from a consumer's side: install this build into a fresh prefix,
# configure and build examples/ini-multimetric-map with find_package() against
# it alone, run it on a real rawlog with the installed default .ini.
# usage: test_sdk_consumer.sh BUILD_DIR SOURCE_DIR RAWLOG
set -euo pipefail
build="$1" src="$2" rawlog="$3"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
prefix="$w/prefix"
cmake --install "$build" --prefix "$prefix" >"$w/install.log" || { cat "$w/install.log"; fail "cmake --install"; }
cfg="$(find "$prefix" -name GroundAwareMappingConfig.cmake)"
[[ -n "$cfg" ]] || fail "no GroundAwareMappingConfig.cmake in the install tree"
for f in include/mrpt/maps/CGroundAwareOccupancyGrid.h include/gam/core/GroundAwarePipeline.h \
	share/ground-aware-mapping/config/ground-aware-grid.ini bin/ground-aware-mapper; do
	[[ -e "$prefix/$f" ]] || fail "$f not installed"
done
cmake -S "$src/examples/ini-multimetric-map" -B "$w/b" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
	>"$w/configure.log" 2>&1 || { cat "$w/configure.log"; fail "configure"; }
# It must use the install tree, not this source tree.
grep -q "$src/libs" "$w/b/CMakeCache.txt" && fail "the consumer saw the source tree"
cmake --build "$w/b" -j2 >"$w/build.log" 2>&1 || { cat "$w/build.log"; fail "build"; }
out="$("$w/b/ini-multimetric-map" "$prefix/share/ground-aware-mapping/config/ground-aware-grid.ini" "$rawlog")"
echo "$out"
grep -Eq "1 depth frames, ground plane in 1; ground-aware grid: [1-9][0-9]* occupied, [1-9][0-9]* free cells" <<<"$out" \
	|| fail "unexpected output"
# The installed mapper runs too (its libraries found through its RPATH).
"$prefix/bin/ground-aware-mapper" --version >/dev/null || fail "installed ground-aware-mapper does not start"
echo PASS
