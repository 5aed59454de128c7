#!/usr/bin/env bash
# Every test: installs what it needs, builds the host preset, runs ctest (cmocka units, sim tests,
# scenario tests, processor-in-the-loop runs of the cross-built images), pytest for the Python
# tools, and the images' size budgets (the host build cross-builds them with warnings as errors).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
scripts/build.sh

status=0
echo "== ctest (unit, sim, integration)"
ctest --preset host -j "$(nproc)" || status=1

echo "== pytest (tools)"
.venv/bin/python -m pytest -q tools/tests || status=1

echo "== firmware images (cross-built by the host build: arm-cm4f = generic port on a Cortex-M4F, am263x = TI AM263x Cortex-R5F)"
for img in build/host/images/*/firmware/image/mc_image_*.elf; do
  [ -e "$img" ] || { echo "firmware images: none built (arm-none-eabi-gcc missing?)"; status=1; break; }
  python3 scripts/image_budget.py "$img" --code 98304 --ram 24576 | grep -E "^-- (image|code)" || status=1
done
echo "== mutation sample (docs/testing.md): the safety-relevant files, fixed seed, covering tests only"
# the lists of equivalent and must-kill mutants must sit on the lines they judge (after an edit:
# scripts/mutation_lists.py --remap BASE)
python3 scripts/mutation_lists.py --check || status=1
# A change that weakens the tests of protection, start-up, the store or CiA 402 shows here: the
# run fails if a mutant of scripts/mutation_must_kill.txt survives or the score falls below the
# threshold (docs/testing.md says why this one). The full run is scripts/mutation.sh (a benchmark).
scripts/mutation.sh --quick --no-baseline --seed 30 --sample 8 --timeout 60 \
  --files "firmware/app/protect.c,firmware/app/startup.c,firmware/app/param_store.c,firmware/app/store.c,firmware/comms/co_402.c" \
  --must-kill scripts/mutation_must_kill.txt --min-score 75 --work build/mutation-ci --out out/mutation-ci \
  --label "CI sample" | grep -E "^mutation:" || status=1
exit $status
