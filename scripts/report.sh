#!/usr/bin/env bash
# Runs every thesis scenario (scenarios/thesis/expected.toml) with both estimator models and
# writes docs/results.md plus the plots under out/thesis/. Extra arguments go to `mctools report`
# (e.g. --only fig6_12,fig6_14). The harsh realism profile is reported beside the realistic one
# (--profiles realistic,harsh: one more run per check, not judged); ctest runs realistic only.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
.venv/bin/mctools report --mcsim build/host/sim/app/mcsim --scenarios scenarios/thesis \
  --out out/thesis --doc docs/results.md --jobs "$(nproc)" --profiles realistic,harsh "$@"
