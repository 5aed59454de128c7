#!/usr/bin/env python3
"""Mutation run of the firmware's C sources (or, with --python, the Python tools' key modules).

Mutants come from universalmutator (`mutate FILE c|python --noCheck`, regex rules, one change a
mutant). A deterministic sample (--seed) is built and tested one at a time in a copy of the
source tree (build/mutation/<kind>/src, its own build folder build/mutation/<kind>/build), so the
worktree is never touched: write the mutant, rebuild (ninja: only what depends on the file),
run the tests that cover the file first (its layer's unit tests, tests named after it, the
scenario tests), then the rest if none failed; stop at the first failure. A mutant that does not
build is counted apart (not a kill); one that runs past --timeout counts as killed (timeout).
Mutants listed in scripts/mutation_equivalent.txt are reported as equivalent with their reason.

Writes OUT/summary.json and OUT/report.md. See docs/testing.md.
"""
from __future__ import annotations

import argparse
import datetime
import fnmatch
import glob
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
C_FILES = "firmware/{core,control,estimators,app,comms}/*.c"
PY_FILES = "tools/mctools/mctune/eds.py,tools/mctools/mctune/drive.py,tools/mctools/sweep/common.py"
# ctest name prefix of each firmware layer's unit tests
LAYER_PREFIX = {"core": ["core_"], "control": ["control_"], "estimators": ["estim_"],
                "app": ["app_"], "comms": ["comms_", "fuzz_canopen"]}
# the first stage also runs the scenario tests (closed loop through the whole drive)
SCENARIO_RE = re.compile(r"^scenario_")
# Python module -> its pytest files first (the rest of tools/tests afterwards)
PY_TESTS = {"eds.py": "tools/tests/test_*eds*.py tools/tests/test_mctune*.py",
            "drive.py": "tools/tests/test_mctune*.py tools/tests/test_*drive*.py",
            "common.py": "tools/tests/test_sweep*.py tools/tests/test_seeds.py tools/tests/test_envelope.py"}


def expand(globs: str) -> list[str]:
    out: list[str] = []
    for g in re.split(r",(?![^{]*\})", globs):   # commas outside braces
        g = g.strip()
        m = re.match(r"(.*)\{([^}]*)\}(.*)", g)
        parts = [m.group(1) + alt + m.group(3) for alt in m.group(2).split(",")] if m else [g]
        for p in parts:
            out += sorted(str(Path(f).relative_to(ROOT)) for f in glob.glob(str(ROOT / p)))
    return sorted(set(out))


def generate(rel: str, lang: str) -> list[dict]:
    """Every universalmutator mutant of one file, as (line, original, mutated) in file order."""
    src = (ROOT / rel).read_text().splitlines(keepends=True)
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([str(ROOT / ".venv/bin/mutate"), str(ROOT / rel), lang, "--noCheck",
                        "--mutantDir", d], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, cwd=d)
        stem = Path(rel).stem
        files = sorted(Path(d).glob(f"{stem}.mutant.*"), key=lambda p: int(p.name.split(".")[-2]))
        mutants = []
        seen = set()
        for f in files:
            mut = f.read_text().splitlines(keepends=True)
            if len(mut) != len(src):
                continue   # a mutant that adds or removes lines: not a one-line change
            diff = [i for i, (a, b) in enumerate(zip(src, mut)) if a != b]
            if len(diff) != 1:
                continue
            i = diff[0]
            key = (i, mut[i])
            if key in seen:
                continue
            seen.add(key)
            mutants.append({"file": rel, "line": i + 1, "original": src[i].rstrip("\n"),
                            "mutated": mut[i].rstrip("\n")})
        if lang == "python":
            # lines inside a multi-line string (docstrings): universalmutator mutates their text
            import io
            import tokenize
            inside = set()
            for tok in tokenize.generate_tokens(io.StringIO("".join(src)).readline):
                if tok.type == tokenize.STRING and tok.end[0] > tok.start[0]:
                    inside |= set(range(tok.start[0], tok.end[0] + 1))
            mutants = [m for m in mutants if m["line"] not in inside]
        return mutants


def skip_line(text: str, lang: str) -> bool:
    t = text.strip()
    if lang == "c":
        return (not t or t.startswith(("//", "/*", "*", "#")) or "static_assert" in t
                or "_Static_assert" in t)
    return not t or t.startswith(("#", '"""', "import ", "from "))


def sample(all_mutants: dict[str, list[dict]], n: int | None, seed: int) -> list[dict]:
    """Proportional to each file's mutant count (largest remainder, at least one a file), the
    pick within a file a seeded shuffle: the same seed and sources give the same sample."""
    rng = random.Random(seed)
    files = sorted(all_mutants)
    pools = {f: sorted(all_mutants[f], key=lambda m: (m["line"], m["mutated"])) for f in files}
    for f in files:
        rng.shuffle(pools[f])
    total = sum(len(p) for p in pools.values())
    if n is None or n >= total:
        chosen = [m for f in files for m in pools[f]]
    else:
        quota = {f: (n * len(pools[f]) / total) for f in files}
        take = {f: min(len(pools[f]), max(1 if n >= len(files) else 0, int(quota[f]))) for f in files}
        rest = sorted(files, key=lambda f: (-(quota[f] - int(quota[f])), f))
        i = 0
        while sum(take.values()) < n and i < 10 * len(files):
            f = rest[i % len(rest)]
            if take[f] < len(pools[f]):
                take[f] += 1
            i += 1
        while sum(take.values()) > n:   # the "at least one" rule overshot: trim the biggest
            f = max(files, key=lambda f: (take[f], f))
            take[f] -= 1
        chosen = [m for f in files for m in pools[f][:take[f]]]
    # a mutant that does not build is replaced by the next of its file's shuffled pool (main())
    for f in files:
        k = sum(1 for m in chosen if m["file"] == f)
        RESERVE[f] = pools[f][k:]
    chosen.sort(key=lambda m: (m["file"], m["line"], m["mutated"]))
    return chosen


RESERVE: dict[str, list[dict]] = {}


def load_equivalent(path: Path) -> list[tuple[str, int, str, str]]:
    """file:line:mutated line (stripped) -> reason"""
    out = []
    if not path.exists():
        return out
    for raw in path.read_text().splitlines():
        if not raw.strip() or raw.lstrip().startswith("#"):
            continue
        head, reason = raw.rsplit(" -> ", 1)
        f, line, mut = head.split(":", 2)
        out.append((f.strip(), int(line), mut.strip(), reason.strip()))
    return out


def load_must_kill(path: Path) -> list[tuple[str, int, str]]:
    out = []
    if path.exists():
        for raw in path.read_text().splitlines():
            if raw.strip() and not raw.lstrip().startswith("#"):
                f, line, mut = raw.split(":", 2)
                out.append((f.strip(), int(line), mut.strip()))
    return out


def copy_tree(work: Path) -> Path:
    """The sources as the worktree has them now (tracked and untracked, not ignored)."""
    src = work / "src"
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=ROOT,
                           check=True, capture_output=True).stdout.decode().split("\0")
    for f in files:
        if not f or not (ROOT / f).is_file():
            continue
        dst = src / f
        if dst.exists() and dst.read_bytes() == (ROOT / f).read_bytes():
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / f, dst)
    venv = src / ".venv"
    if not venv.exists():
        venv.symlink_to(ROOT / ".venv")
    return src


def run(cmd, cwd, timeout, env=None) -> tuple[int | None, str, float]:
    """The command in its own process group: past the timeout the whole group (ctest and the
    tests it started) is killed, so a hung mutant cannot hold the run."""
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True, start_new_session=True)
    try:
        out, _ = p.communicate(timeout=timeout)
        return p.returncode, out, time.monotonic() - t0
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        return None, out or "", time.monotonic() - t0


class CRunner:
    lang = "c"

    def __init__(self, work: Path, jobs: int, quick_files: list[str] | None = None):
        self.work = work
        self.src = copy_tree(work)
        self.build = work / "build"
        self.jobs = jobs
        self.quick = quick_files is not None
        if not (self.build / "build.ninja").exists():
            subprocess.run(["cmake", "-S", str(self.src), "-B", str(self.build), "-G", "Ninja",
                            "-DCMAKE_BUILD_TYPE=Release", "-DMC_BUILD_IMAGES=OFF"], check=True,
                           stdout=subprocess.DEVNULL)
        names = subprocess.run(["ctest", "--test-dir", str(self.build), "-N", "-LE", "pil"],
                               capture_output=True, text=True, check=True).stdout
        self.tests = re.findall(r"Test\s+#\d+:\s+(\S+)", names)
        # the PIL tests need the cross-built images (off here: host and image would carry the
        # same mutant, and their comparison cannot see it)
        self.tests = [t for t in self.tests if not t.startswith("pil_")]
        self.targets: list[str] = []
        if self.quick:
            # --quick (CI): only the covering tests (first stage), only the targets they run:
            # the cmocka executables named as their tests and mcsim for the scenarios
            self.tests = sorted({t for f in quick_files for t in self.stages(f)[0]})
            # the firmware layers' unit-test folders (their executables and generators), the
            # CANopen fuzzer's, and mcsim for the scenarios; not the plant's, PIL's or ports' tests
            self.targets = ["mcsim"] + [f"tests/{d}/all" for d in ("unit/core", "unit/control",
                            "unit/estimators", "unit/app", "unit/comms", "fuzz")]
        rc, out, _ = run(["ninja", "-C", str(self.build), f"-j{jobs}", *self.targets], None, None)
        if rc != 0:
            sys.exit("mutation: the unmutated copy does not build:\n" + out[-3000:])

    def baseline(self, timeout: float) -> float:
        t0 = time.monotonic()
        status, _, _ = self.test_stage(self.tests, timeout)
        if status != "passed":
            sys.exit(f"mutation: the unmutated tests do not pass ({status}); fix that first")
        return time.monotonic() - t0

    def stages(self, rel: str) -> list[list[str]]:
        layer = Path(rel).parent.name
        stem = Path(rel).stem
        first = [t for t in self.tests if any(t.startswith(p) for p in LAYER_PREFIX.get(layer, []))
                 or stem in t or SCENARIO_RE.match(t)]
        rest = [t for t in self.tests if t not in first]
        return [first, rest] if not self.quick else [first]

    def apply(self, m: dict | None, rel: str):
        path = self.src / rel
        lines = (ROOT / rel).read_text().splitlines(keepends=True)
        if m is not None:
            lines[m["line"] - 1] = m["mutated"] + "\n"
        path.write_text("".join(lines))

    def build_mutant(self, timeout: float) -> tuple[bool, str]:
        rc, out, _ = run(["ninja", "-C", str(self.build), f"-j{self.jobs}", *self.targets], None, timeout)
        return rc == 0, out

    def test_stage(self, tests: list[str], timeout: float) -> tuple[str, str, str]:
        if not tests:
            return "passed", "", ""
        regex = "^(" + "|".join(re.escape(t) for t in tests) + ")$"
        per_test = max(10, int(timeout))
        rc, out, _ = run(["ctest", "--test-dir", str(self.build), "-R", regex, "-j", str(self.jobs),
                          "--stop-on-failure", "--timeout", str(per_test), "--output-on-failure"],
                         None, timeout)
        if rc is None:
            return "timeout", "", out
        if rc == 0:
            return "passed", "", out
        if "***Not Run" in out or "Could not find executable" in out:
            sys.exit("mutation: a test's executable is missing from the mutant build (not a kill):\n" + out[-2000:])
        failed = re.findall(r"\d+/\d+ Test\s+#\d+:\s+(\S+)\s+\.+\*+(\w+)", out)
        timeouts = [n for n, why in failed if why.lower().startswith("timeout")]
        names = [n for n, _ in failed]
        return ("timeout" if timeouts and len(timeouts) == len(names) else "failed"), ",".join(names), out


class PyRunner:
    lang = "python"

    def __init__(self, work: Path, jobs: int):
        self.work = work
        self.src = copy_tree(work)
        self.jobs = jobs
        self.env = dict(os.environ, PYTHONPATH=str(self.src / "tools"), PYTHONDONTWRITEBYTECODE="1")
        self.tests = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tools/tests").glob("test_*.py"))

    def baseline(self, timeout: float) -> float:
        t0 = time.monotonic()
        status, _, out = self.test_stage(self.tests, timeout)
        if status != "passed":
            sys.exit(f"mutation: the unmutated Python tests do not pass ({status}):\n{out[-2000:]}")
        return time.monotonic() - t0

    def stages(self, rel: str) -> list[list[str]]:
        pats = PY_TESTS.get(Path(rel).name, "").split()
        first = sorted({t for t in self.tests for p in pats if fnmatch.fnmatch(t, p)})
        return [first, [t for t in self.tests if t not in first]]

    def apply(self, m: dict | None, rel: str):
        self.last = self.src / rel
        CRunner.apply(self, m, rel)

    def build_mutant(self, timeout: float) -> tuple[bool, str]:
        # a mutant that is not valid Python "does not build" (not a kill)
        rc, out, _ = run([str(ROOT / ".venv/bin/python"), "-c",
                          "import ast, sys; ast.parse(open(sys.argv[1]).read())", str(self.last)],
                         None, timeout)
        return rc == 0, out

    def test_stage(self, tests: list[str], timeout: float) -> tuple[str, str, str]:
        if not tests:
            return "passed", "", ""
        rc, out, _ = run([str(ROOT / ".venv/bin/python"), "-m", "pytest", "-x", "-q", "-p",
                          "no:cacheprovider", *tests], self.src, timeout, self.env)
        if rc is None:
            return "timeout", "", out
        if rc == 0:
            return "passed", "", out
        failed = re.findall(r"^FAILED (\S+)", out, re.M)
        return "failed", ",".join(failed) or f"pytest rc={rc}", out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sample", type=int, help="test N mutants (a seeded, per-file proportional sample); all by default")
    ap.add_argument("--files", help=f"comma-separated globs from the repository root (default {C_FILES}, or with --python {PY_FILES})")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=300, help="seconds of tests per mutant; past it the mutant counts as killed (timeout)")
    ap.add_argument("--build-timeout", type=float, default=600)
    ap.add_argument("--out", default="out/mutation")
    ap.add_argument("--python", action="store_true", help="mutate the Python tools' key modules, run pytest")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--equivalent", default="scripts/mutation_equivalent.txt")
    ap.add_argument("--must-kill", help="file of file:line:mutated line that must be killed (fails otherwise)")
    ap.add_argument("--min-score", type=float, help="fail if the killed share of the tested non-equivalent mutants is below this (percent)")
    ap.add_argument("--quick", action="store_true", help="only the covering tests and the targets they need (CI); survivors are then survivors of those tests only")
    ap.add_argument("--no-baseline", action="store_true", help="skip the run of the unmutated tests (CI: ctest just passed)")
    ap.add_argument("--work", help="folder of the source copy and its build (default build/mutation)")
    ap.add_argument("--label", default="", help="a label for the score line")
    a = ap.parse_args()

    lang = "python" if a.python else "c"
    files = expand(a.files or (PY_FILES if a.python else C_FILES))
    if not files:
        sys.exit("mutation: no file matches")
    out = (ROOT / a.out) if not os.path.isabs(a.out) else Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    work = (Path(a.work) if a.work else ROOT / "build" / "mutation") / lang
    work.mkdir(parents=True, exist_ok=True)

    t_start = time.monotonic()
    # universalmutator takes a few seconds a file: its mutants are cached by the file's content
    import hashlib
    from concurrent.futures import ThreadPoolExecutor
    cache = work / "mutants"
    cache.mkdir(exist_ok=True)

    def gen(f):
        key = hashlib.sha256((ROOT / f).read_bytes() + lang.encode() + b"v2").hexdigest()[:20]   # v2: filters
        c = cache / f"{Path(f).name}.{key}.json"
        if c.exists():
            return json.loads(c.read_text())
        ms = [m for m in generate(f, lang) if not skip_line(m["original"], lang)]
        c.write_text(json.dumps(ms))
        return ms
    with ThreadPoolExecutor(max(1, a.jobs)) as ex:
        all_mutants = dict(zip(files, ex.map(gen, files)))
    chosen = sample(all_mutants, a.sample, a.seed)
    # the must-kill mutants always run, whatever the sample (a line number that moved is found
    # again by its text; one that is no longer generated fails the run: update the list)
    must = load_must_kill(ROOT / a.must_kill) if a.must_kill else []
    missing = []
    for (f, ln, mu) in must:
        cands = [m for m in all_mutants.get(f, []) if m["mutated"].strip() == mu]
        cands.sort(key=lambda m: abs(m["line"] - ln))
        if not cands:
            missing.append(f"{f}:{ln}:{mu}")
            continue
        if not any(c is cands[0] for c in chosen) and not any(
                m["file"] == f and m["line"] == cands[0]["line"] and m["mutated"] == cands[0]["mutated"] for m in chosen):
            chosen.append(dict(cands[0]))
    for m in chosen:
        m["must_kill"] = any(m["file"] == f and m["mutated"].strip() == mu for (f, _, mu) in must)
    chosen.sort(key=lambda m: (m["file"], m["line"], m["mutated"]))
    generated = sum(len(v) for v in all_mutants.values())
    print(f"mutation: {generated} mutants of {len(files)} files (universalmutator), testing {len(chosen)} (seed {a.seed})", flush=True)

    equivalent = load_equivalent(ROOT / a.equivalent)
    runner = CRunner(work, a.jobs, files if a.quick else None) if lang == "c" else PyRunner(work, a.jobs)
    for f in files:
        runner.apply(None, f)
    if not a.no_baseline:
        base_t = runner.baseline(max(a.timeout, 1800))
        print(f"mutation: the unmutated tests pass in {base_t:.0f} s", flush=True)

    results = []
    queue = list(chosen)
    k = -1
    while k + 1 < len(queue):
        k += 1
        m = queue[k]
        t0 = time.monotonic()
        eq = next((r for (f, ln, mu, r) in equivalent
                   if f == m["file"] and ln == m["line"] and mu == m["mutated"].strip()), None)
        if eq is not None:
            m.update(status="equivalent", reason=eq, seconds=0.0)
        else:
            runner.apply(m, m["file"])
            ok, bout = runner.build_mutant(a.build_timeout)
            if not ok:
                m.update(status="no_compile")
                # keep the number of tested mutants: the file's next mutant in the seeded order
                while RESERVE.get(m["file"]):
                    r = RESERVE[m["file"]].pop(0)
                    if not any(q["line"] == r["line"] and q["mutated"] == r["mutated"] and q["file"] == r["file"] for q in queue):
                        queue.insert(k + 1, dict(r, must_kill=False))
                        break
            else:
                deadline = t0 + a.timeout
                m["status"] = "survived"
                for stage in runner.stages(m["file"]):
                    left = deadline - time.monotonic()
                    if left <= 0:
                        m.update(status="killed", by="timeout")
                        break
                    st, names, _ = runner.test_stage(stage, left)
                    if st == "failed":
                        m.update(status="killed", by=names)
                        break
                    if st == "timeout":
                        m.update(status="killed", by="timeout" + (f" ({names})" if names else ""))
                        break
            runner.apply(None, m["file"])
            m["seconds"] = round(time.monotonic() - t0, 1)
        results.append(m)
        done = k + 1
        el = time.monotonic() - t_start
        print(f"[{done}/{len(queue)}] {m['file']}:{m['line']} {m['status']}"
              f"{' by ' + m['by'] if m.get('by') else ''} ({m['seconds']:.0f} s; elapsed {el/60:.1f} min)", flush=True)
    runner.build_mutant(a.build_timeout)   # leave the copy's build unmutated

    summary = summarize(results, files, a, generated, lang, time.monotonic() - t_start)
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    (out / "report.md").write_text(report(summary))
    s = summary["totals"]
    print(f"mutation: {s['killed']} killed, {s['survived']} survived, {s['equivalent']} equivalent, "
          f"{s['no_compile']} not compiling (sample of {len(chosen)} of {generated}, {len(queue) - len(chosen)} more drawn for those that do not build, seed {a.seed}"
          f"{', ' + a.label if a.label else ''}): score {s['score']:.1f} %", flush=True)
    print(f"mutation: {out / 'report.md'}", flush=True)

    status = 0
    for x in missing:
        print(f"mutation: must-kill mutant no longer generated (update {a.must_kill}): {x}")
        status = 1
    for m in results:
        if m.get("must_kill") and m["status"] != "killed":
            print(f"mutation: must-kill {m['file']}:{m['line']} {m['status']}: {m['mutated'].strip()}")
            status = 1
    if a.min_score is not None and s["score"] < a.min_score:
        print(f"mutation: score {s['score']:.1f} % below the threshold {a.min_score} %")
        status = 1
    return status


def summarize(results, files, a, generated, lang, seconds):
    def pick(st):
        return [{k: m[k] for k in ("file", "line", "original", "mutated", "by", "reason", "seconds")
                 if k in m} for m in results if m["status"] == st]
    per_file = {}
    for f in files:
        rs = [m for m in results if m["file"] == f]
        if not rs:
            continue
        c = {st: sum(1 for m in rs if m["status"] == st) for st in ("killed", "survived", "equivalent", "no_compile")}
        den = c["killed"] + c["survived"]
        c["score"] = round(100.0 * c["killed"] / den, 1) if den else None
        per_file[f] = c
    tot = {st: sum(1 for m in results if m["status"] == st) for st in ("killed", "survived", "equivalent", "no_compile")}
    den = tot["killed"] + tot["survived"]
    tot["score"] = round(100.0 * tot["killed"] / den, 1) if den else 100.0
    tot["timeouts"] = sum(1 for m in results if m.get("by", "").startswith("timeout"))
    tested = [m["seconds"] for m in results if m["status"] in ("killed", "survived")]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    dirty = bool(subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                                capture_output=True, text=True).stdout.strip())
    return {
        "tool": "universalmutator", "language": lang, "commit": commit + ("+dirty" if dirty else ""),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "seed": a.seed, "sample": a.sample, "quick": bool(getattr(a, "quick", False)), "generated": generated, "files": files,
        "timeout_s": a.timeout, "seconds": round(seconds, 1),
        "seconds_per_tested_mutant": round(sum(tested) / len(tested), 1) if tested else None,
        "totals": tot, "per_file": per_file,
        "mutants": [{k: m[k] for k in ("file", "line", "original", "mutated", "status") } for m in results],
        "killed": pick("killed"), "survived": pick("survived"),
        "equivalent": pick("equivalent"), "no_compile": pick("no_compile"),
    }


def report(s) -> str:
    t = s["totals"]
    L = [f"# Mutation run ({s['language']}, {s['tool']})", "",
         f"Commit {s['commit']}, {s['date']}, seed {s['seed']}, sample {s['sample'] or 'all'} of {s['generated']} mutants, "
         f"{s['seconds']/60:.1f} min ({s['seconds_per_tested_mutant']} s a built and tested mutant).", "",
         f"**{t['killed']} killed** ({t['timeouts']} of them by the time limit of {s['timeout_s']:.0f} s), "
         f"**{t['survived']} survived**, {t['equivalent']} equivalent, {t['no_compile']} not compiling: "
         f"score {t['score']:.1f} % of the non-equivalent mutants that build.", "",
         "| file | killed | survived | equivalent | not compiling | score |", "|---|---:|---:|---:|---:|---:|"]
    for f, c in s["per_file"].items():
        sc = f"{c['score']:.1f} %" if c["score"] is not None else "-"
        L.append(f"| {f} | {c['killed']} | {c['survived']} | {c['equivalent']} | {c['no_compile']} | {sc} |")
    L += ["", "## Survivors", ""]
    for m in s["survived"] or []:
        L += [f"- `{m['file']}:{m['line']}`", f"  - `{m['original'].strip()}`", f"  + `{m['mutated'].strip()}`"]
    if not s["survived"]:
        L.append("None.")
    L += ["", "## Equivalent (scripts/mutation_equivalent.txt)", ""]
    for m in s["equivalent"] or []:
        L.append(f"- `{m['file']}:{m['line']}` `{m['mutated'].strip()}`: {m['reason']}")
    if not s["equivalent"]:
        L.append("None in this sample.")
    L += ["", "## Killed", ""]
    for m in s["killed"]:
        L.append(f"- `{m['file']}:{m['line']}` `{m['mutated'].strip()}` by {m['by']}")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
