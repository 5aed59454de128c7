#!/usr/bin/env bash
# The demo: build, run the default scenario in the simulator, render the plots.
# Usage: scripts/demo.sh [SCENARIO.toml] (default: scenarios/speed_step_inertia.toml)
set -euo pipefail
cd "$(dirname "$0")/.."
scenario="${1:-scenarios/speed_step_inertia.toml}"
name="$(basename "$scenario" .toml)"
out="out/$name"

scripts/setup.sh
scripts/build.sh
build/host/sim/app/mcsim run "$scenario" --out "$out"
.venv/bin/mctools plot "$out/trace.csv" --out "$out/plots" --metrics "$out/metrics.json" \
  --headline "speed_err_steady_max_pct,settling_time_s,current_peak_a,current_limit_a,angle_err_max_deg,fault_count"
echo
echo "demo: metrics in $out/metrics.json, trace in $out/trace.csv, plots in $out/plots/"
