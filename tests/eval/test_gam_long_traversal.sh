#!/usr/bin/env bash
# rawlog_tools/gam-long-traversal (issue #30: code with no test of its own), as a
# smoke run: the first 120 frames of one lap, a snapshot every 20 frames. The
# report has both runs (local window and global map) with their RSS figures,
# the outlets seen so far are kept while out of view (none lost), the final
# maps are scored, the figures are written, and bad options are refused.
# Prints PASS. usage: test_gam_long_traversal.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# A failure shows the report and the tool's last lines (it was seen to fail
# now and then under a loaded ctest -j2, cause unknown; this makes the next
# one readable).
fail() {
	echo "FAIL: $*"
	[[ -s $tmp/out/long_traversal.md ]] && head -30 "$tmp/out/long_traversal.md"
	[[ -s $tmp/log ]] && tail -20 "$tmp/log"
	exit 1
}
tool="$src/rawlog_tools/gam-long-traversal"
python3 "$tool" --build "$build" --out "$tmp/out" --laps 1 --frames 120 --snapshot-frames 20 > "$tmp/log" 2>&1 ||
	{ tail -20 "$tmp/log"; fail "gam-long-traversal failed"; }
rep="$tmp/out/long_traversal.md"
[[ -s $rep ]] || fail "no report"
grep -q "^Office loop: 1 laps, 120 frames" "$rep" || fail "the frame count: $(head -1 "$rep")"
for mode in local global; do
	grep -qE "^\| $mode \| [0-9]+ \| [0-9.]+ \| [0-9.]+ / [0-9.]+ / [0-9.]+ \| [0-9.]+ \|$" "$rep" || fail "$mode: no timing/RSS row"
	# | run | snapshots | inside first / last | checks | kept | lost |: 6 snapshots, none lost
	# (matched by its "first / last" column: the timing row above also starts
	# "| local | 6 |" when the run takes 6 s)
	row=$(grep -E "^\| $mode \| 6 \| [0-9]+ / [0-9]+ \| " "$rep") || fail "$mode: not 6 snapshots"
	lost=$(awk -F'|' '{ gsub(/ /, "", $7); print $7 }' <<< "$row")
	checks=$(awk -F'|' '{ gsub(/ /, "", $5); print $5 }' <<< "$row")
	((checks > 0)) || fail "$mode: no outlet cell was checked out of view: $row"
	[[ $lost == 0 ]] || fail "$mode: $lost outlet cells lost out of view: $row"
done
grep -q "ground_aware   p>0.5" "$rep" || fail "the final maps are not scored"
for f in local_windows.png local_maps.png long_traversal.csv; do [[ -s "$tmp/out/$f" ]] || fail "$f missing"; done
[[ $(grep -c '^local,' "$tmp/out/long_traversal.csv") -gt 0 ]] || fail "no RSS samples"
if python3 "$tool" --build "$build" --out "$tmp/bad" --laps 0 > "$tmp/bad.log" 2>&1; then fail "--laps 0 accepted"; fi
grep -q "laps" "$tmp/bad.log" || fail "the error does not name --laps"
echo PASS
