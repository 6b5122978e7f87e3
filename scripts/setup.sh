#!/usr/bin/env bash
# Installs what mjukf needs to build, test and plot on Debian 12, when it is missing:
# bash scripts/setup.sh [more packages…] (scripts/embedded.sh adds the ARM toolchain and QEMU).
set -euo pipefail
# clang and libclang-rt-14-dev: the libFuzzer target (-fsanitize=fuzzer) of scripts/test.sh; doxygen:
# the API reference (target mjukf_docs); clang-format (14 on Debian 12): scripts/check_format.sh.
packages=(cmake g++ make xz-utils libeigen3-dev libsundials-dev libgtest-dev libbenchmark-dev gnuplot-nox clang libclang-rt-14-dev
  doxygen clang-format "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
((${#missing[@]})) || exit 0

echo "Installing: ${missing[*]}"
run_as_root=()
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null 2>&1; then
    echo "error: these Debian packages are missing and installing them needs root (no sudo here):" >&2
    echo "  apt-get install ${missing[*]}" >&2
    exit 1
  fi
  run_as_root=(sudo)
fi
# env, not a variable assignment in front: sudo resets the environment.
"${run_as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
"${run_as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
