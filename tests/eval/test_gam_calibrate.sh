#!/usr/bin/env bash
# gam-calibrate (issue #15): three simulated mounts with a wrong declared pose
# are measured within 1 cm / 0.3 deg and raise the mapper's alarm within 10
# depth frames (gam-calibration-check), driving and standing; --write-ini writes one [sensor_poses]
# line per camera and replaces it on the next run; bad input: one error line, exit 1.
# usage: test_gam_calibrate.sh BUILD_DIR REPO
set -euo pipefail
build="$1" repo="$2"
cal="$build/rawlog_tools/gam-calibrate"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

bash "$repo/rawlog_tools/gam-calibration-check" --build "$build" --frames 8 \
	--cases "0.55,12,-6,0.08,4,-4 0.95,32,5,-0.06,-3,3" || fail "calibration check"
# The robot standing still: ten frames from one pose.
sed 's/^path .*/path waypoints=0,0,0 frames=10/' "$repo/config/scenes/demo.scene" >"$w/standing.scene"
bash "$repo/rawlog_tools/gam-calibration-check" --build "$build" --scene "$w/standing.scene" --frames 10 \
	--cases "0.7,18,-5,-0.09,4,3" || fail "calibration check, standing"

"$build/rawlog_tools/gam-simulate" --scene "$repo/config/scenes/demo.scene" --out "$w/d" --frames 6 \
	--declared-offset 0.05,2,0 >/dev/null
cp "$repo/config/ground-aware-mapper.ini" "$w/cal.ini"
"$cal" --rawlog "$w/d.rawlog" --config "$w/cal.ini" --write-ini "$w/cal.ini" | tee "$w/out1"
grep -Eq '^KINECT z=(0\.99|1\.00)[0-9]* pitch=2[45]\.[0-9]+ roll=-?0\.[0-9]+ \(\+-[0-9.]+, \+-[0-9.]+, \+-[0-9.]+\) frames=6/6$' "$w/out1" \
	|| fail "output line"
"$cal" --rawlog "$w/d.rawlog" --config "$w/cal.ini" --write-ini "$w/cal.ini" >"$w/out2"
grep -Eq "declared sensorPose: z=(0.99|1.00)" "$w/out2" || fail "the second run does not read [sensor_poses]"
[[ "$(grep -c '^KINECT = ' "$w/cal.ini")" == 1 ]] || fail "[sensor_poses] line duplicated"

set +e
"$cal" --rawlog "$w/missing.rawlog" 2>"$w/e"; rc=$?
[[ $rc == 1 ]] && grep -q "gam-calibrate: error: .*missing.rawlog" "$w/e" || fail "missing rawlog ($rc): $(cat "$w/e")"
"$cal" --rawlog "$w/d.rawlog" --label NOPE 2>"$w/e"; rc=$?
[[ $rc == 1 ]] && grep -q "labelled 'NOPE'" "$w/e" || fail "unknown label ($rc): $(cat "$w/e")"
printf '[sensor_poses]\nKINECT = 0.1 0 0.8 0 25\n' >"$w/bad.ini"
cat "$repo/config/ground-aware-mapper.ini" >>"$w/bad.ini"
"$cal" --rawlog "$w/d.rawlog" --config "$w/bad.ini" 2>"$w/e"; rc=$?
[[ $rc == 1 ]] && grep -q "sensor_poses\] KINECT=.*six numbers" "$w/e" || fail "malformed [sensor_poses] ($rc): $(cat "$w/e")"
"$cal" 2>"$w/e"; rc=$?
[[ $rc == 2 ]] || fail "no --rawlog should be a command-line error ($rc)"
echo PASS
