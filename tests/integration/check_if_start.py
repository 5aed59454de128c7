#!/usr/bin/env python3
"""if_start_spm: the I/f start (issue 24, Deliver 4) on the surface-PM servo without saliency
(siemens-1ft7044-spm, Lq = Ld): `mctools sweep zoo`'s start cell, free rotor under a 50 % rated
reactive load, startup.init_pos = auto, at 8 rotor angles. Each run must reach RUN without a fault,
must have run I/f (if_open_s > 0) and handed over (the steady window after it has an estimated
angle), with the steady angle error <= 3 deg and the peak phase current <= 1.1 x the limit. Also:
an explicit three_step on this motor is still refused at configuration, with the reason, and so
is if_start with an angle sensor."""
import json
import subprocess
import sys
from pathlib import Path

mctools, mcsim, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
motor = "siemens-1ft7044-spm"
js = out / "zoo.json"
cmd = [mctools, "sweep", "zoo", "--motors", motor, "--short", "--mcsim", mcsim,
       "--out", str(out / "runs"), "--json", str(js)]
proc = subprocess.run(cmd, capture_output=True, text=True)
print(proc.stdout[-2000:])
if proc.returncode != 0:
    print(proc.stderr[-3000:], file=sys.stderr)
    sys.exit(f"if_start_spm: exit {proc.returncode}")
cells = {c["test"]: c for c in json.loads(js.read_text())["cells"] if c["motor"] == motor}
start = cells.get("start")
errors = []
if start is None or len(start.get("angles", [])) != 8:
    sys.exit(f"if_start_spm: no start cell of 8 angles: {start}")
for a in start["angles"]:
    mx = json.loads((Path(a["dir"]) / "metrics.json").read_text())
    where = f"{a['angle']} deg"
    if mx.get("faults") or mx.get("final_state") != "RUN":
        errors.append(f"{where}: faults {mx.get('faults')}, final state {mx.get('final_state')}")
    if not (mx.get("if_open_s") or 0.0) > 0.0:
        errors.append(f"{where}: the drive did not run I/f (if_open_s {mx.get('if_open_s')})")
    w = (mx.get("windows") or {}).get("after_handover") or {}
    if w.get("if_open_share") != 0 or w.get("angle_err_max_deg") is None:
        errors.append(f"{where}: not handed over in the window (if_open_share {w.get('if_open_share')})")
    elif abs(w["angle_err_max_deg"]) > 3.0:
        errors.append(f"{where}: steady angle error {w['angle_err_max_deg']:.2f} deg > 3")
    if mx["current_peak_a"] > 1.1 * mx["current_limit_a"]:
        errors.append(f"{where}: peak {mx['current_peak_a']:.2f} A > 1.1 x {mx['current_limit_a']:g} A")
if not start["passed"]:
    errors.append(f"the zoo's start cell: {start['text']}")
# an explicit three-step start on this motor stays a refusal (exit 2) naming the key
scen = Path(start["angles"][0]["dir"]).parent / "start_if.toml"
ref = subprocess.run([mcsim, "check", str(scen), "--set", 'startup.init_pos="three_step"'],
                     capture_output=True, text=True)
if ref.returncode != 2 or "startup.init_pos" not in ref.stderr or "saliency" not in ref.stderr:
    errors.append(f"three_step not refused with the reason (exit {ref.returncode}): {ref.stderr[-300:]}")
# ... and the I/f start with an angle sensor is refused (it knows the angle)
enc = subprocess.run([mcsim, "check", str(scen), "--set", 'startup.init_pos="if_start"',
                      "--set", 'control.angle_source="encoder"'], capture_output=True, text=True)
if enc.returncode != 2 or "sensorless" not in enc.stderr:
    errors.append(f"if_start with an encoder not refused (exit {enc.returncode}): {enc.stderr[-300:]}")
if errors:
    sys.exit("if_start_spm: " + "; ".join(errors))
print("if_start_spm: ok (8 angles)")
