#!/usr/bin/env bash
# Long run: FRAMES (default 10000) simulated frames (half Kinect depth frames, half
# Leddar scans) through ground-aware-mapper (the default .ini, all four maps, with
# octomap project_every=0), with the mapper's resident memory (VmRSS of
# /proc/PID/status) sampled every 2 s against the frame it reached.
# usage: scripts/long-run.sh [FRAMES] [BUILD_DIR] [WORK_DIR]
#   defaults: 10000, build/ (scripts/build.sh first), BUILD_DIR/long-run
# The rawlog is gam-simulate's demo scene (21 frames, seed 1) looped: the gzip
# rawlog is concatenated with itself until it holds FRAMES frames (a multi-member
# gzip file MRPT reads as one stream), so the robot drives the same 2 m again and
# again and the maps should stop growing: RSS flat after the first loop.
# Environment: LONG_RUN_MAPS=ground_aware keeps only the ground-aware grid (the
# comparison maps off); LONG_RUN_MAPPER_ARGS adds mapper options, e.g.
# "--local-map --local-size-cells 600" for a robot-centred 600x600-cell window.
# Writes WORK_DIR/rss.csv (seconds,frame,rss_kib) and prints RSS at the start
# (first sample past frame 100), the maximum and at the end.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
frames=${1:-10000}
build=${2:-$here/build}
work=${3:-$build/long-run}
sim="$build/rawlog_tools/gam-simulate"
mapper="$build/bin/ground-aware-mapper"
[ -x "$sim" ] && [ -x "$mapper" ] || { echo "long-run: build first (scripts/build.sh $build)" >&2; exit 2; }
rm -rf "$work"
mkdir -p "$work"
"$sim" --scene "$here/config/scenes/demo.scene" --out "$work/demo" --seed 1 >/dev/null
# Two mapper frames per simulated pose: the Kinect depth frame and the Leddar scan.
per=$(( 2 * $(awk -F, 'NR>1' "$work/demo_gt_path.csv" | wc -l) ))
loops=$(( (frames + per - 1) / per ))
for _ in $(seq "$loops"); do cat "$work/demo.rawlog"; done >"$work/looped.rawlog"
echo "long-run: $per frames per loop x $loops loops = $((per * loops)) frames ($(du -h "$work/looped.rawlog" | cut -f1)); running the first $frames"

# The default .ini, but the octomap is projected to 2D only when saved
# (project_every=0): re-projecting the whole octomap after every frame is most of
# the run time and allocates nothing that lasts.
"$mapper" --print-default-config | sed 's/^project_every=.*/project_every=0/' >"$work/long-run.ini"
grep -q '^project_every=0' "$work/long-run.ini" || { echo "long-run: project_every not found in the default .ini" >&2; exit 2; }
case "${LONG_RUN_MAPS:-all}" in
  all) ;;
  ground_aware) sed -i 's/^\(heightBandGrid\|octoMapGrid\|CElevation25DMap\)_count=1/\1_count=0/' "$work/long-run.ini"
    [ "$(grep -c '_count=1' "$work/long-run.ini")" = 1 ] || { echo "long-run: could not switch the comparison maps off" >&2; exit 2; } ;;
  *) echo "long-run: LONG_RUN_MAPS must be all or ground_aware" >&2; exit 2 ;;
esac
t0=$(date +%s)
# shellcheck disable=SC2086 # LONG_RUN_MAPPER_ARGS is a list of options
"$mapper" --rawlog "$work/looped.rawlog" --config "$work/long-run.ini" --out "$work/out" --max-frames "$frames" ${LONG_RUN_MAPPER_ARGS:-} >"$work/summary.txt" 2>"$work/progress.txt" &
pid=$!
echo "seconds,frame,rss_kib" >"$work/rss.csv"
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  fr=$(grep -o 'frame [0-9]*' "$work/progress.txt" 2>/dev/null | tail -1 | cut -d' ' -f2 || true)
  [ -n "$rss" ] && echo "$(( $(date +%s) - t0 )),${fr:-0},$rss" >>"$work/rss.csv"
  sleep 2
done
wait "$pid"
rc=$?
cat "$work/summary.txt"
awk -F, 'NR>1 && $2>=100 && !s {s=$3; sf=$2} NR>1 {if ($3>m) m=$3; e=$3; ef=$2}
  END {printf "long-run: VmRSS start %d KiB (frame %d), max %d KiB, end %d KiB (frame %d): %+.1f%%\n", s, sf, m, e, ef, s ? 100*(e-s)/s : 0}' "$work/rss.csv"
exit $rc
