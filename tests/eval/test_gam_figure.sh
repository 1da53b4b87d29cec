#!/usr/bin/env bash
# gam-figure (the paper's Fig. 4): on the first frame of floor_outlets the
# paper's method keeps more obstacle cells with outliers than with the
# 3-sigma rule (the paper's claim that outliers clutter the map), and
# IDW adds cells to the 2.5D map; bad input gives one error line and exit 1.
# usage: test_gam_figure.sh GAM_SIMULATE GAM_FIGURE REPO
set -euo pipefail
sim="$1" fig="$2" repo="$3"
w="$(mktemp -d)"
trap 'rm -rf "$w"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$sim" --scene "$repo/config/scenes/floor_outlets.scene" --out "$w/fo" --frames 1 --seed 1 >/dev/null
"$fig" --figure 4 --config "$repo/config/ground-aware-mapper.ini" --rawlog "$w/fo.rawlog" --gt "$w/fo" \
	--out "$w/fig4.png" --csv "$w/fig4.csv" >"$w/out.txt"
cat "$w/out.txt"
[[ -s "$w/fig4.png" ]] || fail "no PNG"
occ() { grep -F "| $1 |" "$w/out.txt" | sed -E 's/.*occupied ([0-9]+),.*/\1/'; }
with="$(occ "2D, with outliers")" sigma="$(occ "2D, 3-sigma")"
[[ -n "$with" && -n "$sigma" ]] || fail "missing rows"
(( sigma < with )) || fail "3-sigma ($sigma occupied) should remove outlier obstacles (with outliers: $with)"
grep -Eq "\| IDW \| [1-9][0-9]* cells added by IDW" "$w/out.txt" || fail "IDW added no cell"
[[ "$(wc -l <"$w/fig4.csv")" -eq 8 ]] || fail "CSV: header + 7 rows expected"

# Bad input: a clear error, exit 1 (2 for the command line).
set +e
"$fig" --figure 7 --rawlog "$w/fo.rawlog" --out "$w/x.png" --config "$repo/config/ground-aware-mapper.ini" 2>"$w/err"
[[ $? -eq 1 ]] && grep -q "must be 4 or 5" "$w/err" || fail "--figure 7 not rejected"
"$fig" --figure 4 --rawlog "$w/missing.rawlog" --out "$w/x.png" --config "$repo/config/ground-aware-mapper.ini" 2>"$w/err"
[[ $? -eq 1 ]] && grep -q "cannot read rawlog" "$w/err" || fail "missing rawlog not reported"
"$fig" --figure 4 --out "$w/x.png" 2>"$w/err"
[[ $? -eq 2 ]] || fail "missing --rawlog not a command-line error"
echo "PASS"
