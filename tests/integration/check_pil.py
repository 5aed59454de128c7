#!/usr/bin/env python3
"""Processor-in-the-loop against the host build: the same scenario run twice, once with the
firmware built for the host and once as a cross-built image on the emulated core (mcsim run
--pil), every period traced. Passes when the angle the drive uses differs by less than --tol-deg
at every period, the drive's state is the same at every period, and the faults and final state
agree. Prints the cycle figures of the PIL run.

  check_pil.py --mcsim build/host/sim/app/mcsim --image IMAGE.elf --scenario S.toml
               [--set key=value]... [--tol-deg 0.1] [--out DIR]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys


def run(mcsim, scenario, out, sets, image=None):
    cmd = [mcsim, "run", scenario, "--quiet", "--out", out, "--set", "output.decimation=1"]
    for s in sets:
        cmd += ["--set", s]
    if image:
        cmd += ["--pil", image]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"check_pil: {' '.join(cmd)} exited {p.returncode}:\n{p.stderr}")
    with open(os.path.join(out, "metrics.json")) as f:
        m = json.load(f)
    with open(os.path.join(out, "trace.csv")) as f:
        rows = list(csv.DictReader(f))
    return m, rows


def wrap180(x):
    return (x + 180.0) % 360.0 - 180.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--image", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--tol-deg", type=float, default=0.1)
    ap.add_argument("--out", default="out/check_pil")
    a = ap.parse_args()
    if not os.path.exists(a.image):
        sys.exit(f"check_pil: image {a.image} not found (the host build cross-builds it: MC_BUILD_IMAGES)")
    # The image's timer quantises the duties; the host build does the same with the port's
    # compare resolution (reported by the PIL run), so both drive the plant with equal duties.
    mp, tp = run(a.mcsim, a.scenario, os.path.join(a.out, "pil"), a.set, a.image)
    host_sets = a.set + [f"inverter.pwm_counts={mp['pil_pwm_counts']}",
                         f"inverter.pwm_compare=\"{mp['pil_pwm_compare']}\""]
    mh, th = run(a.mcsim, a.scenario, os.path.join(a.out, "host"), host_sets)
    bad = []
    if len(th) != len(tp):
        bad.append(f"trace lengths differ: host {len(th)}, pil {len(tp)}")
    worst, worst_t, states_differ = 0.0, None, 0
    first_state_diff = None
    for rh, rp in zip(th, tp):
        if rh["state"] != rp["state"]:
            states_differ += 1
            if first_state_diff is None:
                first_state_diff = (rh["t_s"], rh["state"], rp["state"])
        a_h, a_p = float(rh["theta_hat_deg"]), float(rp["theta_hat_deg"])
        if math.isnan(a_h) != math.isnan(a_p):
            bad.append(f"t = {rh['t_s']} s: angle defined on one side only")
            break
        if not math.isnan(a_h):
            d = abs(wrap180(a_h - a_p))
            if d > worst:
                worst, worst_t = d, rh["t_s"]
    if states_differ:
        t, sh, sp = first_state_diff
        bad.append(f"state differs in {states_differ} periods (first at t = {t} s: host {sh}, pil {sp})")
    if worst >= a.tol_deg:
        bad.append(f"angle differs by {worst:.4f} deg at t = {worst_t} s (tolerance {a.tol_deg} deg)")
    for k in ("faults", "final_state"):
        if mh.get(k) != mp.get(k):
            bad.append(f"{k}: host {mh.get(k)}, pil {mp.get(k)}")
    print(f"check_pil: {os.path.basename(a.scenario)} on {mp.get('pil_core')} ({mp.get('pil_port')}): "
          f"{len(th)} periods, max angle difference {worst:.5f} deg, states equal in "
          f"{len(th) - states_differ}/{len(th)}, faults host {mh.get('faults')} pil {mp.get('faults')}")
    stages = mp.get("isr_stage_cycles_mean_run", {})
    print(f"  ISR cycles (estimated): mean {mp.get('isr_cycles_mean', 0):.0f}, max {mp.get('isr_cycles_max', 0):.0f}; "
          f"in RUN mean {mp.get('isr_cycles_mean_run', 0):.0f}, max {mp.get('isr_cycles_max_run', 0):.0f}; "
          f"instructions mean {mp.get('isr_instructions_mean', 0):.0f}")
    if stages:
        print("  per stage in RUN (mean): " + ", ".join(f"{k} {v:.0f}" for k, v in stages.items()))
    for b in bad:
        print("check_pil: FAIL: " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
