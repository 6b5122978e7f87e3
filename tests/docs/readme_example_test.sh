#!/usr/bin/env bash
# The README's "Your own model" block is examples/your_own_model.cpp: the fenced block after the line
# `<!-- examples/your_own_model.cpp -->` in README.md must equal the lines of the file between
# `// BEGIN README EXAMPLE` and `// END README EXAMPLE`.   bash readme_example_test.sh <source-dir>
set -euo pipefail
cd "$1"
program=$(sed -n '/^\/\/ BEGIN README EXAMPLE$/,/^\/\/ END README EXAMPLE$/p' examples/your_own_model.cpp | sed '1d;$d')
quoted=$(awk '/^<!-- examples\/your_own_model.cpp -->$/ { marker = 1; next }
              marker && /^```cpp$/ { inside = 1; next }
              inside && /^```$/ { exit }
              inside { print }' README.md)
[ -n "$program" ] || { echo "readme_example_test: no BEGIN/END README EXAMPLE region in examples/your_own_model.cpp" >&2; exit 1; }
[ -n "$quoted" ] || { echo "readme_example_test: no quoted block after <!-- examples/your_own_model.cpp --> in README.md" >&2; exit 1; }
if [ "$program" != "$quoted" ]; then
  echo "readme_example_test: README.md's block differs from examples/your_own_model.cpp (< file, > README):" >&2
  diff <(echo "$program") <(echo "$quoted") >&2 || true
  exit 1
fi
echo "readme_example_test: ok"
