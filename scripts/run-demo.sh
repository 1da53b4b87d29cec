#!/usr/bin/env bash
# All set-up (packages, build), then the main job on the bundled default:
# simulate config/scenes/demo.scene (a walker driving towards a floor outlet,
# a small box and a downward stairwell) and map it with ground-aware-mapper
# and its default .ini (the ground-aware grid + the two comparison maps).
# Outputs: out/demo/ (maps as ROS yaml/pgm, .gridmap.gz, PNG; timing.csv ...),
# ending with the labelled figure out/demo/demo_maps.png.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
# Only the packages and targets the demo needs (issue #30): the three programs
# below and the libraries they link, not the test suites and benchmarks.
# run-tests.sh builds the rest in the same build/, reusing these objects.
bash "$here/scripts/install-deps.sh" demo
# The tests need packages the demo does not install (GoogleTest, ...): they
# are configured only once all packages are there. Switching GAM_BUILD_TESTS
# recompiles nothing.
tests=OFF
if bash "$here/scripts/install-deps.sh" --check all; then tests=ON; fi
bash "$here/scripts/build.sh" "$here/build" -DGAM_BUILD_TESTS=$tests \
  ground-aware-mapper gam-simulate gam-evaluate
out="$here/out/demo"
mkdir -p "$out"
"$here/build/rawlog_tools/gam-simulate" --scene "$here/config/scenes/demo.scene" --out "$out/demo"
"$here/build/bin/ground-aware-mapper" --rawlog "$out/demo.rawlog" --out "$out/maps"
# One labelled figure: ground truth | ground-aware | height band | octomap, same
# scale, the robot's path, a 1 m scale bar, a legend; the scores on stdout.
"$here/build/rawlog_tools/gam-evaluate" --gt "$out/demo" --map "$out/maps/ground_aware.yaml" \
  --map "$out/maps/height_band.yaml" --map "$out/maps/octomap.yaml" --png "$out/demo_maps.png" \
  --title "demo.scene: ground truth and the three maps (one run)"
echo "[run-demo] maps in $out/maps (ground_aware.png, height_band.png, octomap.png, ...);"
echo "[run-demo] the simulated ground truth is $out/demo_gt.pgm"
echo "[run-demo] figure (ground truth | ground_aware | height_band | octomap): $out/demo_maps.png"
