#!/usr/bin/env bash
# gam-benchmark --rrt-seed (2026-11-27): the seed reaches RRT-GPD and nothing else
# changes. On the demo scene: --rrt-seed 1 (the default .ini's random_seed) gives the
# default run's maps byte for byte; --rrt-seed 2 gives another draw of the tree, so
# another grid (the same simulated frames); the report names the seed; bad values and
# a config without random_seed are clear errors. Prints PASS.
# usage: test_gam_benchmark_rrt_seed.sh SOURCE_DIR
# (GAM_SIMULATE, GAM_MAPPER, GAM_EVALUATE: the tools, as for gam-benchmark)
set -euo pipefail
src=$1
bench="$src/rawlog_tools/gam-benchmark"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
run() {  # OUT [options]
	local o=$1; shift
	bash "$bench" --out "$tmp/$o" --scenes "$src/config/scenes/demo.scene" --real "$tmp/no_real_data" \
		--maps ground_aware "$@" > "$tmp/$o.txt" 2> "$tmp/$o.err"
}
grid() { echo "$tmp/$1/scenes/demo/maps/ground_aware.pgm"; }

run plain || fail "gam-benchmark without --rrt-seed: $(tail -3 "$tmp/plain.err")"
run seed1 --rrt-seed 1 || fail "--rrt-seed 1: $(tail -3 "$tmp/seed1.err")"
run seed2 --rrt-seed 2 || fail "--rrt-seed 2: $(tail -3 "$tmp/seed2.err")"

grep -q '^random_seed=1\b' "$src/config/ground-aware-mapper.ini" || fail "the default .ini's random_seed is not 1"
[[ $(grep -c '^random_seed=' "$tmp/seed2/config_rrt_seed.ini") -eq $(grep -c '^random_seed=' "$src/config/ground-aware-mapper.ini") ]] ||
	fail "every random_seed line of the .ini is set"
grep -q '^random_seed=2 ' "$tmp/seed2/config_rrt_seed.ini" || fail "random_seed=2 in the copy (comment kept)"
diff <(grep -v '^random_seed=' "$src/config/ground-aware-mapper.ini") <(grep -v '^random_seed=' "$tmp/seed2/config_rrt_seed.ini") > /dev/null ||
	fail "the copy differs from the .ini in more than random_seed"
grep -q 'seed 1, RRT seed 2)' "$tmp/seed2.txt" || fail "the report names the RRT seed"
grep -q 'RRT seed' "$tmp/plain.txt" && fail "no RRT seed in the report without --rrt-seed"
cmp -s "$tmp/plain/scenes/demo/demo.rawlog" "$tmp/seed2/scenes/demo/demo.rawlog" || fail "the frames must not depend on the RRT seed"
cmp -s "$(grid plain)" "$(grid seed1)" || fail "--rrt-seed 1 is the default's seed: the same grid"
cmp -s "$(grid plain)" "$(grid seed2)" && fail "--rrt-seed 2 left the grid unchanged: the seed did not reach the tree"

# Bad input: a clear error (exit 2), no run.
set +e
bash "$bench" --out "$tmp/bad" --rrt-seed x > /dev/null 2> "$tmp/bad.err"; rc=$?
set -e
[[ $rc -eq 2 ]] || fail "--rrt-seed x: exit $rc, expected 2"
grep -q -- "--rrt-seed needs a whole number (got 'x')" "$tmp/bad.err" || fail "--rrt-seed x: message: $(cat "$tmp/bad.err")"
grep -v '^random_seed=' "$src/config/ground-aware-mapper.ini" > "$tmp/noseed.ini"
set +e
bash "$bench" --out "$tmp/bad2" --config "$tmp/noseed.ini" --rrt-seed 3 > /dev/null 2> "$tmp/bad2.err"; rc=$?
set -e
[[ $rc -eq 2 ]] || fail "a config without random_seed: exit $rc, expected 2"
grep -q "sets no random_seed" "$tmp/bad2.err" || fail "a config without random_seed: message: $(cat "$tmp/bad2.err")"
echo PASS
