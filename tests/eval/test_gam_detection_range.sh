#!/usr/bin/env bash
# rawlog_tools/gam-detection-range smoke test (issue #13), ~20-40 s:
# - single mode, two holes (10 x 5 cm and 30 x 5 cm), ranges 1.0 and 4.0 m,
#   one seed: the table has its header and one row per object, with the
#   geometric limits by hand: 0.10 * 0.8 / 0.03 = 2.67 m and
#   0.30 * 0.8 / 0.03 = 8.0 m capped by the 4.5 m range; the Kinect One's
#   range of trust is the map's whole 5 m, so the limits stay 2.67 and 4.5 m;
#   the summary CSV has one row per object and map and names the commit;
# - --camera d435 --maps ground_aware: one map; the geometric limit of the
#   30 cm hole is 8.0 m capped by the map's 5 m (the D435 reaches 6 m), and
#   the limit is the range of trust the mapper prints (below 5 m at 0.8 m);
# - approach mode, the 30 x 5 cm hole, one seed: a row whose ground_aware
#   entry is a range within the 5.0 .. 1.0 m the approach covers;
# - --rrt-seed 7 (on the approach run): the mapper's config_used.ini has
#   random_seed=7, the CSV names it;
# - --help exits 0; a bad option, a missing build, --objects matching nothing
#   and a bad --rrt-seed exit 2 with one error line; --from re-reads detections.csv;
# - --cell-phases 2 --seeds 2: seed 2's scene shifts the robot and the hole by 2.5 cm;
#   --cell-phases 0 exits 2.
# usage: test_gam_detection_range.sh BUILD_DIR REPO
set -euo pipefail
build="$1" repo="$2"
tool="$repo/rawlog_tools/gam-detection-range"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$tool" --build "$build" --modes single --objects '^hole_0\.(10|30)x0\.05$' --ranges "1.0 4.0" --seeds 1 \
	--out "$w/single" --csv "$w/single.csv" --commit smoke >"$w/single.txt" 2>"$w/single.err" ||
	{ cat "$w/single.err"; fail "single run failed"; }
cat "$w/single.txt"
hdr="| object | geometric limit [m] | range of trust [m] | limit [m] | ground_aware [m] | ratio to the limit |"
grep -qxF "$hdr height_band [m] | octomap [m] |" "$w/single.txt" || fail "single-frame table header"
grep -Eq '^\| hole_0\.10x0\.05 \| 2\.67 \| 5\.00 \| 2\.67 \| (1\.00|4\.00|not detected)( \(gaps; all to [-0-9.]+\))? \| [-0-9.]+ \| ' \
	"$w/single.txt" || fail "hole_0.10x0.05 row (limit 2.67)"
grep -Eq '^\| hole_0\.30x0\.05 \| 4\.50 \| 5\.00 \| 4\.50 \| (1\.00|4\.00|not detected)( \(gaps; all to [-0-9.]+\))? \| [-0-9.]+ \| ' \
	"$w/single.txt" || fail "hole_0.30x0.05 row (limit 8.0 m capped at 4.50)"
[[ "$(grep -c '^| hole_' "$w/single.txt")" -eq 2 ]] || fail "two rows expected"
grep -qx "# commit: smoke" "$w/single.csv" || fail "CSV names the commit"
[[ "$(grep -c '^hole_0\.[13]0x0\.05,hole,.*,single,' "$w/single.csv")" -eq 6 ]] || fail "CSV: 2 objects x 3 maps"
grep -q '^hole_0.30x0.05,hole,0.3,0.05,kinect_one,4.5,5.0,4.5,single,ground_aware,1,' "$w/single.csv" ||
	fail "CSV limit columns"
[[ -s "$w/single/detections.csv" && -s "$w/single/tables.md" ]] || fail "--out files"
# Issue #27's verdict: 0.9 x the limit, 0.9 * 2.667 = 2.40 m and 0.9 * 4.5 = 4.05 m. The ranges
# 1.0 and 4.0 m never reach 4.05 m, so the 30 cm hole is always a miss; the 10 cm hole passes
# when both ranges are marked (its unbroken range is 1.00, 4.00 or none).
v="$(grep '^single: every hazard out to >= 0.9 x its limit at every range up to it (issue #27): ' "$w/single.txt")" ||
	fail "issue #27 verdict line"
grep -Eq 'hole_0\.10x0\.05 \((1\.00|4\.00|-) of 2\.40\)' <<<"$v" || fail "issue #27 verdict: 10 cm hole needs 2.40 m"
grep -Eq 'miss it: [12]: (.*, )?hole_0\.30x0\.05 \((1\.00|4\.00|-) of 4\.05\)' <<<"$v" ||
	fail "issue #27 verdict: 30 cm hole needs 4.05 m"

"$tool" --build "$build" --camera d435 --maps ground_aware --modes single --objects '^hole_0\.30x0\.05$' \
	--ranges "1.5" --seeds 1 --csv "$w/d435.csv" --commit smoke >"$w/d435.txt" 2>"$w/d435.err" ||
	{ cat "$w/d435.err"; fail "d435 run failed"; }
cat "$w/d435.txt"
grep -qxF "$hdr" "$w/d435.txt" || fail "d435 table header: ground_aware only"
row="$(grep '^| hole_0.30x0.05 | 5.00 |' "$w/d435.txt")" || fail "d435 row (8.0 m capped at the map's 5 m)"
trust="$(cut -d'|' -f4 <<<"$row" | xargs)" limit="$(cut -d'|' -f5 <<<"$row" | xargs)"
awk -v t="$trust" -v l="$limit" 'BEGIN { exit !(t + 0 > 1.5 && t + 0 < 5.0 && l == t) }' ||
	fail "d435: range of trust '$trust' not in (1.5, 5) m or not the limit ('$limit')"
grep -qx "# camera: d435" "$w/d435.csv" || fail "d435 CSV names the camera"
[[ "$(grep -c '^hole_0.30x0.05,hole,' "$w/d435.csv")" -eq 1 ]] || fail "d435 CSV: one map"
grep -q "^# rrt_seed" "$w/d435.csv" && fail "no rrt_seed in the CSV without --rrt-seed"

# (With --rrt-seed 7: the approach run keeps its maps, whose config_used.ini shows the seed the
# mapper ran with.)
"$tool" --build "$build" --modes approach --objects '^hole_0\.30x0\.05$' --seeds 1 --out "$w/appr" \
	--rrt-seed 7 --csv "$w/appr.csv" --commit smoke >"$w/appr.txt" 2>"$w/appr.err" ||
	{ cat "$w/appr.err"; fail "approach run failed"; }
used="$w/appr/approach/hole_0.30x0.05/s1/maps/config_used.ini"
[[ -f "$used" ]] || fail "approach: no $used"
grep -q '^random_seed=7\b' "$used" || fail "--rrt-seed 7: the mapper ran with $(grep '^random_seed=' "$used")"
grep -qx "# rrt_seed: 7" "$w/appr.csv" || fail "--rrt-seed: the CSV names the seed"
cat "$w/appr.txt"
row="$(grep '^| hole_0.30x0.05 | 4.50 |' "$w/appr.txt")" || fail "approach row"
ga="$(cut -d'|' -f6 <<<"$row" | xargs)"
awk -v v="$ga" 'BEGIN { exit !(v + 0 >= 1.0 && v + 0 <= 5.0) }' || fail "approach ground_aware '$ga' not in 1..5 m"
[[ "$(awk -F, '$2 == "approach" && $6 == "ground_aware"' "$w/appr/detections.csv" | wc -l)" -eq 81 ]] ||
	fail "approach: 81 frames per map"
[[ ! -e "$w/appr/approach/hole_0.30x0.05/s1/maps/snapshots" ]] || fail "snapshots not removed"

"$tool" --from "$w/single/detections.csv" --commit smoke >"$w/from.txt" || fail "--from"
cmp -s <(grep '^| hole_' "$w/single.txt") <(grep '^| hole_' "$w/from.txt") || fail "--from gives other tables"

# Cell phases: with --cell-phases 2, seed s shifts the robot and the object by ((s - 1) mod 2) x
# 5 cm / 2: seed 1 by 0, seed 2 by 2.5 cm. A 10 cm hole at 1.0 m from the camera (0.1 m ahead of
# the robot) has its centre at 0.1 + 1.0 + 0.05 = 1.15 m, and 1.175 m with the shift.
"$tool" --build "$build" --maps ground_aware --modes single --objects '^hole_0\.10x0\.05$' --ranges "1.0" \
	--seeds 2 --cell-phases 2 --out "$w/phase" --commit smoke >"$w/phase.txt" 2>"$w/phase.err" ||
	{ cat "$w/phase.err"; fail "--cell-phases 2 run failed"; }
for sd_shift_x in "1 0.0000 1.1500" "2 0.0250 1.1750"; do
	read -r sd shift x <<<"$sd_shift_x"
	sc="$w/phase/single/hole_0.10x0.05/r1.00_s$sd/s.scene"
	grep -qx "path waypoints=$shift,0,0 frames=1" "$sc" || { cat "$sc"; fail "seed $sd: robot at x = $shift"; }
	grep -q "^hole id=1 name=obj shape=rect x=$x y=0 " "$sc" || { cat "$sc"; fail "seed $sd: hole centre at $x"; }
	grep -q "^hole_0.10x0.05,single,$sd,.*,$shift," "$w/phase/detections.csv" ||
		fail "seed $sd: detections.csv cell_phase_m $shift"
done
grep -qF "seed 1: 0.00 cm, seed 2: 2.50 cm." "$w/phase.txt" || fail "the phases line"

# Gaps, from a detections.csv written by hand (no runs): a 15 x 5 cm hole (limit 0.15 * 0.8 /
# 0.03 = 4.00 m) marked by 3, 1 and 2 of 3 seeds at 1, 2 and 3 m: the majority reaches 3.00 m
# with a gap at 2.00 m, so every range is marked only up to 1.00 m, and issue #27's verdict
# (0.9 * 4.00 = 3.60 m) takes that 1.00 m. Per seed the farthest is 3, 3 and 2 m; ratio 3 / 4 = 0.75.
{
	echo "object,mode,seed,frame,range_m,map,camera,trust_range_m,detected,detected_any,occupied_cells,free_cells,observed_cells,floor_occupied_pct"
	for rd in "1.00 1 1 1" "2.00 0 0 1" "3.00 1 1 0"; do
		read -r r d1 d2 d3 <<<"$rd"
		sd=1
		for d in $d1 $d2 $d3; do
			echo "hole_0.15x0.05,single,$sd,0,$r,ground_aware,kinect_one,5.00,$d,$d,$((3 * d)),0,4,0.0"
			sd=$((sd + 1))
		done
	done
} >"$w/gaps.csv"
"$tool" --from "$w/gaps.csv" --commit smoke >"$w/gaps.txt" || fail "--from gaps.csv"
grep -qF '| hole_0.15x0.05 | 4.00 | 5.00 | 4.00 | 3.00 (gaps; all to 1.00) [2.00–3.00] | 0.75 |' "$w/gaps.txt" ||
	{ cat "$w/gaps.txt"; fail "gaps: farthest 3.00, every range to 1.00"; }
grep -qF 'every hazard out to >= 0.9 x its limit at every range up to it (issue #27): 0: -; miss it: 1: hole_0.15x0.05 (1.00 of 3.60)' \
	"$w/gaps.txt" || fail "gaps: issue #27 verdict takes the unbroken range"

# (Into a file: grep -q in a pipe may close it before the help is written,
# and the tool then dies of a broken pipe -- a flaky failure under pipefail.)
"$tool" --help >"$w/help.txt" || fail "--help exit status"
grep -q "usage: rawlog_tools/gam-detection-range" "$w/help.txt" || fail "--help"
set +e
"$tool" --bogus 2>"$w/err"
[[ $? -eq 2 && "$(wc -l <"$w/err")" -eq 1 ]] || fail "unknown option: exit 2, one line"
"$tool" --build "$w/nowhere" 2>"$w/err"
[[ $? -eq 2 ]] && grep -q "not built" "$w/err" || fail "missing build not reported"
"$tool" --build "$build" --objects 'no_such_object' 2>"$w/err"
[[ $? -eq 2 ]] && grep -q "matches no object" "$w/err" || fail "--objects matching nothing"
"$tool" --seeds 0 2>"$w/err"
[[ $? -eq 2 ]] || fail "--seeds 0 accepted"
"$tool" --cell-phases 0 2>"$w/err"
[[ $? -eq 2 ]] && grep -q "cell-phases takes a whole number" "$w/err" || fail "--cell-phases 0 accepted"
"$tool" --rrt-seed x 2>"$w/err"
[[ $? -eq 2 ]] && grep -q "rrt-seed takes a whole number" "$w/err" || fail "--rrt-seed x accepted"
echo "PASS"
