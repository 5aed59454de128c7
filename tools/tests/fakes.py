"""Shared test inputs: a stand-in for the mcsim binary and the thesis preset as a TOML text."""

import stat
import sys
import textwrap
from pathlib import Path

# What every fake mcsim starts with: `run SCENARIO --set k=v ... --out DIR [--quiet]` parsed into
# `scenario` (the file's stem), `sets` (the raw TOML value strings) and `out`; anything else is
# rejected with exit status 2 like the real one.
_FAKE_HEAD = '''\
import json, math, os, pathlib, sys, time, tomllib
a = sys.argv[1:]
if not a or a[0] != "run":
    sys.exit(2)
scenario = pathlib.Path(a[1]).stem
sets, out, i = {}, None, 2
while i < len(a):
    if a[i] == "--set":
        k, v = a[i + 1].split("=", 1)
        sets[k] = v
        i += 2
    elif a[i] == "--out":
        out = pathlib.Path(a[i + 1])
        i += 2
    elif a[i] == "--quiet":
        i += 1
    else:
        print("bad arg", a[i], file=sys.stderr)
        sys.exit(2)
'''


def write_fake_mcsim(path: Path, body: str) -> Path:
    """An executable fake mcsim at `path`: the shared argument parsing, then `body`."""
    path.write_text(f"#!{sys.executable}\n" + _FAKE_HEAD + textwrap.dedent(body))
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


# The sun2016 preset with the machines.md fit (a_dq 1441.3), inline so that the tests do not
# depend on presets/ (which carries the recalibrated fit).
SUN_PRESET_TOML = """\
name = "sun2016-ipm-5kw"
pole_pairs = 5
rs_ohm = 0.400
psi_pm_wb = 0.34305
ld_h = 10.5e-3
lq_h = 12.9e-3
inertia_kgm2 = 0.013
friction_nms = 1.3e-3
i_rated_peak_a = 13.29
torque_rated_nm = 29.7
vdc_nominal_v = 300.0
f_sample_hz = 10000.0

[saturation]
S = 2.0
T = 2.0
U = 1.0
V = 0.0
a_d0 = 86.58
a_dd = 24.52
a_q0 = 58.12
a_qq = 774.0
a_dq = 1441.3
i_f = 30.69
"""
