#!/usr/bin/env python3
"""No false trips (protection issue): every scenario under scenarios/ but scenarios/faults/ (the
fault scenarios are meant to trip) x seeds 1..N runs without a fault, a recovery or a polarity flip (a
running re-check that turned the estimate by pi). And the current limit is a limit (issue 24,
Deliver 7): every run's peak phase current is at most 1.1 x its configured limit, except the
known, documented cases in OVER_LIMIT, each held to the ratio measured (it may not get worse).

    check_false_trips.py --mcsim PATH [--seeds 10] [--profile realistic|harsh] [--root DIR]

The thesis scenarios run with both estimator models (const, fluxmap). Prints progress, one line
per run with a fault or recovery, and a summary; exits 1 if any run faulted, recovered or failed.
"""
import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

SKIP = {"expected.toml", "sweeps.toml"}   # tables of bounds and sweeps, not scenarios
LIMIT_X = 1.1
# Known runs over 1.1 x the limit (issue 24, Deliver 7, open): scenario -> (the worst ratio over
# seeds 1..10 measured, why). A case fixed comes out of the list; a new one fails.
OVER_LIMIT = {
    "scenarios/brodatzki/torque_steps_0rpm.toml": (
        1.30, "the 0 -> 127 A q step overshoots to 193 A: the current-loop gain from the small-signal "
              "Lq at i = 0 while the saturated incremental l_qq is far smaller (docs/zoo.md, Baldor)"),
}


def waits_for_bus(path: Path) -> bool:
    """A scenario whose commands come over CANopen (scenarios/can_drive.toml): without a bus it
    only idles for its (long) duration; the CAN end-to-end test runs it instead."""
    import tomllib  # noqa: PLC0415
    with open(path, "rb") as f:
        return tomllib.load(f).get("can", {}).get("commands") == "canopen"


def scenarios(root: Path) -> list[Path]:
    out = []
    for sub in ("", "brodatzki", "envelope", "flying", "thesis"):
        d = root / "scenarios" / sub if sub else root / "scenarios"
        out += sorted(p for p in d.glob("*.toml") if p.name not in SKIP and not waits_for_bus(p))
    return out


def run(mcsim: str, scen: Path, model: str | None, seed: int, profile: str) -> tuple:
    with tempfile.TemporaryDirectory() as d:
        cmd = [mcsim, "run", str(scen), "--out", d, "--quiet", "--set", "output.trace=false",
               "--set", f"scenario.seed={seed}", "--set", f'scenario.profile="{profile}"']
        if model:
            cmd += ["--set", f'estimator.model="{model}"']
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            return scen, model, seed, [f"mcsim exit {r.returncode}: {r.stderr.strip()[-200:]}"], 0.0
        m = json.loads(Path(d, "metrics.json").read_text())
        events = list(m.get("faults") or [])
        lim = m.get("current_limit_a") or 0.0
        ratio = (m.get("current_peak_a") or 0.0) / lim if lim else 0.0
        if m.get("recoveries"):
            events.append(f"recoveries={m['recoveries']} ({', '.join(m.get('recovered_from') or [])})")
        if m.get("polarity_flips"):
            events.append(f"polarity_flips={m['polarity_flips']}")
        return scen, model, seed, events, ratio


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--profile", default="realistic")
    ap.add_argument("--root", default=str(Path(__file__).resolve().parents[2]))
    a = ap.parse_args()
    jobs = [(s, m, k) for s in scenarios(Path(a.root))
            for m in (("const", "fluxmap") if s.parent.name == "thesis" else (None,))
            for k in range(1, a.seeds + 1)]
    print(f"false trips: {len(jobs)} runs ({a.profile} profile, seeds 1..{a.seeds})", flush=True)
    bad, done, worst = [], 0, {}
    with cf.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as ex:
        for scen, model, seed, events, ratio in ex.map(lambda j: run(a.mcsim, j[0], j[1], j[2], a.profile), jobs):
            done += 1
            key = str(scen.relative_to(a.root)) + (f" [{model}]" if model else "")
            if ratio > worst.get(key, (0.0, 0))[0]:
                worst[key] = (ratio, seed)
            if events:
                bad.append(f"{scen.relative_to(a.root)}{f' [{model}]' if model else ''} seed {seed}: "
                           + ", ".join(events))
                print("FAIL:", bad[-1], flush=True)
            if done % 100 == 0:
                print(f"  {done}/{len(jobs)} runs done", flush=True)
    print(f"false trips: {len(jobs)} runs, {len(bad)} with a fault, a recovery or a polarity flip")
    over = []
    for key, (ratio, seed) in sorted(worst.items()):
        known = OVER_LIMIT.get(key) if a.profile == "realistic" else None
        if ratio > LIMIT_X and not (known and ratio <= known[0]):
            over.append(f"{key} seed {seed}: peak {ratio:.3f} x the limit"
                        + (f" (known: {known[0]:.2f} x, {known[1]})" if known else ""))
            print("FAIL (current):", over[-1], flush=True)
        elif known:
            print(f"known over the limit: {key}: {ratio:.3f} x (held to {known[0]:.2f} x: {known[1]})")
    top = sorted(worst.items(), key=lambda kv: -kv[1][0])[:5]
    print("current limit: worst peak / limit " + ", ".join(f"{k} {r:.2f}" for k, (r, _) in top))
    print(f"current limit: {len(over)} scenario(s) above {LIMIT_X:g} x the limit beyond the known list")
    return 1 if bad or (over and a.profile == "realistic") else 0


if __name__ == "__main__":
    sys.exit(main())
