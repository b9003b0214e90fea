#!/usr/bin/env bash
# Installs exactly the Debian 12 packages handemo needs that are missing; non-interactive, idempotent.
# Usage: ./setup.sh               build, test and demo dependencies, and Debian's chromium, which the
#                                 viewer test (CTest label browser) opens headless: about 110 MB, 9 s to
#                                 download and install on the project's machine
#        ./setup.sh --no-browser  the same without chromium (the browser test then reports itself skipped)
#        ./setup.sh --chromium    accepted for clarity: chromium is in the default set
#        ./setup.sh --golden      also python3-torch, to regenerate the PyTorch golden fixtures and run
#                                 the side-by-side benchmark (bench/compare.sh)
#        ./setup.sh --cross       also the cross toolchains and emulators of the CTest label `cross`: aarch64
#                                 (g++-aarch64-linux-gnu, qemu-user) and Cortex-M (gcc-arm-none-eabi,
#                                 libstdc++-arm-none-eabi-newlib, qemu-system-arm: the same packages build and
#                                 run the Cortex-M7 and the Cortex-M55 firmware)
#        ./setup.sh --fuzz        also clang 14's runtime libraries (libFuzzer, sanitizers), for the
#                                 libFuzzer harnesses (-DHANDEMO_FUZZ=ON, tests/fuzz/)
#        ./setup.sh --mpi         also Debian's Open MPI (libopenmpi-dev, openmpi-bin): training across processes
#                                 (target handemo::mpi, `handemo train --mpi`, CTest label mpi; docs/scale-out.md)
# clang-14 itself is in the default set: the test clang_syntax compiles the library with it.
set -euo pipefail
# libgif-dev: giflib, the animated GIFs of `handemo render --animate` and the demo (target handemo::gif).
pkgs=(g++ cmake make pkg-config libxtensor-dev libxsimd-dev xtl-dev nlohmann-json3-dev libstb-dev libgif-dev
      libhidapi-dev doctest-dev libbenchmark-dev libcli11-dev
      libxtensor-blas-dev   # libxtensor-blas-dev: LAPACK-backed solves of the circumplex maps (target handemo::rcm)
      clang-14)             # clang-14: the second compiler of the test clang_syntax (label clang)
browser=1
for arg in "$@"; do
  case "$arg" in
    --golden) pkgs+=(python3 python3-torch python3-numpy) ;;
    --cross) pkgs+=(g++-aarch64-linux-gnu qemu-user gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib qemu-system-arm) ;;
    --fuzz) pkgs+=(libclang-rt-14-dev) ;;
    --mpi) pkgs+=(libopenmpi-dev openmpi-bin) ;;
    --chromium) browser=1 ;;
    --no-browser) browser=0 ;;
    *) echo "setup.sh: unknown option $arg (expected --golden, --cross, --fuzz, --mpi, --chromium, --no-browser)" >&2; exit 2 ;;
  esac
done
if ((browser)); then pkgs+=(chromium); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then exit 0; fi
echo "setup.sh: installing ${missing[*]}" >&2
sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
