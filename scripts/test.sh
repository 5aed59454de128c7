#!/usr/bin/env bash
# Every test: installs what it needs, builds the host preset, runs ctest (cmocka units, sim tests,
# scenario tests), pytest for the Python tools, and the cross build of the firmware for the
# Cortex-M4F (warnings are errors there too; it prints the section sizes).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
scripts/build.sh

status=0
echo "== ctest (unit, sim, integration)"
ctest --preset host -j "$(nproc)" || status=1

echo "== pytest (tools)"
.venv/bin/python -m pytest -q tools/tests || status=1

echo "== cross build: the firmware (core, control, estimators, drive) for arm-cm4f"
rm -rf build/arm-cm4f
if cmake --preset arm-cm4f >/dev/null && cmake --build --preset arm-cm4f; then
  echo "arm-cm4f: built with no warnings"
else
  echo "arm-cm4f: FAILED"
  status=1
fi
exit $status
