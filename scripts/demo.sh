#!/usr/bin/env bash
# The demo: build, run the default scenario in the simulator, render the plots.
# Usage: scripts/demo.sh [SCENARIO.toml] (default: scenarios/sensorless_demo.toml)
set -euo pipefail
cd "$(dirname "$0")/.."
scenario="${1:-scenarios/sensorless_demo.toml}"
name="$(basename "$scenario" .toml)"
out="out/$name"

scripts/setup.sh
scripts/build.sh
build/host/sim/app/mcsim run "$scenario" --out "$out"
.venv/bin/mctools plot "$out/trace.csv" --out "$out/plots" --metrics "$out/metrics.json" \
  --headline "angle_err_steady_max_deg,angle_err_max_deg,speed_err_steady_rms_rpm,current_peak_a,newton_iter_mean,fault_count"
echo
echo "demo: metrics in $out/metrics.json, trace in $out/trace.csv, plots in $out/plots/"
