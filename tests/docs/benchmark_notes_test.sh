#!/usr/bin/env bash
# The benchmark pages end with hand-written notes that their reports append when they regenerate them:
# docs/performance.md with bench/performance_notes.md as it is (bench/report.py) and
# docs/performance-scaling.md with bench/compile_time_notes.md less its `<!--` lines
# (bench/scaling_report.py). A note edited on the page alone would be lost at the next run of
# scripts/bench.sh or scripts/scaling.sh, so each page must end with its notes, line for line. (Text
# written by hand among a page's generated tables is not caught here; it belongs in the notes.)
#   bash benchmark_notes_test.sh <source-dir>
set -euo pipefail
cd "$1"
status=0
check() {  # <page> <notes> <lines dropped from the notes: an extended regular expression, or "">
  local notes page_tail lines
  [ -f "$2" ] || { echo "benchmark_notes_test: $2 is missing" >&2; status=1; return; }
  if [ -n "$3" ]; then notes=$(grep -Ev "$3" "$2" || true); else notes=$(cat "$2"); fi
  [ -n "$notes" ] || { echo "benchmark_notes_test: $2 has no notes" >&2; status=1; return; }
  lines=$(printf '%s\n' "$notes" | wc -l)
  page_tail=$(tail -n "$lines" "$1")
  if [ "$page_tail" != "$notes" ]; then
    echo "benchmark_notes_test: $1 does not end with $2 (< notes, > page); edit the notes file too:" >&2
    diff <(printf '%s\n' "$notes") <(printf '%s\n' "$page_tail") | head -20 >&2 || true
    status=1
  fi
}
check docs/performance.md bench/performance_notes.md ""
check docs/performance-scaling.md bench/compile_time_notes.md '^<!--'
[ "$status" = 0 ] && echo "benchmark_notes_test: ok"
exit "$status"
