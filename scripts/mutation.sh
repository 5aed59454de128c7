#!/usr/bin/env bash
# Mutation run (docs/testing.md): universalmutator's one-line mutants of the firmware's C sources
# (or with --python the Python tools' key modules), each rebuilt and tested in a copy of the tree
# under build/mutation/, out/mutation/summary.json and report.md.
#   scripts/mutation.sh [--sample N] [--files GLOB[,GLOB]] [--seed S] [--timeout SEC] [--out DIR] [--python]
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/mutate ] || scripts/setup.sh
exec .venv/bin/python scripts/mutation.py "$@"
