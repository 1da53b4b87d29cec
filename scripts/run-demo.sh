#!/usr/bin/env bash
# All set-up (packages, build), then the main job on the bundled default:
# simulate config/scenes/demo.scene (a walker driving towards a floor outlet,
# a small box and a downward stairwell) and map it with ground-aware-mapper
# and its default .ini (the ground-aware grid + the two comparison maps).
# Outputs: out/demo/ (maps as ROS yaml/pgm, .gridmap.gz, PNG; timing.csv ...)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bash "$here/scripts/install-deps.sh"
bash "$here/scripts/build.sh" "$here/build"
out="$here/out/demo"
mkdir -p "$out"
"$here/build/rawlog_tools/gam-simulate" --scene "$here/config/scenes/demo.scene" --out "$out/demo"
"$here/build/bin/ground-aware-mapper" --rawlog "$out/demo.rawlog" --out "$out/maps"
echo "[run-demo] maps in $out/maps (ground_aware.png, height_band.png, octomap.png, ...);"
echo "[run-demo] the simulated ground truth is $out/demo_gt.pgm"
