#!/usr/bin/env bash
# Configure and build the host preset (firmware + host HAL + simulator + tests).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc)"
