#!/usr/bin/env python3
"""zoo_smoke: `mctools sweep zoo` on one motor (the thesis motor), one start angle, the short demo
and torque steps: the tool runs, the table and the JSON have every cell, and the thesis motor,
on which the default rules were made, passes its start, demo, torque-step and flying-start cells."""
import json
import subprocess
import sys
from pathlib import Path

mctools, mcsim, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
motor = "sun2016-ipm-5kw"
js, md = out / "zoo.json", out / "zoo.md"
cmd = [mctools, "sweep", "zoo", "--motors", motor, "--angles", "0", "--short", "--mcsim", mcsim,
       "--out", str(out / "runs"), "--json", str(js), "--md", str(md)]
proc = subprocess.run(cmd, capture_output=True, text=True)
print(proc.stdout[-3000:])
if proc.returncode != 0:
    print(proc.stderr[-3000:], file=sys.stderr)
    sys.exit(f"zoo_smoke: exit {proc.returncode}")
tests = ["start", "demo", "torque", "fly5", "fly50", "fly100", "demo_low_fs"]
cells = {c["test"]: c for c in json.loads(js.read_text())["cells"] if c["motor"] == motor}
errors = [f"no cell for {t}" for t in tests if t not in cells or not cells[t]["text"]]
row = [ln for ln in md.read_text().splitlines() if ln.startswith(f"| {motor} |") and "pass" in ln
       or ln.startswith(f"| {motor} |") and "FAIL" in ln]
if len(row) != 1 or len(row[0].strip().strip("|").split(" | ")) != 1 + len(tests):
    errors.append(f"the markdown row has not one cell per test: {row}")
for t in ("start", "demo", "torque", "fly5", "fly50", "fly100"):
    if t in cells and not cells[t]["passed"]:
        errors.append(f"{motor} {t}: {cells[t]['text']}")
if errors:
    sys.exit("zoo_smoke: " + "; ".join(errors))
print("zoo_smoke: ok")
