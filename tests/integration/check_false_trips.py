#!/usr/bin/env python3
"""No false trips (protection issue): every scenario under scenarios/ but scenarios/faults/ (the
fault scenarios are meant to trip) x seeds 1..N runs without a fault, a recovery or a polarity flip (a
running re-check that turned the estimate by pi).

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
            return scen, model, seed, [f"mcsim exit {r.returncode}: {r.stderr.strip()[-200:]}"]
        m = json.loads(Path(d, "metrics.json").read_text())
        events = list(m.get("faults") or [])
        if m.get("recoveries"):
            events.append(f"recoveries={m['recoveries']} ({', '.join(m.get('recovered_from') or [])})")
        if m.get("polarity_flips"):
            events.append(f"polarity_flips={m['polarity_flips']}")
        return scen, model, seed, events


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
    bad, done = [], 0
    with cf.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as ex:
        for scen, model, seed, events in ex.map(lambda j: run(a.mcsim, j[0], j[1], j[2], a.profile), jobs):
            done += 1
            if events:
                bad.append(f"{scen.relative_to(a.root)}{f' [{model}]' if model else ''} seed {seed}: "
                           + ", ".join(events))
                print("FAIL:", bad[-1], flush=True)
            if done % 100 == 0:
                print(f"  {done}/{len(jobs)} runs done", flush=True)
    print(f"false trips: {len(jobs)} runs, {len(bad)} with a fault, a recovery or a polarity flip")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
