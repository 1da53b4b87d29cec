#!/usr/bin/env bash
# Issue #14: two depth cameras and the Leddar fuse into one grid. two_cameras.scene has
# a small box and a floor outlet 0.35-0.5 m ahead of the walker, below the forward
# KINECT's view (its floor starts 0.66 m ahead) and inside KINECT_DOWN's. The same
# scene without KINECT_DOWN leaves them unseen and unmarked; with it, the ground-aware
# grid marks both, each camera's ground plane comes from its own frames (one
# ground_planes.csv row per depth frame, both cameras' mounts measured).
# usage: test_two_cameras.sh GAM_SIMULATE GROUND_AWARE_MAPPER GAM_EVALUATE REPO
set -euo pipefail
sim="$1" mapper="$2" eval="$3" repo="$4"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

scene="$repo/config/scenes/two_cameras.scene"
grep -q 'label=KINECT_DOWN' "$scene" || fail "two_cameras.scene has no KINECT_DOWN"
grep -v 'label=KINECT_DOWN' "$scene" > "$w/one.scene"
"$sim" --scene "$scene" --out "$w/two/two" --frames 3 --seed 1 >/dev/null
"$sim" --scene "$w/one.scene" --out "$w/one/one" --frames 3 --seed 1 >/dev/null
# the forward camera alone never sees the near objects (ids 1 and 2)
grep -qE '^[0-9]+,[0-9]+,[^,]+,[^,]+,(obstacle|drop),(1|2),' "$w/one/one_gt_labels.csv" &&
	fail "the forward camera alone sees the near objects"
grep -qE ',obstacle,1,small$' "$w/two/two_gt_labels.csv" || fail "KINECT_DOWN does not see the near box"
grep -qE ',drop,2,negative$' "$w/two/two_gt_labels.csv" || fail "KINECT_DOWN does not see the near outlet"

"$mapper" --rawlog "$w/two/two.rawlog" --out "$w/two/maps" -q > "$w/two/mapper.txt"
"$mapper" --rawlog "$w/one/one.rawlog" --out "$w/one/maps" -q > "$w/one/mapper.txt"
cat "$w/two/mapper.txt"
grep -q 'sensor mount KINECT_DOWN: declared z=0.600 m pitch=60.00' "$w/two/mapper.txt" || fail "no mount line for KINECT_DOWN"
[[ "$(awk -F, 'NR > 1 && $7 == "ok"' "$w/two/maps/ground_planes.csv" | wc -l)" -eq 6 ]] ||
	fail "expected 6 ground planes (3 frames x 2 cameras)"
# KINECT_DOWN's rows (every second one) measure its own mount: 0.6 m, 60 deg
awk -F, 'NR > 1 && NR % 2 == 1 { if ($8 < 0.58 || $8 > 0.62 || $9 < 59 || $9 > 61) bad = 1 } END { exit bad }' \
	"$w/two/maps/ground_planes.csv" || fail "KINECT_DOWN's plane does not give its mount"

# both maps scored against the two-camera ground truth (where the near objects are seen)
for m in two one; do
	"$eval" -q --gt "$w/two/two" --map "$w/$m/maps/ground_aware.yaml" --json "$w/$m.json"
done
obj() { grep -m1 "\"name\": \"$2\"" "$w/$1.json"; }
obj two near_box | grep -q '"detected": true' || fail "near box not marked with two cameras: $(obj two near_box)"
obj two near_outlet | grep -q '"detected": true' || fail "near outlet not marked with two cameras: $(obj two near_outlet)"
obj one near_box | grep -q '"occupied": 0,' || fail "near box marked without KINECT_DOWN: $(obj one near_box)"
obj one near_outlet | grep -q '"occupied": 0,' || fail "near outlet marked without KINECT_DOWN: $(obj one near_outlet)"
obj one far_box | grep -q '"detected": true' || fail "far box not marked by the forward camera"
echo "near box: two cameras $(obj two near_box | grep -o '"occupied": [0-9]*'), forward only $(obj one near_box | grep -o '"occupied": [0-9]*')"
echo "PASS"
