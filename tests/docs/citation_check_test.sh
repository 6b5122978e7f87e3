#!/usr/bin/env bash
# The citation check must fail on a dangling citation: runs scripts/check_citations.sh on a small tree
# with one missing file and one missing section (it must name both and exit 1), then on the same tree
# with both fixed (it must pass).   bash citation_check_test.sh <source-dir>
set -euo pipefail
# The fixture's file names are spelt with $md so that this script cites nothing itself.
md=md
check="$1/scripts/check_citations.sh"
tree=$(mktemp -d)
trap 'rm -rf "$tree"' EXIT
mkdir -p "$tree/docs" "$tree/include"
printf "# Method\n\n## 1. One\n\ntext\n" >"$tree/docs/method.$md"
printf "See [the method §1](method.$md) and [design](design.$md).\n" >"$tree/docs/index.$md"
printf "/// As in docs/method.$md §1 and docs/method.$md §1–2.\n/// And plants.$md.\n" >"$tree/include/x.hpp"

fail() { echo "citation_check_test: $*" >&2; exit 1; }
if out=$(bash "$check" "$tree" 2>&1); then fail "passed a tree with dangling citations:"$'\n'"$out"; fi
grep -q "include/x.hpp:1: cites docs/method.$md §2, but docs/method.$md has no heading '## 2.'" <<<"$out" ||
  fail "missed the missing section:"$'\n'"$out"
grep -q "include/x.hpp:2: cites plants.$md, which is not in the repository" <<<"$out" ||
  fail "missed the missing file:"$'\n'"$out"
grep -q "docs/index.$md:1: cites design.$md, which is not in the repository" <<<"$out" ||
  fail "missed the missing link target:"$'\n'"$out"
[ "$(grep -c cites <<<"$out")" = 3 ] || fail "complained about something that is there:"$'\n'"$out"

printf "## 2. Two\n" >>"$tree/docs/method.$md"
touch "$tree/docs/design.$md"
printf "/// As in docs/method.$md §1 and docs/method.$md §1–2.\n/// And docs/design.$md.\n" >"$tree/include/x.hpp"
out=$(bash "$check" "$tree" 2>&1) || fail "refused a tree whose citations all resolve:"$'\n'"$out"
echo "citation_check_test: ok"
