#!/usr/bin/env python3
"""Round trip of a measured-map preset (issue 24, part 1): the thesis preset's analytic model is
tabulated into a map CSV (`mctools preset sun2016-ipm-5kw --export-map`), loaded as a `[flux_map]`
preset (psi_pm_wb, ld_h, lq_h omitted: derived from the map), and scenarios/sensorless_demo.toml
runs on both presets. The metrics must agree within tolerances set by the grid, not bit for bit:
the map is a 41 x 41 bilinear table of the closed form (node spacing ~1 A), inverted for the plant
and resampled for the estimator.

usage: check_fluxmap_roundtrip.py --mcsim MCSIM --python VENV_PYTHON --repo REPO [--out DIR]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

# |analytic - map| allowed per window of the demo; observed (41 x 41, Taylor integrator):
# angle mean <= 0.03 deg, torque <= 0.004 N m, i_d/i_q <= 0.002 A, window peaks <= 0.055 A,
# steady max angle 0.27 deg.
WINDOW_TOL = {"angle_err_mean_deg": 0.15, "speed_mean_rpm": 0.5, "torque_mean_nm": 0.05,
              "id_mean_a": 0.02, "iq_mean_a": 0.02, "current_peak_a": 0.2}
TOP_TOL = {"angle_err_steady_mean_deg": 0.1, "angle_err_steady_max_deg": 0.6, "speed_final_rpm": 1.0}
PRESET_KEYS = ["pole_pairs", "rs_ohm", "inertia_kgm2", "friction_nms", "i_rated_peak_a",
               "torque_rated_nm", "vdc_nominal_v", "f_sample_hz"]


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--python", required=True)
    ap.add_argument("--repo", required=True)
    ap.add_argument("--out")
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="fluxmap-roundtrip-")
    os.makedirs(out, exist_ok=True)
    csv = os.path.join(out, "sun2016-map.csv")
    run([a.python, "-m", "mctools", "preset", "sun2016-ipm-5kw", "--export-map", csv])
    import tomllib
    with open(os.path.join(a.repo, "presets", "sun2016-ipm-5kw.toml"), "rb") as f:
        src = tomllib.load(f)
    toml = os.path.join(out, "sun2016-map.toml")
    with open(toml, "w") as f:
        f.write('name = "sun2016-ipm-5kw-map"\n')
        for k in PRESET_KEYS:
            f.write(f"{k} = {src[k]!r}\n")
        f.write('[flux_map]\nfile = "sun2016-map.csv"\n')
    scn = os.path.join(a.repo, "scenarios", "sensorless_demo.toml")
    res = {}
    for tag, preset in (("analytic", "sun2016-ipm-5kw"), ("map", toml)):
        d = os.path.join(out, tag)
        run([a.mcsim, "run", scn, "--set", f"machine.preset={preset}", "--set", "output.trace=false",
             "--out", d, "--quiet"])
        with open(os.path.join(d, "metrics.json")) as f:
            res[tag] = json.load(f)
    an, mp = res["analytic"], res["map"]
    bad = []
    for k in ("faults", "final_state"):
        if an.get(k) != mp.get(k):
            bad.append(f"{k}: analytic {an.get(k)!r}, map {mp.get(k)!r}")
    if mp.get("fluxmap_outside_s") != 0:
        bad.append(f"fluxmap_outside_s = {mp.get('fluxmap_outside_s')}: the demo left the map's grid")
    for k, tol in TOP_TOL.items():
        if abs(an[k] - mp[k]) > tol:
            bad.append(f"{k}: analytic {an[k]}, map {mp[k]} (tolerance {tol})")
    for w, wa in an["windows"].items():
        for k, tol in WINDOW_TOL.items():
            x, y = wa[k], mp["windows"][w][k]
            line = f"{w}.{k}: analytic {x}, map {y}"
            print(line + f" (|diff| {abs(x - y):.4g}, tolerance {tol})")
            if abs(x - y) > tol:
                bad.append(line)
    if bad:
        sys.exit("FAIL: the map preset's run differs from the analytic one:\n  " + "\n  ".join(bad))
    print("OK: sensorless_demo on the exported map agrees with the analytic preset")

    # A map too small for the demo (+-4 A; the load needs i_q ~ 5.8 A): the run leaves the grid,
    # extrapolates, warns once on stderr with the time and reports the time outside.
    small = os.path.join(out, "sun2016-small.csv")
    run([a.python, "-m", "mctools", "preset", "sun2016-ipm-5kw", "--export-map", small,
         "--export-points", "9", "--export-span", "4"])
    with open(toml) as f:
        text = f.read().replace("sun2016-map.csv", "sun2016-small.csv")
    toml_small = os.path.join(out, "sun2016-small.toml")
    with open(toml_small, "w") as f:
        f.write(text)
    d = os.path.join(out, "small")
    p = run([a.mcsim, "run", scn, "--set", f"machine.preset={toml_small}", "--set", "output.trace=false",
             "--out", d, "--quiet"])
    with open(os.path.join(d, "metrics.json")) as f:
        ms = json.load(f)
    warn = [ln for ln in p.stderr.splitlines() if "leaves the flux map's grid" in ln]
    t0, outside = ms.get("fluxmap_first_outside_s"), ms.get("fluxmap_outside_s")
    print(f"small map: first outside at {t0} s, {outside} s outside; stderr: {warn}")
    if len(warn) != 1 or t0 is None or f"t = {t0:.6f} s" not in warn[0] or not outside > 0.5:
        sys.exit("FAIL: leaving the map's grid was not warned once with its time, or not measured")
    print("OK: leaving the grid is warned with its time and measured")


if __name__ == "__main__":
    main()
