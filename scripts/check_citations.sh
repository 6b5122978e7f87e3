#!/usr/bin/env bash
# Checks that every Markdown file the project cites exists in the repository, and every cited section
# `§N` (or range `§N–M`) of it has a heading `## N.`:  bash scripts/check_citations.sh [source-dir]
#
# A citation is any `<name>.md` or `<path>/<name>.md` in the text files of include/, tests/, examples/,
# bench/, scripts/, docs/, cmake/ and README.md (comments, strings and Markdown links alike). It must
# resolve from the repository's root or from the citing file's directory (Markdown links are relative).
# Prints every dangling citation as file:line and exits 1 if there is one. tests/docs runs it under ctest.
set -euo pipefail
root=$(cd "${1:-$(dirname "$0")/..}" && pwd)
cd "$root"

# A path token ending in .md, not part of a URL or a <placeholder.md>, optionally followed by a section.
citation='(?<![\w/.:<-])(?:\.\./|[\w.-]+/)*[\w.-]+\.md(?![\w])(?:[`)]?\s{0,2}§\s*\d+(?:\s*[–-]\s*\d+)?)?'

status=0
complain() {
  echo "$1: $2" >&2
  status=1
}

scan=()
for part in include tests examples bench scripts docs cmake README.md; do [ -e "$part" ] && scan+=("$part"); done
while IFS= read -r file; do
  dir=$(dirname "$file")
  while IFS=: read -r line match; do
    path=$(grep -oP '^(?:\.\./|[\w.-]+/)*[\w.-]+\.md' <<<"$match")
    if [ -f "$path" ]; then
      target=$path
    elif [ -f "$dir/$path" ]; then
      target=$dir/$path
    else
      complain "$file:$line" "cites $path, which is not in the repository"
      continue
    fi
    # The sections cited: §N, or both ends of §N–M.
    for section in $(grep -oP '§\s*\K\d+(?:\s*[–-]\s*\d+)?' <<<"$match" | grep -oP '\d+'); do
      grep -qP "^#{2,}\s+$section\.(\s|$)" "$target" ||
        complain "$file:$line" "cites $path §$section, but $target has no heading '## $section.'"
    done
  done < <(grep -noP "$citation" "$file" | awk '!seen[$0]++' || true)
done < <(grep -rIl --exclude-dir=.git -P '\.md' "${scan[@]}" | sort)

[ "$status" = 0 ] && echo "citations: every cited document and section exists"
exit "$status"
