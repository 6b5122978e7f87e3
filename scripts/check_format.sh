#!/usr/bin/env bash
# Checks that every C++ source of the project is formatted as .clang-format says, with clang-format 14
# (another version formats some constructs differently):  bash scripts/check_format.sh [source-dir]
#
# The sources are the *.hpp and *.cpp files under include/, examples/, tests/ and bench/ that git tracks
# (every such file when the directory is not a git work tree). Prints each file that is not formatted,
# with the number of places clang-format would change, and exits 1 if there is one; exits 77 (ctest:
# skipped) when clang-format 14 is not installed, or 1 if MJUKF_REQUIRE_CLANG_FORMAT=1.
# `clang-format -i <file>` formats a file in place.
# tests/format runs it under ctest (format_check). CLANG_FORMAT names another binary of version 14.
set -euo pipefail
root=$(cd "${1:-$(dirname "$0")/..}" && pwd -P)
cd "$root"

# clang-format 14: Debian 12's clang-format-14, or a `clang-format` that is version 14.
version14() { "$1" --version 2>/dev/null | grep -qE 'clang-format version 14\.'; }
tool=${CLANG_FORMAT:-}
if [ -z "$tool" ]; then
  for candidate in clang-format-14 clang-format; do
    if command -v "$candidate" >/dev/null 2>&1 && version14 "$candidate"; then
      tool=$candidate
      break
    fi
  done
fi
if [ -z "$tool" ] || ! version14 "$tool"; then
  echo "check_format: clang-format 14 not found (Debian 12: apt-get install clang-format, which" \
    "scripts/setup.sh does); not checked" >&2
  # scripts/test.sh sets MJUKF_REQUIRE_CLANG_FORMAT=1: after its setup a missing formatter is an error.
  [ "${MJUKF_REQUIRE_CLANG_FORMAT:-0}" = 1 ] && exit 1
  exit 77
fi
[ -f .clang-format ] || { echo "check_format: no .clang-format in $root" >&2; exit 1; }

dirs=(include examples tests bench)
files=()
if [ "$(git rev-parse --show-toplevel 2>/dev/null)" = "$root" ]; then
  while IFS= read -r -d '' file; do files+=("$file"); done < \
    <(git ls-files -z -- "${dirs[@]/%//*.hpp}" "${dirs[@]/%//*.cpp}")
else
  existing=()
  for dir in "${dirs[@]}"; do [ -d "$dir" ] && existing+=("$dir"); done
  if ((${#existing[@]})); then
    while IFS= read -r -d '' file; do files+=("$file"); done < \
      <(find "${existing[@]}" -type f \( -name '*.hpp' -o -name '*.cpp' \) -print0 | sort -z)
  fi
fi

unformatted=0
for file in "${files[@]}"; do
  # --dry-run --Werror: one warning per place to change, and a non-zero exit if there is any.
  if ! out=$("$tool" --style="file:$root/.clang-format" --dry-run --Werror "$file" 2>&1); then
    places=$(grep -c 'clang-format-violations' <<<"$out" || true)
    if [ "$places" = 0 ]; then
      echo "check_format: $tool failed on $file:"$'\n'"$out" >&2
    else
      [ "$places" = 1 ] && what=place || what=places
      echo "$file: not formatted ($places $what to change)" >&2
    fi
    unformatted=$((unformatted + 1))
  fi
done

if [ "$unformatted" != 0 ]; then
  echo "check_format: $unformatted of ${#files[@]} files are not formatted as .clang-format says;" \
    "\`$tool -i <file>\` formats one" >&2
  exit 1
fi
echo "check_format: all ${#files[@]} C++ files are formatted ($tool)"
