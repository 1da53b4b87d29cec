#!/usr/bin/env bash
# ground_patches.csv: the ramp patches that judged each depth frame beside the ground
# plane, the frame's own and those its camera's earlier frames fitted (patch_memory).
# ramp_6deg.scene has two 6 deg ramps (a wide one with a plateau, a thin plate) and a
# 15 deg wedge. By hand: a plane a x + b y + c z + d = 0 is tilted atan(hypot(a, b) / |c|)
# from level, so a patch on either ramp reads 6 deg; the wedge is steeper than any
# ground the tree takes (N_th = 0.2: asin(0.2) = 11.54 deg) and reads as no patch.
# usage: test_ground_patches.sh GAM_SIMULATE GROUND_AWARE_MAPPER REPO
set -euo pipefail
sim="$1" mapper="$2" repo="$3"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$sim" --scene "$repo/config/scenes/ramp_6deg.scene" --camera kinect_one --out "$w/s" --seed 1 >/dev/null
"$mapper" --print-default-config > "$w/default.ini"
# ground_aware alone (the other maps write no patches), then with patch_memory=0
sed -e 's/^heightBandGrid_count=1/heightBandGrid_count=0/' -e 's/^octoMapGrid_count=1/octoMapGrid_count=0/' \
	-e 's/^CElevation25DMap_count=1/CElevation25DMap_count=0/' "$w/default.ini" > "$w/ga.ini"
sed -e 's/^patch_memory=[^ ;]*/patch_memory=0/' "$w/ga.ini" > "$w/nomem.ini"
grep -q '^patch_memory=0' "$w/nomem.ini" || fail "patch_memory not in the default config"
"$mapper" --rawlog "$w/s.rawlog" --config "$w/ga.ini" --out "$w/mem" -q > /dev/null
"$mapper" --rawlog "$w/s.rawlog" --config "$w/nomem.ini" --out "$w/nomem" -q > /dev/null

csv="$w/mem/ground_patches.csv"
[[ "$(head -1 "$csv")" == "frame,patch,a,b,c,d,nodes,slope_deg,source,sensor" ]] || fail "header: $(head -1 "$csv")"
okFrames=$(awk -F, 'NR > 1 && $7 == "ok"' "$w/mem/ground_planes.csv" | wc -l)
[[ "$okFrames" -ge 8 ]] || fail "only $okFrames frames with a ground plane"
# slope_deg is the tilt of (a, b, c); patches numbered 1.. per frame; nodes > 0 for the frame's own
awk -F, 'NR > 1 {
	s = atan2(sqrt($3 * $3 + $4 * $4), ($5 < 0 ? -$5 : $5)) * 180 / 3.14159265358979
	if (s - $8 > 1e-6 || $8 - s > 1e-6) { print "slope " $0; bad = 1 }
	if ($1 != f) { f = $1; n = 0 }
	if ($2 != ++n) { print "numbering " $0; bad = 1 }
	if ($9 != "frame" && $9 != "remembered") { print "source " $0; bad = 1 }
	if ($9 == "frame" && $7 < 3) { print "nodes " $0; bad = 1 }
} END { exit bad }' "$csv" || fail "malformed rows"
# every frame with a ground plane has a patch of a 6 deg ramp (within 1 deg) of its own
ramps=$(awk -F, 'NR > 1 && $9 == "frame" && $8 > 5 && $8 < 7 { f[$1] = 1 } END { n = 0; for (k in f) n++; print n }' "$csv")
[[ "$ramps" -eq "$okFrames" ]] || fail "a 6 deg ramp patch in $ramps of $okFrames frames"
# nothing as steep as the wedge
awk -F, 'NR > 1 && $8 > 11.54 { print; bad = 1 } END { exit bad }' "$csv" || fail "a patch steeper than N_th"
# earlier frames' patches judged some frames; none without patch_memory
rem=$(awk -F, 'NR > 1 && $9 == "remembered"' "$csv" | wc -l)
[[ "$rem" -ge 1 ]] || fail "no remembered patch in the default run"
[[ "$(awk -F, 'NR > 1 && $9 == "remembered"' "$w/nomem/ground_patches.csv" | wc -l)" -eq 0 ]] ||
	fail "remembered patches with patch_memory=0"
# the frame's own patches do not depend on the memory (it only judges cells)
diff <(awk -F, '$9 != "remembered"' "$csv") <(awk -F, '$9 != "remembered"' "$w/nomem/ground_patches.csv") > /dev/null ||
	fail "the frames' own patches changed with patch_memory"
echo "ground_patches.csv: $okFrames frames, a 6 deg ramp patch in each, $rem remembered rows"
echo PASS
