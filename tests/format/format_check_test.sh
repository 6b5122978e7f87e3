#!/usr/bin/env bash
# The format check must fail on an unformatted source: runs scripts/check_format.sh on a small git tree
# with the project's .clang-format, one formatted header, one unformatted test source (it must name
# that one, and only it, and exit 1) and unformatted files it must not look at (untracked, outside
# include/ examples/ tests/ bench/, not *.hpp/*.cpp); then on the same tree with the source formatted
# by hand (it must pass). Exits 77 (ctest: skipped) without clang-format 14, as the check does.
#   bash format_check_test.sh <source-dir>
set -euo pipefail
check="$1/scripts/check_format.sh"
tree=$(mktemp -d)
trap 'rm -rf "$tree"' EXIT
fail() { echo "format_check_test: $*" >&2; exit 1; }

cp "$1/.clang-format" "$tree/"
mkdir -p "$tree/include/lib" "$tree/tests/fuzz/regressions" "$tree/docs" "$tree/bench"
printf '#pragma once\n\nnamespace lib {\n\ninline int twice(int x) { return 2 * x; }\n\n}  // namespace lib\n' \
  >"$tree/include/lib/twice.hpp"
unformatted='#include "lib/twice.hpp"\nint   main( ){return lib::twice(1)==2?0:1;}\n'
printf "$unformatted" >"$tree/tests/twice_test.cpp"
printf "$unformatted" >"$tree/docs/snippet.cpp"             # tracked, outside the checked directories
printf "$unformatted" >"$tree/tests/fuzz/regressions/input" # tracked data, not C++
git -C "$tree" init -q
git -C "$tree" add -A
printf "$unformatted" >"$tree/bench/untracked.cpp"          # in a checked directory, untracked

set +e
out=$(bash "$check" "$tree" 2>&1)
status=$?
set -e
[ "$status" = 77 ] && { echo "$out"; exit 77; }
[ "$status" = 1 ] || fail "exit $status, not 1, on a tree with an unformatted source:"$'\n'"$out"
grep -q '^tests/twice_test.cpp: not formatted' <<<"$out" || fail "did not name tests/twice_test.cpp:"$'\n'"$out"
[ "$(grep -c 'not formatted (' <<<"$out")" = 1 ] || fail "named files it should not check:"$'\n'"$out"

printf '#include "lib/twice.hpp"\nint main() { return lib::twice(1) == 2 ? 0 : 1; }\n' >"$tree/tests/twice_test.cpp"
out=$(bash "$check" "$tree" 2>&1) || fail "refused a tree whose sources are formatted:"$'\n'"$out"
grep -q 'all 2 C++ files are formatted' <<<"$out" || fail "did not check the two tracked sources:"$'\n'"$out"
echo "format_check_test: ok"
