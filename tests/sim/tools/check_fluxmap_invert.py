#!/usr/bin/env python3
"""fluxmap-invert on bad input: exit status 2 with a one-line-ish message naming the problem, never
an abort (uncaught exception) or a run without bound. Also usable under pytest
(FLUXMAP_INVERT=path/to/fluxmap-invert).

usage: check_fluxmap_invert.py PATH/TO/fluxmap-invert
"""
import os
import subprocess
import sys
import tempfile


def write_map(path, f, n=5):
    rows = ["i_d_A,i_q_A,psi_d_Wb,psi_q_Wb"]
    for a in range(n):
        for b in range(n):
            d, q = f(a, b)
            rows.append(f"{a},{b},{d!r},{q!r}")
    with open(path, "w") as fh:
        fh.write("\n".join(rows) + "\n")


def cases(tmp):
    const = os.path.join(tmp, "const.csv")
    write_map(const, lambda a, b: (0.5, 0.25))
    flat_q = os.path.join(tmp, "flat_q.csv")
    write_map(flat_q, lambda a, b: (0.01 * a, 0.25))
    degen = os.path.join(tmp, "degen.csv")
    write_map(degen, lambda a, b: (0.01 * (a + b), 0.02 * (a + b)))
    good = os.path.join(tmp, "good.csv")
    write_map(good, lambda a, b: (0.01 * a + 0.001 * b, 0.02 * b))
    out = os.path.join(tmp, "out.csv")
    return [
        # (name, args, expected exit status, substrings of stderr)
        ("constant map", [const, out], 2, ["constant"]),
        ("psi_q constant", [flat_q, out], 2, ["constant"]),
        ("degenerate map", [degen, out], 2, ["degenerate"]),
        ("huge --grid", [good, out, "--grid", "100000", "100000"], 2, ["--grid", "1001"]),
        ("overflowing --grid", [good, out, "--grid", "99999999999999999999", "5"], 2, ["--grid"]),
        ("huge --n", ["--from-preset", "sun2016-ipm-5kw", out, "--n", "5000"], 2, ["--n", "1001"]),
        ("--imax inf", ["--from-preset", "sun2016-ipm-5kw", out, "--imax", "inf"], 2, ["--imax"]),
        ("--imax nan", ["--from-preset", "sun2016-ipm-5kw", out, "--imax", "nan"], 2, ["--imax"]),
        ("/dev/zero input", ["/dev/zero", out], 2, ["not a regular file"]),
        ("directory input", [tmp, out], 2, ["not a regular file"]),
        ("missing input", [os.path.join(tmp, "nope.csv"), out], 2, ["nope.csv"]),
        ("unknown preset", ["--from-preset", "no-such-machine", out], 2, ["not found"]),
        ("good map", [good, out], 0, []),
    ]


def run_all(exe):
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, args, want, needles in cases(tmp):
            try:
                r = subprocess.run([exe] + args, capture_output=True, timeout=60)
            except subprocess.TimeoutExpired:
                failures.append(f"{name}: timeout")
                continue
            err = r.stderr.decode("utf-8", "replace")
            if r.returncode != want:
                failures.append(f"{name}: exit {r.returncode}, expected {want}; stderr: {err[:300]}")
                continue
            if want == 2 and len(r.stderr) > 2048:
                failures.append(f"{name}: stderr {len(r.stderr)} bytes")
            for s in needles:
                if s not in err:
                    failures.append(f"{name}: '{s}' not in stderr: {err[:300]}")
            print(f"ok  {name}: {err.splitlines()[0] if err else '(exit 0)'}")
    return failures


def test_fluxmap_invert_bad_input():
    exe = os.environ.get("FLUXMAP_INVERT")
    if not exe:
        import pytest
        pytest.skip("set FLUXMAP_INVERT to the fluxmap-invert binary")
    assert run_all(exe) == []


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    f = run_all(sys.argv[1])
    for line in f:
        print("FAIL", line)
    sys.exit(1 if f else 0)
