#!/usr/bin/env bash
# rawlog_tools/gam-ablation-ini (issue #30: code with no test of its own): the
# labels, one ground-aware grid per label with that variant's keys, an .ini the
# mapper runs, and a clear error for a missing base file. Prints PASS.
# usage: test_gam_ablation_ini.sh SOURCE_DIR MAPPER_EXE REAL_DATA_DIR
set -euo pipefail
src=$1 mapper=$2 real=$3
tool="$src/rawlog_tools/gam-ablation-ini"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

read -r -a labels <<< "$(bash "$tool" --labels)"
[[ ${#labels[@]} -eq 23 ]] || fail "23 labels expected, got ${#labels[@]}: ${labels[*]}"
[[ ${labels[0]} == ground_aware && ${labels[1]} == paper ]] || fail "the default and the paper first: ${labels[*]}"

bash "$tool" "$src/config/ground-aware-mapper.ini" > "$tmp/ablation.ini"
grep -qx "groundAwareGrid_count=23" "$tmp/ablation.ini" || fail "groundAwareGrid_count=23 missing"
# The _groundOpts section of the grid labelled $1, as KEY=VALUE lines without comments.
opts_of() {
	local nn
	nn=$(awk -v l="label=$1" '/^\[map_groundAwareGrid_[0-9]+_creationOpts\]/ { s = $0 } $1 == l { print s }' "$tmp/ablation.ini" |
		sed -E 's/.*_([0-9]+)_creationOpts.*/\1/')
	[[ -n $nn ]] || fail "no grid labelled $1"
	awk -v h="[map_groundAwareGrid_${nn}_groundOpts]" '$0 == h { on = 1; next } /^\[/ { on = 0 } on' "$tmp/ablation.ini" |
		sed -E 's/[;#].*//; s/[[:space:]]+//g' | grep -v '^$' || true
}
for l in "${labels[@]}"; do opts_of "$l" > /dev/null; done
opts_of paper | grep -qx "ism_model=paper" || fail "paper: ism_model=paper"
opts_of paper | grep -qx "rrt_variant=paper" || fail "paper: rrt_variant=paper"
opts_of paper | grep -qx "scan_keeps_3d_obstacles=false" || fail "paper: the beam model for 2D scans"
opts_of paper | grep -qx "sparse_scan_near_edge=false" || fail "paper: a sparse scan's arcs"
opts_of no_scan_rule | grep -qx "scan_keeps_3d_obstacles=false" || fail "no_scan_rule"
opts_of no_near_edge_scan | grep -qx "sparse_scan_near_edge=false" || fail "no_near_edge_scan"
opts_of ground_aware | grep -qx "sparse_scan_near_edge=true" || fail "ground_aware keeps the near-edge scans"
opts_of ground_aware | grep -qx "scan_keeps_3d_obstacles=true" || fail "ground_aware keeps the base's scan rule"
opts_of no_min_points | grep -qx "min_obstacle_points=1" || fail "no_min_points: min_obstacle_points=1"
opts_of no_range_of_trust | grep -qx "range_of_trust=false" || fail "no_range_of_trust"
opts_of no_range_smear | grep -qx "range_smear=false" || fail "no_range_smear"
opts_of ground_aware | grep -qx "range_smear=true" || fail "ground_aware keeps range_smear"
opts_of no_ground_offset | grep -qx "max_ground_offset=0" || fail "no_ground_offset"
opts_of no_patch_memory | grep -qx "patch_memory=0" || fail "no_patch_memory"
opts_of no_step_shadows | grep -qx "missing_floor_step_shadows=false" || fail "no_step_shadows"
opts_of no_raised_sample_test | grep -qx "raised_sample_test=false" || fail "no_raised_sample_test"
[[ $(opts_of ground_aware | grep -c "ism_model=paper") -eq 0 ]] || fail "ground_aware must not be the paper's ISM"
# Each key appears once per section (a variant replaces the base's value).
for l in "${labels[@]}"; do
	dup=$(opts_of "$l" | cut -d= -f1 | sort | uniq -d)
	[[ -z $dup ]] || fail "$l: keys given twice: $dup"
done

# The mapper runs it: one map file per label.
milk="$real/pcl_milk_bottles_on_carpet/pcl_milk_bottles_on_carpet.rawlog"
if [[ -f $milk ]]; then
	"$mapper" --rawlog "$milk" --config "$tmp/ablation.ini" --out "$tmp/out" -q > "$tmp/log" 2>&1 || { cat "$tmp/log"; fail "the mapper refused the .ini"; }
	for l in "${labels[@]}"; do [[ -f "$tmp/out/$l.pgm" ]] || fail "no map $l.pgm"; done
fi

# A missing base file: a non-zero exit and a message naming it.
if bash "$tool" "$tmp/missing.ini" > "$tmp/out.ini" 2> "$tmp/err"; then fail "a missing base file was accepted"; fi
grep -q "missing.ini" "$tmp/err" || fail "the error does not name the file: $(cat "$tmp/err")"
echo PASS
