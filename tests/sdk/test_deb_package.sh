#!/usr/bin/env bash
# The Debian package (issue #16): cpack writes ground-aware-mapping_<version>_amd64.deb
# whose Depends name the Debian 12 runtime libraries it needs (MRPT 2.5, wxWidgets);
# unpacked anywhere, its ground-aware-mapper runs a real rawlog without the
# build tree, and its plugin loads into stock rawlog-edit.
# usage: test_deb_package.sh BUILD_DIR VERSION RAWLOG
set -euo pipefail
build="$1" version="$2" rawlog="$3"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
(cd "$build" && cpack -B "$w/pkg" >"$w/cpack.log" 2>&1) || { cat "$w/cpack.log"; fail "cpack"; }
deb="$w/pkg/ground-aware-mapping_${version}_amd64.deb"
[[ -f "$deb" ]] || fail "no $(basename "$deb"): $(ls "$w/pkg")"
info="$(dpkg-deb -f "$deb" Package Version Architecture Depends)"
echo "$info"
grep -q "^Package: ground-aware-mapping$" <<<"$info" || fail "package name"
grep -q "^Version: ${version}$" <<<"$info" || fail "version"
for lib in libmrpt-maps2.5 libmrpt-obs2.5 libmrpt-nav2.5 libwxgtk3.2-1; do
	grep -q "Depends:.*$lib" <<<"$info" || fail "Depends lacks $lib"
done
dpkg-deb -x "$deb" "$w/root"
for f in usr/bin/ground-aware-mapper usr/bin/ground-aware-viewer usr/bin/gam-calibrate usr/lib/libground_aware_maps.so \
	usr/lib/cmake/GroundAwareMapping/GroundAwareMappingConfig.cmake usr/include/mrpt/maps/CGroundAwareOccupancyGrid.h \
	usr/share/ground-aware-mapping/config/ground-aware-mapper.ini usr/share/doc/ground-aware-mapping/CHANGELOG.md; do
	[[ -e "$w/root/$f" ]] || fail "$f not in the package"
done
# The packaged mapper, with the packaged config, away from the build tree.
v="$("$w/root/usr/bin/ground-aware-mapper" --version)"
grep -q "version: ${version}$" <<<"$v" || fail "mapper --version: $v"
"$w/root/usr/bin/ground-aware-mapper" --rawlog "$rawlog" --config "$w/root/usr/share/ground-aware-mapping/config/ground-aware-mapper.ini" \
	--out "$w/out" -q >"$w/run.log" 2>&1 || { cat "$w/run.log"; fail "packaged mapper"; }
[[ -s "$w/out/ground_aware.pgm" ]] || fail "no ground_aware.pgm"
if command -v rawlog-edit >/dev/null; then
	GAM_PLUGIN_VERBOSE=1 rawlog-edit -p "$w/root/usr/lib/libground_aware_maps.so" -i "$rawlog" --info >"$w/edit.log" 2>&1 </dev/null
	grep -q "\[ground_aware_maps\] plugin loaded" "$w/edit.log" || { cat "$w/edit.log"; fail "stock rawlog-edit did not load the packaged plugin"; }
fi
echo PASS
