#!/usr/bin/env bash
# Installs what the build, the demo and the tests need on a fresh Debian 12 machine (as root),
# and the Python tools into .venv. Safe to re-run: apt and pip skip what is already there.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(cmake ninja-build g++ gcc make pkg-config python3 python3-venv
              libeigen3-dev libcmocka-dev libtomlplusplus-dev libgtest-dev
              gcc-arm-none-eabi libnewlib-arm-none-eabi
              libunicorn-dev libcapstone-dev)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  python3 -m venv .venv
fi
if ! .venv/bin/python -c "import mctools, pytest, matplotlib, distributed, can, canopen, universalmutator, mutmut" 2>/dev/null ||
   [ ! -x .venv/bin/mctune ] || [ ! -x .venv/bin/mutate ]; then
  echo "setup: installing the Python tools into .venv"
  .venv/bin/pip install -q --upgrade pip
  .venv/bin/pip install -q -e "tools[test,can]"
fi
