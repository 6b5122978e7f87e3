#!/usr/bin/env bash
# The firmware stage of scripts/test.sh (docs/embedded.md): bash scripts/embedded.sh <host-build-dir> [--figures]
#   1. installs Debian's gcc-arm-none-eabi, newlib, libstdc++ for it and qemu-system-arm when missing;
#   2. builds examples/embedded for the Cortex-M4F (cmake/arm-none-eabi.cmake; -fno-exceptions -fno-rtti,
#      the project's warnings and -Wdouble-promotion as errors) and checks that the image holds no
#      allocator, operator new or exception machinery;
#   3. runs it under qemu-system-arm -M mps2-an386 (-icount shift=0) with a time limit: it must exit 0
#      (every filter ran the schedule, refused a broken R by name, ended near the true parameters, and
#      the wrapped malloc counted no call);
#   4. compares its float estimates with those of the host build of the same program
#      (<host-build-dir>/examples/embedded/mjukf_embedded_host, built if missing) to the tolerance of
#      docs/embedded.md: per filter and component, 4 × the largest |host float − host double| over the
#      run, plus 2 ulp;
#   5. does 2–3 for the same filters compiled without the health monitor and the MJUKF's automatic
#      modes (robot_all_lean, features.hpp), and requires their estimates to be those of step 3 bit for bit.
# --figures also builds every variant at -O2 and -Os, with every feature and without the optional
# ones, and prints the tables of docs/embedded.md.
set -euo pipefail
cd "$(dirname "$0")/.."
host=${1:?usage: scripts/embedded.sh <host-build-dir> [--figures]}
figures=${2:-}
bash scripts/setup.sh gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib qemu-system-arm
jobs=$(nproc)
out="$host-embedded"
mkdir -p "$out"

# $1 build dir, $2 optimisation, $3… targets
build_firmware() {
  local dir=$1 opt=$2
  shift 2
  cmake -S examples/embedded -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$PWD/cmake/arm-none-eabi.cmake" \
    -DMJUKF_FIRMWARE_OPT="$opt" >/dev/null
  cmake --build "$dir" -j "$jobs" --target "$@"
}

# $1 image, $2 output file. QEMU's semihosting console is the program's stdout.
run_firmware() {
  timeout 120 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none -icount shift=0 \
    -chardev stdio,id=console -semihosting-config enable=on,target=native,chardev=console -kernel "$1" >"$2"
}

# No allocator, no operator new/delete, no exception machinery linked in (the --wrap counters excepted).
check_symbols() {
  local found
  # "<8 hex digits or spaces> <type> <name>": the name alone, spaces in it kept.
  found=$(arm-none-eabi-nm -C "$1" | sed -E 's/^[0-9a-fA-F ]{8} [A-Za-z] //' |
    grep -E '^(malloc|_malloc_r|calloc|_calloc_r|realloc|_realloc_r|free|_free_r|operator new|operator delete|__cxa_allocate_exception|__cxa_throw|__gxx_personality_v0)\b' || true)
  if [ -n "$found" ]; then
    echo "error: $1 links heap or exception code:" >&2
    echo "$found" >&2
    return 1
  fi
}

# Decodes the hex float/double bits of "est" lines and compares target (file 1) with host (file 2).
compare_runs() {
  awk '
    function hexval(s,   i, v) { v = 0; for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1; return v }
    function decode(h,   hi, e, m, s, bits) {
      if (length(h) == 8) { bits = hexval(h); s = int(bits / 2^31); e = int(bits / 2^23) % 256; m = bits % 2^23
        v = (e == 0) ? m / 2^23 * 2^-126 : (1 + m / 2^23) * 2^(e - 127) }
      else { hi = hexval(substr(h, 1, 3)); s = int(hi / 2048); e = hi % 2048; m = hexval(substr(h, 4))
        v = (e == 0) ? m / 2^52 * 2^-1022 : (1 + m / 2^52) * 2^(e - 1023) }
      return s ? -v : v
    }
    function abs(x) { return x < 0 ? -x : x }
    FNR == 1 { file++ }
    $1 != "est" { next }
    file == 1 && $2 == "f" { for (i = 5; i <= NF; i++) target[$3, $4, i] = decode($i); rows[$3, $4] = NF; next }
    file == 2 && $2 == "f" { for (i = 5; i <= NF; i++) hostf[$3, $4, i] = decode($i); hostrows[$3, $4] = 1; next }
    file == 2 && $2 == "d" { for (i = 5; i <= NF; i++) hostd[$3, $4, i] = decode($i); next }
    END {
      for (key in rows) {   # the scale of float rounding: largest |float - double| per filter and component
        split(key, k, SUBSEP)
        for (i = 5; i <= rows[key]; i++) {
          if (!((k[1], k[2], i) in hostf)) { print "no host row for " k[1] " " k[2]; bad++; continue }
          d = abs(hostf[k[1], k[2], i] - hostd[k[1], k[2], i]); if (d > scale[k[1], i]) scale[k[1], i] = d
        }
      }
      for (key in rows) {
        split(key, k, SUBSEP)
        for (i = 5; i <= rows[key]; i++) {
          diff = abs(target[k[1], k[2], i] - hostf[k[1], k[2], i])
          tol = 4 * scale[k[1], i] + 2 * 2^-23 * abs(hostd[k[1], k[2], i])
          if (diff > tol) { printf "%s row %s value %d: target %.9g host %.9g (tolerance %.3g)\n", k[1], k[2], i - 4, target[k[1], k[2], i], hostf[k[1], k[2], i], tol; bad++ }
          if (tol > 0 && diff / tol > worst[k[1]]) worst[k[1]] = diff / tol
          compared++
        }
      }
      for (key in hostrows) if (!(key in rows)) { split(key, k, SUBSEP); print "the target printed no row " k[2] " of " k[1]; bad++ }
      for (f in worst) printf "  %-6s largest |target - host| = %.2f of the tolerance\n", f, worst[f]
      if (!compared) { print "nothing compared"; exit 1 }
      printf "compared %d values: %s\n", compared, bad ? bad " outside the tolerance" : "all within the tolerance"
      exit bad ? 1 : 0
    }' "$1" "$2"
}

echo "== firmware: build (-O2), symbols, run under QEMU, compare with the host's float run"
build_firmware "$out/O2" -O2 robot_checked  # robot_all and robot_all_lean, compiled in parallel
image="$out/O2/robot_all.elf"
check_symbols "$image"
run_firmware "$image" "$out/target.txt" || { cat "$out/target.txt"; echo "error: the firmware failed" >&2; exit 1; }
grep -v '^est' "$out/target.txt"
cmake --build "$host" -j "$jobs" --target mjukf_embedded_host
"$host/examples/embedded/mjukf_embedded_host" >"$out/host.txt"
compare_runs "$out/target.txt" "$out/host.txt"

echo "== firmware without the health monitor and the automatic modes (-O2): symbols, run, the same estimates"
check_symbols "$out/O2/robot_all_lean.elf"
run_firmware "$out/O2/robot_all_lean.elf" "$out/target-lean.txt" ||
  { cat "$out/target-lean.txt"; echo "error: the firmware without the optional features failed" >&2; exit 1; }
grep '^fig' "$out/target-lean.txt" | sed 's/^fig /fig lean /'
if ! cmp -s <(grep '^est' "$out/target.txt") <(grep '^est' "$out/target-lean.txt"); then
  diff <(grep '^est' "$out/target.txt") <(grep '^est' "$out/target-lean.txt") | head -5
  echo "error: the filters without the optional features estimated otherwise" >&2
  exit 1
fi
echo "the same $(grep -c '^est' "$out/target.txt") estimate rows, bit for bit"

[ "$figures" = --figures ] || exit 0

echo "== figures: flash of each filter (image minus the plant-only image), -O2 and -Os"
filters="ukf jukf mjukf dual ukf_sr jukf_sr mjukf_sr dual_sr"
# Every filter with every feature, without the optional ones (_lean), and the MJUKF with the monitor
# but without the automatic modes (_fixed).
variants="$filters $(printf '%s_lean ' $filters) mjukf_fixed mjukf_sr_fixed"
build_firmware "$out/Os" -Os robot_images
build_firmware "$out/O2" -O2 robot_images
run_firmware "$out/Os/robot_all.elf" "$out/target-Os.txt"
run_firmware "$out/Os/robot_all_lean.elf" "$out/target-lean-Os.txt"
for opt in O2 Os; do
  base=$(arm-none-eabi-size "$out/$opt/robot_none.elf" | awk 'NR == 2 { print $1 + $2 }')
  echo "-$opt: plant-only image $base B (text + data)"
  for f in $variants all all_lean; do
    size=$(arm-none-eabi-size "$out/$opt/robot_$f.elf" | awk 'NR == 2 { print $1 + $2 }')
    echo "  $f: $size B, own cost $((size - base)) B"
  done
done
echo "== figures: per filter, from the runs (-O2, then -Os; every feature, then without the optional ones)"
for run in target target-Os target-lean target-lean-Os; do
  echo " $run:"
  awk '$1 == "clock" { perTick = $3 / $5 }
       $1 == "fig" { printf "  %-8s sizeof %5d B  stack %4d B  instructions/measurement step %6.0f  /open-loop step %5.0f\n",
                     $3, $5, $15, $7 * perTick / $9, $11 * perTick / $13 }
       $1 == "clock" { printf "  %s instructions / %s ticks = %.3f instructions a tick\n", $3, $5, perTick }
       $1 == "heap" { print "  heap calls " $3 }' "$out/$run.txt"
done
