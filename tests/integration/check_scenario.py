#!/usr/bin/env python3
"""Run one mcsim scenario and assert on its metrics.json.

    check_scenario.py --mcsim PATH --scenario FILE --out DIR [--set k=v]... \
        --expect 'windows.steady.speed_err_max_pct < 1' --expect 'current_peak_a <= @current_limit_a'

A right-hand side starting with @ names another metric. Every expectation is checked and printed;
the exit status is 1 if any fails (or if mcsim fails), so ctest reports the scenario as failed.
"""
import argparse
import json
import math
import operator
import re
import subprocess
import sys

OPS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge, "==": operator.eq, "!=": operator.ne}


def lookup(metrics, path):
    node = metrics
    for part in path.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]   # faults.0: the first fault reason
            continue
        if not isinstance(node, dict) or part not in node:
            raise KeyError(path)
        node = node[part]
    return node


def parse_value(metrics, text):
    text = text.strip()
    if text.startswith("@"):
        return lookup(metrics, text[1:])
    if text.startswith('"') and text.endswith('"'):
        return text[1:-1]
    if text in ("[]",):
        return []
    return float(text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--expect", action="append", default=[])
    a = ap.parse_args()

    cmd = [a.mcsim, "run", a.scenario, "--out", a.out, "--quiet"]
    for s in a.set:
        cmd += ["--set", s]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(f"FAIL: {' '.join(cmd)} exited {r.returncode}\n{r.stderr}")
        return 1
    with open(f"{a.out}/metrics.json") as f:
        metrics = json.load(f)

    failed = 0
    for e in a.expect:
        m = re.match(r"^\s*([\w.]+)\s*(<=|>=|==|!=|<|>)\s*(.+)$", e)
        if not m:
            print(f"FAIL: cannot parse expectation '{e}'")
            failed += 1
            continue
        path, op, rhs = m.groups()
        try:
            lhs = lookup(metrics, path)
            want = parse_value(metrics, rhs)
        except KeyError as k:
            print(f"FAIL: {e}: metric {k} missing")
            failed += 1
            continue
        ok = lhs is not None and not (isinstance(lhs, float) and math.isnan(lhs)) and OPS[op](lhs, want)
        print(f"{'ok  ' if ok else 'FAIL'}: {path} = {lhs!r} {op} {rhs.strip()}" + (f" ({want!r})" if rhs.strip().startswith("@") else ""))
        failed += 0 if ok else 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
