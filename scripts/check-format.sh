#!/usr/bin/env bash
# Checks that every C++ source of the project is formatted with .clang-format
# (clang-format 14, Debian's `clang-format` package). Exit 1 lists the files
# that are not. With --fix, formats them in place.
# usage: scripts/check-format.sh [--fix]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
command -v clang-format >/dev/null || { echo "check-format: clang-format not found (apt-get install clang-format)" >&2; exit 2; }
mapfile -t files < <(git ls-files '*.cpp' '*.h' '*.hpp')
if [[ "${1:-}" == "--fix" ]]; then
	clang-format --style=file -i "${files[@]}"
	echo "check-format: formatted ${#files[@]} files"
	exit 0
fi
bad=()
for f in "${files[@]}"; do
	if ! clang-format --style=file "$f" | cmp -s - "$f"; then bad+=("$f"); fi
done
if [[ ${#bad[@]} -gt 0 ]]; then
	echo "check-format: ${#bad[@]} of ${#files[@]} files are not formatted (scripts/check-format.sh --fix):" >&2
	printf '  %s\n' "${bad[@]}" >&2
	exit 1
fi
echo "check-format: ${#files[@]} files formatted"
