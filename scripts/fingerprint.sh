#!/usr/bin/env bash
# Compares every filter's trajectories, bit for bit, between a git revision and the working tree:
#   bash scripts/fingerprint.sh [REV]      (REV defaults to HEAD)
# Builds tests/fingerprint/fingerprint.cpp (of the working tree) against the headers of REV and against
# those of the working tree, runs both on the reference measurement files and compares the 224
# fingerprints (tests/fingerprint/fingerprint.cpp says what they cover). Exits 1 and shows the
# differing cases when any differs. Takes about 5 minutes (two -O2 builds of every filter).
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:-HEAD}
work=$(mktemp -d)
trap 'git worktree remove --force "$work/old" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
git worktree add --detach "$work/old" "$rev" >/dev/null
mkdir -p "$work/data"
tar xJf tests/data/reference_measurements.tar.xz -C "$work/data"
eigen=$(pkg-config --cflags eigen3 2>/dev/null || echo -I/usr/include/eigen3)
build() {  # build <headers tree> <output>
  local tree=$1
  g++ -std=c++17 -O2 -DNDEBUG $eigen -I"$tree/include" -I"$tree/examples/support" \
    tests/fingerprint/fingerprint.cpp -o "$2"
}
build "$work/old" "$work/old.bin" &
build . "$work/new.bin"
wait
"$work/old.bin" "$work/data" >"$work/old.txt"
"$work/new.bin" "$work/data" >"$work/new.txt"
cases=$(wc -l <"$work/new.txt")
if diff "$work/old.txt" "$work/new.txt" >"$work/diff.txt"; then
  echo "fingerprints: all $cases identical to $rev"
else
  echo "fingerprints: these differ from $rev (< $rev, > working tree):"
  cat "$work/diff.txt"
  exit 1
fi
