#!/usr/bin/env bash
# Behaviour fingerprint of the drive: runs every scenario (and a few variants: encoder, the model
# 10 % off, the harsh profile, flying starts at speed) with this build's mcsim and writes one
# sha256 per metrics.json (wall-time fields left out) and trace.csv to OUT/SUMS. A refactor that
# claims "no behaviour change" compares two builds' SUMS: `diff A/SUMS B/SUMS` prints nothing.
#   scripts/golden.sh OUT [MCSIM]      (MCSIM: build/host/sim/app/mcsim)
set -uo pipefail
cd "$(dirname "$0")/.."
out=$(mkdir -p "$1" && cd "$1" && pwd)
m=${2:-build/host/sim/app/mcsim}
[ -x "$m" ] || { echo "golden: no mcsim at $m (scripts/build.sh)" >&2; exit 2; }
: > "$out/rc.txt"
fail=0
run() {   # NAME SCENARIO [--set ...]
  local name=$1; shift
  timeout 600 "$m" run "$@" --out "$out/$name" --quiet > /dev/null 2> "$out/$name.err"
  local rc=$?
  echo "$name rc=$rc" >> "$out/rc.txt"
  [ $rc -eq 0 ] || fail=1
}
n=0
for s in $(find scenarios -name '*.toml' | sort); do
  case $s in *expected.toml|*sweeps.toml|*can_drive.toml) continue;; esac
  run "$(echo "$s" | tr / _)" "$s"; n=$((n + 1))
done
run demo_enc scenarios/sensorless_demo.toml --set 'control.angle_source="encoder"'
run demo_L09 scenarios/sensorless_demo.toml --set estimator.l_scale=0.9
run demo_harsh scenarios/sensorless_demo.toml --set 'scenario.profile="harsh"'
run fly1500 scenarios/flying/catch_dyno.toml --set mechanics.dyno_speed_rpm=1500
run flym1450 scenarios/flying/catch_dyno.toml --set mechanics.dyno_speed_rpm=-1450
run fly_b3000 scenarios/flying/catch_dyno_brodatzki.toml --set mechanics.dyno_speed_rpm=3000
(cd "$out" && for f in $(find . -name metrics.json -o -name trace.csv | sort); do
   printf "%s  %s\n" "$(grep -v -e wall_time_s -e realtime_factor "$f" | sha256sum | cut -c1-64)" "$f"
 done) > "$out/SUMS"
echo "golden: $n scenarios + 6 variants, $(wc -l < "$out/SUMS") files hashed into $out/SUMS$([ $fail -eq 0 ] || echo ', some runs failed: see rc.txt')"
exit $fail
