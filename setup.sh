#!/usr/bin/env bash
# Installs exactly the Debian 12 packages handemo needs that are missing; non-interactive, idempotent.
# Usage: ./setup.sh            build, test and demo dependencies
#        ./setup.sh --golden   also python3-torch, to regenerate the PyTorch golden fixtures and run
#                              the side-by-side benchmark (bench/compare.sh)
#        ./setup.sh --fuzz     also clang 14 and its runtime libraries (libFuzzer, sanitizers), for the
#                              libFuzzer harnesses (-DHANDEMO_FUZZ=ON, tests/fuzz/) and the clang build
set -euo pipefail
pkgs=(g++ cmake make pkg-config libxtensor-dev libxsimd-dev xtl-dev nlohmann-json3-dev libstb-dev
      libhidapi-dev doctest-dev libbenchmark-dev libcli11-dev)
for arg in "$@"; do
  case "$arg" in
    --golden) pkgs+=(python3 python3-torch python3-numpy) ;;
    --fuzz) pkgs+=(clang-14 libclang-rt-14-dev) ;;
    *) echo "setup.sh: unknown option $arg (expected --golden or --fuzz)" >&2; exit 2 ;;
  esac
done
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
