#!/usr/bin/env bash
# rawlog_tools/gam-paper-figures (issue #30: code with no test of its own): it
# writes Fig. 4 and Fig. 5 with their CSVs, and the paper's claims read off
# them hold in their direction: the 3-sigma rule removes obstacle cells that
# outliers add, IDW adds cells, and over the office traversal the paper's map
# finds more low and negative hazards than the Leddar alone and the height
# band. Prints PASS. usage: test_gam_paper_figures.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
bash "$src/rawlog_tools/gam-paper-figures" --build "$build" --out "$tmp" > "$tmp/log" 2>&1 || { tail -20 "$tmp/log"; fail "gam-paper-figures failed"; }
for f in fig4.png fig4.csv fig5.png fig5.csv; do [[ -s "$tmp/$f" ]] || fail "$f missing"; done
# "occupied N" of a panel of a scene in a CSV.
occ() { grep -F "$2,\"$3\"" "$tmp/$1" | sed -E 's/.*occupied ([0-9]+).*/\1/'; }
for scene in floor_outlets downward_stairs; do
	kept=$(occ fig4.csv "$scene" "2D, with outliers") sigma=$(occ fig4.csv "$scene" "2D, 3-sigma")
	idw=$(occ fig4.csv "$scene" "2D, 3-sigma + IDW")
	[[ -n $kept && -n $sigma && -n $idw ]] || fail "$scene: a Fig. 4 panel is missing"
	((sigma <= kept)) || fail "$scene: 3-sigma $sigma > outliers kept $kept"
	((idw >= sigma)) || fail "$scene: IDW $idw < 3-sigma $sigma"
	grep -qF "$scene,\"IDW\",\"" "$tmp/fig4.csv" || fail "$scene: the IDW cell count"
done
# Negative + small hazards found per Fig. 5 map ("negative a/b", "small c/d").
found() {
	local row
	row=$(grep -F "office_traverse,\"$1\"" "$tmp/fig5.csv")
	echo $(($(sed -E 's/.*negative ([0-9]+)\/.*/\1/' <<< "$row") + $(sed -E 's/.*small ([0-9]+)\/.*/\1/' <<< "$row")))
}
paper=$(found "paper mode") leddar=$(found "Leddar alone (beam model)") band=$(found "height band 0.2-1.5 m")
((paper > leddar && paper > band)) || fail "hazards found: paper $paper, Leddar $leddar, height band $band"
echo PASS
