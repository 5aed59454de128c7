#!/usr/bin/env python3
"""Mutation fuzzer for mcsim's input handling: scenarios (scenarios/**/*.toml) and machine presets
(presets/*.toml). Python 3.11, standard library only.

Each mutation takes a seed scenario (one that `mcsim check` accepts unchanged), changes it (drop,
duplicate or add keys, swap types, extreme numbers 0, -0, +-1e300, nan, inf, huge strings, NUL and
quote characters, empty arrays, wrong nesting, random byte flips, truncation; or a preset mutated the
same way, written to a temp dir and selected with `machine.preset = "<its path>"`), then runs
`mcsim check` on it, and for a subset `mcsim run --set scenario.duration_s=0.02` (windows dropped).
Asserted, per call:
  * exit status 0 or 2 (no 1, no signal, no sanitizer report, no timeout),
  * exit 2: stderr is one short message (non-empty, <= 2 KB, <= 4 lines),
  * exit 0 of a run: metrics.json exists and parses with json.loads (strict UTF-8).
Failures are saved (scenario, preset, command, stderr) under --keep and summarised; exit status 1.

usage: fuzz_scenarios.py --mcsim PATH [--n N] [--seed S] [--timeout T] [--jobs J]
                         [--run-fraction F] [--only I] [--keep DIR] [--root DIR]
Reproduce one mutation: the same --seed and --only I (its index in the report).
"""
import argparse
import concurrent.futures as cf
import json
import math
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
MAX_STDERR = 2048
MAX_LINES = 4
RUN_DURATION = "0.02"

EXTREME_NUMBERS = [0, -0.0, 0.0, 1e300, -1e300, math.nan, math.inf, -math.inf, 1e-300, -1, -1e-9,
                   2**63 - 1, -2**63, 1e20, -1e20, 5e-324]
HUGE = 1_000_000


def odd_strings(rng):
    return rng.choice([
        "", "x" * HUGE, "a\0b", "\0", 'quo"te', "back\\slash", "'", "new\nline", "\x01\x7f",
        "\u00b5\u2026\U0001F600", "\ufffd", "\ud7ff", "nan", "inf", "1e300", "analytic", "taylor",
        "/dev/zero", "/nonexistent/preset.toml", "../" * 50 + "etc/passwd", "%s%n%x", "\t" * 1000,
    ])


# --------------------------------------------------------------------------------------------
# TOML writer (enough for the mutated documents: strings, numbers incl. nan/inf/-0, bools, arrays,
# inline tables; top-level tables as [sections]).

def toml_key(k):
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else toml_str(k)


def toml_str(s):
    out = ['"']
    for ch in s:
        o = ord(ch)
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif o < 0x20 or o == 0x7F:
            out.append("\\u%04x" % o)
        elif 0xD800 <= o <= 0xDFFF:
            out.append("\\ufffd")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def toml_value(v, depth=0):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        r = repr(v)
        return r if any(c in r for c in ".en") else r + ".0"
    if isinstance(v, str):
        return toml_str(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x, depth + 1) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(x, depth + 1)}" for k, x in v.items()) + "}"
    return toml_str(str(v))


def toml_dump(doc):
    lines = []
    for k, v in doc.items():
        if not isinstance(v, dict):
            lines.append(f"{toml_key(k)} = {toml_value(v)}")
    for k, v in doc.items():
        if isinstance(v, dict):
            lines.append(f"[{toml_key(k)}]")
            for kk, vv in v.items():
                lines.append(f"{toml_key(kk)} = {toml_value(vv)}")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------------------------
# The scenario schema, from `mcsim keys` (key, type, range or choices).

def read_schema(mcsim):
    out = subprocess.run([mcsim, "keys"], capture_output=True, text=True, timeout=60).stdout
    keys = {}
    for line in out.splitlines():
        m = re.match(r"\| `([^`]+)` \| ([^|]+) \|(.*)", line)
        if not m:
            continue
        cells = [c.strip() for c in m.group(3).split(" | ")]
        rng = cells[2] if len(cells) > 2 else ""
        lo = hi = None
        choices = []
        mm = re.match(r"([-+0-9.eE]+) \.\. ([-+0-9.eE]+)", rng)
        if mm:
            lo, hi = float(mm.group(1)), float(mm.group(2))
        elif "\\|" in rng or re.fullmatch(r"[a-z0-9_]+", rng or "-"):
            choices = [c for c in rng.replace("\\|", "|").split("|") if c]
        keys[m.group(1)] = {"type": m.group(2).strip(), "lo": lo, "hi": hi, "choices": choices}
    return keys


def in_range_value(rng, spec):
    """A value the schema accepts (boundaries favoured), to get past `check` into the runner."""
    t = spec["type"]
    lo, hi = spec["lo"], spec["hi"]
    if spec["choices"]:
        return rng.choice(spec["choices"])
    if t == "bool":
        return rng.choice([True, False])
    if lo is None:
        return None
    def num():
        x = rng.choice([lo, hi, lo, hi, (lo + hi) / 2, rng.uniform(lo, hi),
                        lo + (hi - lo) * 10 ** rng.uniform(-6, 0)])
        x = min(max(x, lo), hi)
        return int(round(x)) if t == "int" else float(x)
    if t == "int":
        return num()
    if t == "float[3]":
        return [num() for _ in range(3)]
    if t == "profile":
        if rng.random() < 0.5:
            return num()
        ts = sorted(rng.choice([0.0, 0.0, 0.005, 0.01, 0.01, 0.015]) for _ in range(rng.randint(1, 5)))
        return [[t_, num()] for t_ in ts]
    return num()


def wild_value(rng, spec=None):
    """Any value: wrong types, extremes, odd strings, nesting."""
    r = rng.random()
    if r < 0.35:
        return rng.choice(EXTREME_NUMBERS)
    if r < 0.55:
        return odd_strings(rng)
    if r < 0.62:
        return rng.choice([True, False])
    if r < 0.72:
        return rng.choice([[], [[]], [1], [1, 2, 3], [[0, 1]], [[0.0, math.nan]], [[1.0, 0], [0.5, 1]],
                           [[0, 1e300], [1e-300, -1e300]], [[math.inf, 1]], ["a", "b", "c"],
                           [0.0] * 100000, [[[[[[1]]]]]], [[0, 0]] * 5000])
    if r < 0.8:
        return rng.choice([{}, {"x": 1}, {"name": "w", "from_s": 0, "to_s": 0.01}, {"a": {"b": {}}}])
    if spec is not None:
        v = in_range_value(rng, spec)
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            return rng.choice([v * -1, v * 10, v * 1e6, v / 1e6, v + 1e-12, v - 1e-12, str(v), [v]])
        if v is not None:
            return v
    return rng.choice(EXTREME_NUMBERS)


# --------------------------------------------------------------------------------------------
# Mutators. Each returns (scenario_text_or_bytes, preset_bytes_or_None, description).

def leaves(doc):
    return [(s, k) for s, t in doc.items() if isinstance(t, dict) for k in t]


def set_key(doc, key, value):
    sec, _, name = key.partition(".")
    if not isinstance(doc.get(sec), dict):
        doc[sec] = {}
    doc[sec][name] = value


def mutate_doc(rng, doc, schema, valid_bias):
    """Structured mutations of a scenario dict, in place; returns descriptions."""
    what = []
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        op = rng.random()
        lv = leaves(doc)
        if valid_bias and op < 0.75:
            key = rng.choice(list(schema))
            if key == "metrics.window" or key == "machine.preset":
                continue
            v = in_range_value(rng, schema[key])
            if v is None:
                continue
            set_key(doc, key, v)
            what.append(f"set {key} = {toml_value(v)[:60]}")
        elif op < 0.15 and lv:
            s, k = rng.choice(lv)
            del doc[s][k]
            what.append(f"drop {s}.{k}")
        elif op < 0.55:
            key = rng.choice(list(schema))
            v = wild_value(rng, schema[key])
            set_key(doc, key, v)
            what.append(f"set {key} = {toml_value(v)[:60]}")
        elif op < 0.65 and lv:
            s, k = rng.choice(lv)
            v = wild_value(rng)
            doc[s][k] = v
            what.append(f"retype {s}.{k} = {toml_value(v)[:60]}")
        elif op < 0.72:
            sec = rng.choice(list(doc) or ["scenario"])
            name = rng.choice(["x", "speed_ref_rmp", "k" * HUGE, "a\0b", 'q"k', "", "\u00e9", "window"])
            if isinstance(doc.get(sec), dict):
                doc[sec][name] = wild_value(rng)
            what.append(f"unknown key in [{sec}] ({len(name)} chars)")
        elif op < 0.8:
            sec = rng.choice(list(doc) or ["scenario"])
            doc[sec] = wild_value(rng)  # a section that is not a table
            what.append(f"section {sec} replaced by a value")
        elif op < 0.87:
            v = rng.choice([{"inner": {"x": 1}}, {"name": "w"}, [{"name": "a", "from_s": 0.0, "to_s": 0.01}] * 3,
                            [{"name": "w", "from_s": 0.01, "to_s": 0.005}], [{"name": "", "from_s": 0, "to_s": 1}],
                            [{"name": 'q"\0', "from_s": 0, "to_s": 0.01}], [{"name": "a", "from_s": 0, "to_s": 1e300}],
                            [{"name": "d", "from_s": 0, "to_s": 0.01, "extra": 1}], [{}], []])
            set_key(doc, "metrics.window", v)
            what.append(f"metrics.window = {toml_value(v)[:60]}")
        else:
            key = rng.choice(list(schema))
            sec, _, name = key.partition(".")
            set_key(doc, key, {name: wild_value(rng)})  # wrong nesting: a table where a value goes
            what.append(f"nest {key}")
    return what


def mutate_bytes(rng, data):
    """Text-level damage: byte flips, truncation, inserted bytes, duplicated lines."""
    b = bytearray(data)
    op = rng.random()
    if op < 0.3 and b:
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(b))
            b[i] ^= 1 << rng.randrange(8)
        return bytes(b), "byte flips"
    if op < 0.5 and b:
        return bytes(b[: rng.randrange(len(b))]), "truncated"
    if op < 0.7:
        i = rng.randrange(len(b) + 1)
        ins = rng.choice([b"\0", b'"', b"'", b"\xff\xfe", b"[", b"]]", b"=", b"\n[scenario]\n", b"\\u0000",
                          b"\r", b"\x1b[2J", bytes(rng.randrange(256) for _ in range(16))])
        return bytes(b[:i] + ins + b[i:]), f"inserted {ins[:16]!r}"
    lines = bytes(b).split(b"\n")
    if lines:
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])  # duplicated key (or header)
    return b"\n".join(lines), "duplicated line"


def mutate_preset(rng, text):
    """A mutated copy of a preset: numbers to extremes or scaled, keys dropped, types swapped, or
    byte-level damage."""
    if rng.random() < 0.15:
        data, what = mutate_bytes(rng, text.encode())
        return data, "preset " + what
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return text.encode(), "preset unchanged"
    sat = doc.get("saturation", {})
    nums = [("", k) for k, v in doc.items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    nums += [("saturation", k) for k, v in sat.items() if isinstance(v, (int, float))]
    what = []
    for _ in range(rng.choice([1, 1, 2])):
        sec, k = rng.choice(nums)
        tbl = doc if not sec else sat
        op = rng.random()
        if op < 0.35:
            tbl[k] = rng.choice(EXTREME_NUMBERS)
        elif op < 0.75:
            v = tbl.get(k, 1)
            v = v if isinstance(v, (int, float)) and not isinstance(v, bool) else 1
            tbl[k] = type(v)(v * 10 ** rng.choice([-6, -3, -2, -1, 1, 2, 3, 6])) if isinstance(v, float) else \
                max(1, int(v * rng.choice([2, 10, 20, 100])))
        elif op < 0.85:
            tbl.pop(k, None)
        else:
            tbl[k] = wild_value(rng)
        what.append(f"{sec + '.' if sec else ''}{k} = {toml_value(tbl.get(k, '(dropped)'))[:40]}")
    return toml_dump(doc).encode(), "preset " + ", ".join(what)


# --------------------------------------------------------------------------------------------

def seeds(mcsim, root, timeout):
    """Scenarios that `mcsim check` accepts as they are."""
    out = []
    for dirpath, _, files in sorted(os.walk(os.path.join(root, "scenarios"))):
        for f in sorted(files):
            if f.endswith(".toml"):
                p = os.path.join(dirpath, f)
                r = subprocess.run([mcsim, "check", p], capture_output=True, timeout=timeout)
                if r.returncode == 0:
                    out.append(p)
    return out


def make_case(i, args, schema, seed_files, presets, workdir):
    rng = random.Random(f"{args.seed}:{i}")
    base = rng.choice(seed_files)
    with open(base, "rb") as f:
        raw = f.read()
    doc = tomllib.loads(raw.decode())
    run = rng.random() < args.run_fraction
    what = []
    preset_bytes = None
    kind = rng.random()
    if kind < 0.25:  # preset mutation
        with open(rng.choice(presets), encoding="utf-8") as f:
            preset_bytes, w = mutate_preset(rng, f.read())
        what.append(w)
        if rng.random() < 0.3:
            what += mutate_doc(rng, doc, schema, valid_bias=True)
    elif kind < 0.4 and not run:  # text-level damage
        data, w = mutate_bytes(rng, raw)
        what.append(w)
        return rng, base, data, None, run, what
    else:
        what += mutate_doc(rng, doc, schema, valid_bias=run or rng.random() < 0.3)
    case_dir = os.path.join(workdir, f"m{i}")
    os.makedirs(case_dir, exist_ok=True)
    if preset_bytes is not None:
        pp = os.path.join(case_dir, "preset.toml")
        with open(pp, "wb") as f:
            f.write(preset_bytes)
        set_key(doc, "machine.preset", pp)
    if run:
        m = doc.get("metrics")
        if isinstance(m, dict):
            m.pop("window", None)  # windows end after the short duration
    return rng, base, toml_dump(doc).encode(), preset_bytes, run, what


def check_result(r, run, out_dir, timed_out):
    """Problems with one call (empty list: fine)."""
    if timed_out:
        return ["timeout"]
    rc = r.returncode
    err = r.stderr
    problems = []
    if rc < 0:
        problems.append(f"killed by signal {signal.Signals(-rc).name if -rc in signal.Signals._value2member_map_ else -rc}")
    elif rc not in (0, 2):
        problems.append(f"exit status {rc}")
    if b"AddressSanitizer" in err or b"runtime error:" in err or b"LeakSanitizer" in err:
        problems.append("sanitizer report")
    if rc == 2:
        lines = err.decode("utf-8", "replace").strip().splitlines()
        if not lines:
            problems.append("exit 2 without a message")
        if len(err) > MAX_STDERR:
            problems.append(f"exit 2 message of {len(err)} bytes (> {MAX_STDERR})")
        if len(lines) > MAX_LINES:
            problems.append(f"exit 2 message of {len(lines)} lines")
    if rc == 0 and run:
        mj = os.path.join(out_dir, "metrics.json")
        try:
            with open(mj, "rb") as f:
                json.loads(f.read().decode("utf-8"))
        except FileNotFoundError:
            problems.append("exit 0 but no metrics.json")
        except (ValueError, UnicodeDecodeError) as e:
            problems.append(f"metrics.json does not parse: {e}")
    return problems


def one(i, args, schema, seed_files, presets, workdir):
    rng, base, text, preset_bytes, run, what = make_case(i, args, schema, seed_files, presets, workdir)
    case_dir = os.path.join(workdir, f"m{i}")
    os.makedirs(case_dir, exist_ok=True)
    scn = os.path.join(case_dir, "scenario.toml")
    with open(scn, "wb") as f:
        f.write(text)
    out_dir = os.path.join(case_dir, "out")
    if run:
        cmd = [args.mcsim, "run", scn, "--set", f"scenario.duration_s={RUN_DURATION}", "--out", out_dir, "--quiet"]
    else:
        cmd = [args.mcsim, "check", scn]
    t0 = time.monotonic()
    timed_out = False
    try:
        r = subprocess.run(cmd, capture_output=True, timeout=args.timeout)
    except subprocess.TimeoutExpired as e:
        timed_out = True
        r = subprocess.CompletedProcess(cmd, -999, e.stdout or b"", e.stderr or b"")
    dt = time.monotonic() - t0
    problems = check_result(r, run, out_dir, timed_out)
    res = {"i": i, "base": os.path.relpath(base, args.root), "run": run, "what": what, "rc": r.returncode,
           "problems": problems, "stderr": r.stderr[:4000].decode("utf-8", "replace"), "seconds": dt,
           "cmd": cmd}
    if problems and args.keep:
        dst = os.path.join(args.keep, f"m{i}")
        shutil.rmtree(dst, ignore_errors=True)
        shutil.copytree(case_dir, dst, ignore=shutil.ignore_patterns("trace.csv"))
        with open(os.path.join(dst, "report.txt"), "w") as f:
            f.write(f"seed {args.seed} mutation {i} base {res['base']}\nwhat: {what}\ncmd: {' '.join(cmd)}\n"
                    f"rc: {r.returncode}\nproblems: {problems}\n--- stderr ---\n{res['stderr']}\n")
    shutil.rmtree(case_dir, ignore_errors=True)
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mcsim", required=True, help="path to the mcsim binary")
    ap.add_argument("--n", type=int, default=200, help="mutations (default 200)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the mutations (default 1)")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds per mcsim call (default 30)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel mcsim calls (default 2)")
    ap.add_argument("--run-fraction", type=float, default=0.15,
                    help="share of mutations that `mcsim run` instead of `check` (default 0.15)")
    ap.add_argument("--only", type=int, action="append", help="run only mutation I (repeatable)")
    ap.add_argument("--keep", default=None, help="save failing cases here (default: a temp dir, printed)")
    ap.add_argument("--root", default=ROOT, help="repository root (scenarios/, presets/)")
    ap.add_argument("--quiet", action="store_true", help="print failures and the summary only")
    ap.add_argument("--messages", type=int, default=0, metavar="K",
                    help="also list the K most frequent exit-2 messages of `run` calls (key names kept)")
    args = ap.parse_args(argv)
    args.mcsim = os.path.abspath(args.mcsim)
    if not os.access(args.mcsim, os.X_OK):
        ap.error(f"--mcsim {args.mcsim}: not an executable")
    if args.keep is None:
        args.keep = tempfile.mkdtemp(prefix="mcsim_fuzz_failures_")
    os.makedirs(args.keep, exist_ok=True)

    schema = read_schema(args.mcsim)
    if not schema:
        sys.exit("fuzz_scenarios: `mcsim keys` gave no keys")
    seed_files = seeds(args.mcsim, args.root, args.timeout)
    presets = sorted(os.path.join(args.root, "presets", f) for f in os.listdir(os.path.join(args.root, "presets"))
                     if f.endswith(".toml"))
    if not seed_files or not presets:
        sys.exit("fuzz_scenarios: no seed scenarios or presets found")
    idx = args.only if args.only else list(range(args.n))
    t0 = time.monotonic()
    results = []
    with tempfile.TemporaryDirectory(prefix="mcsim_fuzz_") as work:
        with cf.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as ex:
            futs = [ex.submit(one, i, args, schema, seed_files, presets, work) for i in idx]
            for fut in cf.as_completed(futs):
                res = fut.result()
                results.append(res)
                if res["problems"] or not args.quiet and args.only:
                    print(f"{'FAIL' if res['problems'] else 'ok  '} #{res['i']} ({'run' if res['run'] else 'check'}, "
                          f"{res['base']}): {'; '.join(res['what'])[:300]} -> exit {res['rc']}: "
                          f"{', '.join(res['problems'])}\n      {res['stderr'].strip()[:600]}", flush=True)
    wall = time.monotonic() - t0
    fails = [r for r in results if r["problems"]]
    by_rc = {}
    for r in results:
        key = ("run" if r["run"] else "check", r["rc"])
        by_rc[key] = by_rc.get(key, 0) + 1
    print(f"fuzz_scenarios: {len(results)} mutations (seed {args.seed}) in {wall:.1f} s; "
          f"{len(seed_files)} seed scenarios, {len(presets)} presets")
    print("  exit status counts: " + ", ".join(f"{m} {rc}: {n}" for (m, rc), n in sorted(by_rc.items())))
    slow = max(results, key=lambda r: r["seconds"]) if results else None
    if slow:
        print(f"  slowest: #{slow['i']} {slow['seconds']:.2f} s")
    if args.messages:
        cls = {}
        for r in results:
            if r["run"] and r["rc"] == 2:
                m = r["stderr"].strip().splitlines()[0] if r["stderr"].strip() else ""
                m = re.sub(r"^mcsim: error: \S+?: ", "", m)
                m = re.sub(r"' = .*?: ", "' = V: ", m)
                m = re.sub(r"(?<![A-Za-z_])[-+]?\d[\d.eE+-]*", "N", m)[:140]
                cls[m] = cls.get(m, 0) + 1
        print(f"  most frequent exit-2 messages of runs:")
        for m, n in sorted(cls.items(), key=lambda kv: -kv[1])[: args.messages]:
            print(f"    {n:5d}  {m}")
    if fails:
        print(f"  {len(fails)} FAILED: " + " ".join(f"#{r['i']}" for r in sorted(fails, key=lambda r: r["i"])))
        print(f"  cases saved under {args.keep} (reproduce: --seed {args.seed} --only I)")
        return 1
    shutil.rmtree(args.keep, ignore_errors=True) if not os.listdir(args.keep) else None
    print("  no failures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
