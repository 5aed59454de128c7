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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from mutation_cov import TCE, build_coverage, tree_key  # noqa: E402
from mutation_keys import Keys, journal_fkeys  # noqa: E402

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
    # universalmutator leaves every line with a comment alone, so a code line ending in
    # "/* why */" (the project's style for the thesis' equation numbers) would never be mutated:
    # it gets a copy with those trailing comments cut, and each mutant its line's comment back
    bare, tails = src, [""] * len(src)
    if lang == "c":
        bare, tails = zip(*(cut_trailing_comment(ln) for ln in src)) if src else ((), ())
        bare, tails = list(bare), list(tails)
    with tempfile.TemporaryDirectory() as d:
        target = Path(d) / "in" / Path(rel).name
        target.parent.mkdir()
        target.write_text("".join(bare))
        subprocess.run([str(ROOT / ".venv/bin/mutate"), str(target), lang, "--noCheck",
                        "--mutantDir", d], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, cwd=d)
        stem = Path(rel).stem
        files = sorted(Path(d).glob(f"{stem}.mutant.*"), key=lambda p: int(p.name.split(".")[-2]))
        mutants = []
        seen = set()
        for f in files:
            mut = f.read_text().splitlines(keepends=True)
            if len(mut) != len(bare):
                continue   # a mutant that adds or removes lines: not a one-line change
            diff = [i for i, (a, b) in enumerate(zip(bare, mut)) if a != b]
            if len(diff) != 1:
                continue
            i = diff[0]
            line = mut[i].rstrip("\n") + tails[i] if tails[i] else mut[i].rstrip("\n")
            key = (i, line)
            if key in seen or line == src[i].rstrip("\n"):
                continue
            seen.add(key)
            mutants.append({"file": rel, "line": i + 1, "original": src[i].rstrip("\n"),
                            "mutated": line})
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


def cut_trailing_comment(line: str) -> tuple[str, str]:
    """A C line as code and its trailing one-line comment ("x = 1;   /* (6.4) */" ->
    ("x = 1;\\n", "   /* (6.4) */")); lines that are only a comment, hold a string or a comment
    that goes on to the next line are left whole."""
    body = line.rstrip("\n")
    m = re.match(r"^(?P<code>.*?\S)(?P<tail>\s*(/\*(?:(?!\*/).)*\*/|//.*))\s*$", body)
    if not m or '"' in m["code"] or "'" in m["code"] or "/*" in m["code"] or m["code"].lstrip().startswith(("*", "//")):
        return line, ""
    return m["code"] + line[len(body):], m["tail"]


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
        head, reason = raw.split(" -> ", 1)   # the reason may say "->" itself; the C line does not
        f, line, mut = head.split(":", 2)
        out.append((f.strip(), int(line), mut.strip(), reason.strip()))
    return out


def resolve_equivalent(entries, all_mutants, reach: int = 40) -> dict[tuple[str, int, str], str]:
    """(file, line, mutated text) of a generated mutant -> the reason of its equivalence entry.
    An entry names its mutant by line; one whose line moved (an edit above it) is found again by
    its text, the nearest such mutant within `reach` lines that no entry names exactly, so the
    judgement follows the code (scripts/mutation_lists.py --check names the ones that are lost)."""
    out: dict[tuple[str, int, str], str] = {}
    by_text: dict[tuple[str, str], list[int]] = {}
    for f, ms in all_mutants.items():
        for m in ms:
            by_text.setdefault((f, m["mutated"].strip()), []).append(m["line"])
    loose = []
    for (f, ln, mu, why) in entries:
        if ln in by_text.get((f, mu), ()):
            out[(f, ln, mu)] = why
        else:
            loose.append((f, ln, mu, why))
    for (f, ln, mu, why) in loose:
        cands = sorted((abs(n - ln), n) for n in by_text.get((f, mu), ()) if abs(n - ln) <= reach and (f, n, mu) not in out)
        if cands:
            out[(f, cands[0][1], mu)] = why
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
        # copy, not copy2: the copy's time is now, so ninja rebuilds what depends on it even when
        # the worktree's file is older than objects built from a mutant or an earlier refresh
        shutil.copy(ROOT / f, dst)
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


def test_targets(build: Path) -> dict[str, list[str]]:
    """Each test's build outputs (ninja targets): the paths inside the build folder its command
    names, with those of the fixtures it requires."""
    outs = set()
    for ln in subprocess.run(["ninja", "-C", str(build), "-t", "targets", "all"], capture_output=True,
                             text=True, check=True).stdout.splitlines():
        outs.add(ln.rsplit(": ", 1)[0])
    js = json.loads(subprocess.run(["ctest", "--test-dir", str(build), "--show-only=json-v1"],
                                   capture_output=True, text=True, check=True).stdout)
    own: dict[str, set[str]] = {}
    requires: dict[str, list[str]] = {}
    setup: dict[str, list[str]] = {}
    b = str(build.resolve()) + "/"
    for t in js["tests"]:
        mine = set()
        for tok in t.get("command", []):
            for part in tok.split("="):
                if part.startswith(b) and part[len(b):] in outs:
                    mine.add(part[len(b):])
        own[t["name"]] = mine
        props = {p["name"]: p["value"] for p in t.get("properties", [])}
        requires[t["name"]] = list(props.get("FIXTURES_REQUIRED", []))
        for fx in props.get("FIXTURES_SETUP", []):
            setup.setdefault(fx, []).append(t["name"])
    return {t: sorted(own[t].union(*[own[s] for fx in requires[t] for s in setup.get(fx, [])]))
            for t in own}


class CRunner:
    lang = "c"

    def __init__(self, work: Path, jobs: int, quick_files: list[str] | None = None, name: str = "w0"):
        self.work = work
        self.src = copy_tree(work / name)
        self.build = work / name / "build"
        self.jobs = jobs
        self.quick = quick_files is not None
        if not (self.build / "build.ninja").exists():
            subprocess.run(["cmake", "-S", str(self.src), "-B", str(self.build), "-G", "Ninja",
                            "-DCMAKE_BUILD_TYPE=Release", "-DMC_BUILD_IMAGES=OFF",
                            "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON"], check=True,
                           stdout=subprocess.DEVNULL)
        # the copy is built (re-configured when a CMakeLists.txt changed) before the tests are
        # listed: a test added since the last run would be missing from the list otherwise
        rc, out, _ = run(["ninja", "-C", str(self.build), f"-j{jobs}"] + ([] if quick_files is None else ["build.ninja"]), None, None)
        if rc != 0:
            sys.exit("mutation: the unmutated copy does not build:\n" + out[-3000:])
        names = subprocess.run(["ctest", "--test-dir", str(self.build), "-N", "-LE", "pil"],
                               capture_output=True, text=True, check=True).stdout
        self.tests = re.findall(r"Test\s+#\d+:\s+(\S+)", names)
        # the PIL tests need the cross-built images (off here: host and image would carry the
        # same mutant, and their comparison cannot see it)
        self.tests = [t for t in self.tests if not t.startswith("pil_")]
        self.targets: list[str] = []
        self.cov = None   # Coverage (mutation_cov.py) when the run selects tests by line
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
        self.needs = test_targets(self.build)
        self.tce = TCE(self.build, self.src)
        self.tce_dir = Path(tempfile.mkdtemp(prefix="tce-", dir=work / name))
        self.orig_obj: dict[str, str | None] = {}

    def object_hash(self, rel: str) -> str | None:
        """The mutated (as written now) file's object code hash; None: it does not compile."""
        return self.tce.object_hash(rel, self.tce_dir / "m.o")

    def original_object(self, rel: str) -> str | None:
        if rel not in self.orig_obj:
            self.apply(None, rel)
            self.orig_obj[rel] = self.object_hash(rel)
        return self.orig_obj[rel]

    def baseline(self, timeout: float) -> float:
        t0 = time.monotonic()
        status, _, _ = self.test_stage(self.tests, timeout)
        if status != "passed":
            sys.exit(f"mutation: the unmutated tests do not pass ({status}); fix that first")
        return time.monotonic() - t0

    def stages(self, rel: str, line: int | None = None) -> list[list[str]]:
        if self.cov is not None and line is not None:
            kind, first = self.cov.tests_for(rel, line, self.tests)
            if kind == "function":
                # only the tests that enter the function can tell the mutant from the original
                return [first]
            return [first, [t for t in self.tests if t not in first]]
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

    def build_mutant(self, timeout: float, tests: list[str] | None = None) -> tuple[bool, str]:
        targets = self.targets
        if tests is not None and not self.quick:
            # only what the stage's tests run (and their fixtures'): ninja rebuilds a target
            # whose sources changed when it is asked for, so nothing stale is ever run
            targets = sorted({x for t in tests for x in self.needs.get(t, [])})
            if not targets:
                return True, ""
        rc, out, _ = run(["ninja", "-C", str(self.build), f"-j{self.jobs}", *targets], None, timeout)
        return rc == 0, out

    def test_stage(self, tests: list[str], timeout: float) -> tuple[str, str, str]:
        if not tests:
            return "passed", "", ""
        if self.cov is not None and len(tests) > 1:
            # one at a time in the given order (fastest first): ctest would start the costliest
            deadline = time.monotonic() + timeout
            outs = []
            for t in tests:
                left = deadline - time.monotonic()
                if left <= 0:
                    return "timeout", "", "".join(outs)
                # a hung mutant: ten times the test's own time (coverage build, -O0) at most
                st, names, out = self.test_stage([t], min(left, max(30.0, 10 * self.cov.seconds.get(t, 60.0))))
                outs.append(out)
                if st != "passed":
                    return st, names, "".join(outs)
            return "passed", "", "".join(outs)
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

    def stages(self, rel: str, line: int | None = None) -> list[list[str]]:
        pats = PY_TESTS.get(Path(rel).name, "").split()
        first = sorted({t for t in self.tests for p in pats if fnmatch.fnmatch(t, p)})
        return [first, [t for t in self.tests if t not in first]]

    def apply(self, m: dict | None, rel: str):
        self.last = self.src / rel
        CRunner.apply(self, m, rel)

    def build_mutant(self, timeout: float, tests: list[str] | None = None) -> tuple[bool, str]:
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
    ap.add_argument("--jobs", type=int, default=None, help="ninja/ctest jobs of a worker (default: the cores shared among the workers)")
    ap.add_argument("--workers", type=int, default=1, help="mutants tested at once, each in its own copy and build folder")
    ap.add_argument("--no-coverage", action="store_true", help="C: do not select the tests by per-test line coverage (run the file's tests, then the rest)")
    ap.add_argument("--no-carry", action="store_true", help="with --resume or --summarize: use only results of the files' present content (no results carried over from an older content whose function is unchanged)")
    ap.add_argument("--no-tce", action="store_true", help="C: do not compile a mutant alone first to set apart the ones that do not build, the equivalent and the duplicate")
    ap.add_argument("--resume", action="store_true", help="reuse the results in OUT/journal.jsonl of mutants whose file has not changed since")
    ap.add_argument("--retest-survivors", action="store_true", help="with --resume: test the journal's survivors again (after new tests)")
    ap.add_argument("--only-survivors", action="store_true", help="with --resume: test the journal's survivors again and nothing else (a record put together from several runs, after new tests)")
    ap.add_argument("--summarize", action="store_true", help="write summary.json and report.md from OUT/journal.jsonl as it stands (a run stopped early, or shards' journals put together), test nothing")
    ap.add_argument("--shard", help="I/N: only the I-th of N interleaved parts of the mutants (1-based), for several machines")
    ap.add_argument("--equivalent", default="scripts/mutation_equivalent.txt")
    ap.add_argument("--must-kill", help="file of file:line:mutated line that must be killed (fails otherwise)")
    ap.add_argument("--min-score", type=float, help="fail if the killed share of the tested non-equivalent mutants is below this (percent)")
    ap.add_argument("--quick", action="store_true", help="only the covering tests and the targets they need (CI); survivors are then survivors of those tests only")
    ap.add_argument("--no-baseline", action="store_true", help="skip the run of the unmutated tests (CI: ctest just passed)")
    ap.add_argument("--work", help="folder of the source copy and its build (default build/mutation)")
    ap.add_argument("--label", default="", help="a label for the score line")
    a = ap.parse_args()
    a.jobs = a.jobs or max(1, (os.cpu_count() or 2) // max(1, a.workers))

    lang = "python" if a.python else "c"
    files = expand(a.files or (PY_FILES if a.python else C_FILES))
    if not files:
        sys.exit("mutation: no file matches")
    out = (ROOT / a.out) if not os.path.isabs(a.out) else Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    work = ((Path(a.work) if a.work else ROOT / "build" / "mutation") / lang).resolve()
    work.mkdir(parents=True, exist_ok=True)

    t_start = time.monotonic()
    # universalmutator takes a few seconds a file: its mutants are cached by the file's content
    import hashlib
    import threading
    from concurrent.futures import ThreadPoolExecutor
    cache = work / "mutants"
    cache.mkdir(exist_ok=True)
    fhash = {f: hashlib.sha256((ROOT / f).read_bytes()).hexdigest()[:16] for f in files}

    def gen(f):
        key = hashlib.sha256((ROOT / f).read_bytes() + lang.encode() + b"v3").hexdigest()[:20]   # v3: trailing comments
        c = cache / f"{Path(f).name}.{key}.json"
        if c.exists():
            return json.loads(c.read_text())
        ms = [m for m in generate(f, lang) if not skip_line(m["original"], lang)]
        c.write_text(json.dumps(ms))
        return ms
    with ThreadPoolExecutor(max(1, a.jobs * a.workers)) as ex:
        all_mutants = dict(zip(files, ex.map(gen, files)))
    chosen = sample(all_mutants, a.sample, a.seed)
    if a.shard:
        i, n = (int(x) for x in a.shard.split("/"))
        chosen = chosen[i - 1::n]
        for f in RESERVE:
            RESERVE[f] = RESERVE[f][i - 1::n]
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
        if not any(m["file"] == f and m["line"] == cands[0]["line"] and m["mutated"] == cands[0]["mutated"] for m in chosen):
            chosen.append(dict(cands[0]))
    for m in chosen:
        m["must_kill"] = any(m["file"] == f and m["mutated"].strip() == mu for (f, _, mu) in must)
    chosen.sort(key=lambda m: (m["file"], m["line"], m["mutated"]))
    if not a.quick:
        # tested in a seeded random order: a run stopped early (--summarize) is still a sample
        # of every file, not of the first files in name order
        random.Random(a.seed).shuffle(chosen)
    generated = sum(len(v) for v in all_mutants.values())
    print(f"mutation: {generated} mutants of {len(files)} files (universalmutator), testing {len(chosen)} (seed {a.seed}"
          f"{', shard ' + a.shard if a.shard else ''}, {a.workers} worker{'s' if a.workers > 1 else ''})", flush=True)

    def mkey(m):
        return f"{m['file']}@{fhash[m['file']]}:{m['line']}:{m['mutated']}"
    fkeys = {f: Keys(f, (ROOT / f).read_text()) for f in files}

    def fk(m):
        """The block key (mutation_keys.py): unchanged while the mutant's function is."""
        return fkeys[m["file"]].fkey(m["line"], m["mutated"])
    journal = out / "journal.jsonl"
    entries = [json.loads(ln) for ln in journal.read_text().splitlines()] if journal.exists() else []
    entry_fk = journal_fkeys(ROOT, entries) if (a.summarize or a.resume) and not a.no_carry else {}
    if a.summarize:
        index = {mkey(m): m for f in files for m in all_mutants[f]}
        index_f = {fk(m): m for f in files for m in all_mutants[f]}
        # journals put together (shards, per-file runs, a re-test of survivors): the last result of
        # a mutant counts; a result of a file's older content counts while the mutant's function
        # (its top-level block) is unchanged: carried over (docs/testing.md)
        last = {}
        for i, r in enumerate(entries):
            fields = {k: r[k] for k in ("status", "by", "reason", "of", "seconds") if k in r}
            if r.get("key") in index:
                m = index[r["key"]]
                last[fk(m)] = dict(m, **fields)
            elif entry_fk.get(i) in index_f:
                m = index_f[entry_fk[i]]
                last[entry_fk[i]] = dict(m, **fields, carried=True)
        # a survivor judged equivalent since its run is reported so, with the list's reason
        judged = resolve_equivalent(load_equivalent(ROOT / a.equivalent), all_mutants)
        for m in last.values():
            why = judged.get((m["file"], m["line"], m["mutated"].strip()))
            if m["status"] == "survived" and why:
                m.update(status="equivalent", reason=why)
        results = sorted(last.values(), key=lambda m: (m["file"], m["line"], m["mutated"]))
        summary = summarize(results, files, a, generated, lang, time.monotonic() - t_start,
                            {f: len(all_mutants[f]) for f in files})
        summary["from_journal"] = True
        (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
        (out / "report.md").write_text(report(summary))
        t = summary["totals"]
        print(f"mutation: {t['killed']} killed, {t['survived']} survived, {t['equivalent']} equivalent, {t['duplicate']} duplicate, "
              f"{t['no_compile']} not compiling (from {journal}): score {t['score']:.1f} % {t['ci95']}")
        return 0
    done_before: dict[str, dict] = {}
    done_f: dict[str, dict] = {}   # by block key: results carried over from a file's older content
    if a.resume and journal.exists():
        for i, r in enumerate(entries):
            if r.get("key"):
                done_before[r["key"]] = r
            if i in entry_fk:
                done_f[entry_fk[i]] = r
        survived = {k for k, r in done_before.items() if r["status"] == "survived"}
        survived_f = {k for k, r in done_f.items() if r["status"] == "survived"}
        if a.retest_survivors or a.only_survivors:
            done_before = {k: r for k, r in done_before.items() if r["status"] != "survived"}
            done_f = {k: r for k, r in done_f.items() if r["status"] != "survived"}
        if a.only_survivors:   # the journal's survivors and nothing else (after new tests)
            chosen = [m for m in chosen if mkey(m) in survived or fk(m) in survived_f]
            for f in RESERVE:
                RESERVE[f] = []
        n_same = sum(1 for m in chosen if mkey(m) in done_before)
        n_carry = sum(1 for m in chosen if mkey(m) not in done_before and fk(m) in done_f)
        print(f"mutation: {n_same} of the {len(chosen)} mutants have a result in {journal}, {n_carry} more "
              f"carried over from an older content of their file (their function unchanged); "
              f"{len(chosen) - n_same - n_carry} to test", flush=True)
    elif journal.exists():
        journal.unlink()

    judged = resolve_equivalent(load_equivalent(ROOT / a.equivalent), all_mutants)
    use_tce = lang == "c" and not a.no_tce
    if lang == "c":
        runners = [CRunner(work, a.jobs, files if a.quick else None, f"w{i}") for i in range(a.workers)]
    else:
        runners = [PyRunner(work, a.jobs)]
        a.workers = 1
    for r in runners:
        for f in files:
            r.apply(None, f)
    if lang == "c" and not a.quick and not a.no_coverage:
        r0 = runners[0]
        srcs = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, check=True,
                              capture_output=True, text=True).stdout.split()
        # what the tests and the code are (not this script, the docs or the equivalence list)
        key = tree_key(r0.src, [f for f in srcs if not f.startswith(("scripts/mutation", "docs/"))])
        cov = build_coverage(r0.src, work, r0.tests, expand(C_FILES), key,
                             log=lambda s: print(s, flush=True))
        for r in runners:
            r.cov = cov
    if not a.no_baseline:
        base_t = runners[0].baseline(max(a.timeout, 1800))
        print(f"mutation: the unmutated tests pass in {base_t:.0f} s", flush=True)

    results = []
    queue = list(chosen)
    lock = threading.Lock()
    seen_obj: dict[str, dict] = {}   # object hash -> the first mutant with it (TCE duplicates)
    state = {"next": 0}

    def replace(m):
        """A sampled mutant that is not tested (no build, equivalent, duplicate): the file's next
        one in the seeded order keeps the number of tested mutants (under the lock)."""
        if a.sample is None:
            return
        while RESERVE.get(m["file"]):
            r = RESERVE[m["file"]].pop(0)
            if not any(q["line"] == r["line"] and q["mutated"] == r["mutated"] and q["file"] == r["file"] for q in queue):
                queue.append(dict(r, must_kill=False))
                break

    def test_one(runner, m):
        t0 = time.monotonic()
        eq = judged.get((m["file"], m["line"], m["mutated"].strip()))
        prev = done_before.get(mkey(m))
        carried = prev is None and fk(m) in done_f
        prev = done_f.get(fk(m)) if carried else prev
        if eq is not None:
            m.update(status="equivalent", reason=eq, seconds=0.0)
            return
        if prev is not None:
            m.update({k: prev[k] for k in ("status", "by", "reason", "of", "seconds") if k in prev}, reused=True,
                     **({"carried": True} if carried else {}))
            return
        if use_tce:
            orig = runner.original_object(m["file"])
            runner.apply(m, m["file"])
            h = runner.object_hash(m["file"])
            if h is None:
                m.update(status="no_compile")
            elif h == orig:
                m.update(status="equivalent", reason="TCE: the object code is identical to the original's")
            else:
                with lock:
                    first = seen_obj.setdefault(h, m)
                if first is not m:
                    m.update(status="duplicate", reason="TCE: the object code is identical to another mutant's",
                             of=f"{first['file']}:{first['line']}: {first['mutated'].strip()}")
            if m.get("status"):
                runner.apply(None, m["file"])
                m["seconds"] = round(time.monotonic() - t0, 1)
                return
        else:
            runner.apply(m, m["file"])
        if getattr(runner, "cov", None) is not None:
            kind, tests = runner.cov.tests_for(m["file"], m["line"], runner.tests)
            if kind == "function" and not tests:
                # no test enters the function: the mutant survives every test without a build
                runner.apply(None, m["file"])
                m.update(status="survived", reason="no test enters the function",
                         seconds=round(time.monotonic() - t0, 1))
                return
        deadline = t0 + a.timeout
        m["status"] = "survived"
        for stage in runner.stages(m["file"], m["line"]):
            ok, bout = runner.build_mutant(a.build_timeout, stage)
            if not ok:
                # compiled alone (TCE) but the build failed: a test target compiles the file with
                # other options, or the link failed; the build's last lines say which
                m.update(status="no_compile", reason="build: " + " | ".join(bout.strip().splitlines()[-3:])[:300])
                break
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

    def worker(runner):
        while True:
            with lock:
                if state["next"] >= len(queue):
                    return
                k = state["next"]
                state["next"] += 1
                m = queue[k]
            try:
                test_one(runner, m)
            except BaseException as e:   # a worker's error stops the run, with the mutant named
                m.update(status="error", reason=repr(e))
                with lock:
                    state["next"] = len(queue)
                raise
            with lock:
                if m["status"] in ("no_compile", "duplicate") or (
                        m["status"] == "equivalent" and m.get("reason", "").startswith("TCE")):
                    replace(m)
                results.append(m)
                if not m.get("reused"):
                    with journal.open("a") as j:
                        j.write(json.dumps(dict({k: m[k] for k in ("file", "line", "mutated", "status", "by", "reason", "of", "seconds") if k in m},
                                                key=mkey(m), fkey=fk(m))) + "\n")
                el = time.monotonic() - t_start
                tested = [x for x in results if x["status"] in ("killed", "survived")]
                sc = 100.0 * sum(x["status"] == "killed" for x in tested) / len(tested) if tested else 0.0
                if not m.get("reused") or len(results) % 500 == 0:
                    print(f"[{len(results)}/{len(queue)}] {m['file']}:{m['line']} {m['status']}"
                          f"{' by ' + m['by'] if m.get('by') else ''}{' (' + m['reason'] + ')' if m.get('reason') and m['status'] == 'survived' else ''}"
                          f" ({m.get('seconds', 0):.0f} s; elapsed {el/60:.1f} min; score so far {sc:.1f} % of {len(tested)})", flush=True)

    with ThreadPoolExecutor(len(runners)) as ex:
        for fut in [ex.submit(worker, r) for r in runners]:
            fut.result()
    for r in runners:
        r.build_mutant(a.build_timeout)   # leave the copies' builds unmutated
    results.sort(key=lambda m: (m["file"], m["line"], m["mutated"]))

    summary = summarize(results, files, a, generated, lang, time.monotonic() - t_start,
                            {f: len(all_mutants[f]) for f in files})
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    (out / "report.md").write_text(report(summary))
    s = summary["totals"]
    print(f"mutation: {s['killed']} killed, {s['survived']} survived, {s['equivalent']} equivalent, "
          f"{s['duplicate']} duplicate, {s['no_compile']} not compiling (sample of {len(chosen)} of {generated}, "
          f"{len(queue) - len(chosen)} more drawn for those not tested, seed {a.seed}"
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


def wilson(k: int, n: int) -> list[float] | None:
    """95 % Wilson interval of a killed share k/n (percent): what a sample's score says of the
    whole population of mutants it was drawn from."""
    if n == 0:
        return None
    z = 1.96
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * ((p * (1 - p) / n + z * z / (4 * n * n)) ** 0.5) / (1 + z * z / n)
    return [round(100 * max(0.0, c - h), 1), round(100 * min(1.0, c + h), 1)]


def summarize(results, files, a, generated, lang, seconds, gen_per_file=None):
    def pick(st):
        return [{k: m[k] for k in ("file", "line", "original", "mutated", "by", "reason", "of", "seconds")
                 if k in m} for m in results if m["status"] == st]
    per_file = {}
    for f in files:
        rs = [m for m in results if m["file"] == f]
        if not rs:
            continue
        c = {st: sum(1 for m in rs if m["status"] == st) for st in STATUSES}
        den = c["killed"] + c["survived"]
        c["score"] = round(100.0 * c["killed"] / den, 1) if den else None
        c["ci95"] = wilson(c["killed"], den)
        c["results"] = len(rs)   # of the file's generated mutants: all of them in a full run
        c["carried"] = sum(1 for m in rs if m.get("carried"))   # of them, from an older content
        c["generated"] = (gen_per_file or {}).get(f)
        per_file[f] = c
    tot = {st: sum(1 for m in results if m["status"] == st) for st in STATUSES}
    tot["not_covered"] = sum(1 for m in results if m["status"] == "survived" and m.get("reason"))
    den = tot["killed"] + tot["survived"]
    tot["score"] = round(100.0 * tot["killed"] / den, 1) if den else 100.0
    tot["ci95"] = wilson(tot["killed"], den)
    tot["timeouts"] = sum(1 for m in results if m.get("by", "").startswith("timeout"))
    tot["carried"] = sum(1 for m in results if m.get("carried"))
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
        "equivalent": pick("equivalent"), "duplicate": pick("duplicate"), "no_compile": pick("no_compile"),
        "workers": getattr(a, "workers", 1), "coverage": not getattr(a, "no_coverage", True) and not a.quick,
    }


STATUSES = ("killed", "survived", "equivalent", "duplicate", "no_compile")


def report(s) -> str:
    t = s["totals"]
    L = [f"# Mutation run ({s['language']}, {s['tool']})", "",
         f"Commit {s['commit']}, {s['date']}, seed {s['seed']}, sample {s['sample'] or 'all'} of {s['generated']} mutants, "
         f"{s['seconds']/60:.1f} min ({s['seconds_per_tested_mutant']} s a built and tested mutant).", "",
         f"**{t['killed']} killed** ({t['timeouts']} of them by the time limit of {s['timeout_s']:.0f} s), "
         f"**{t['survived']} survived** ({t['not_covered']} in functions no test enters), {t['equivalent']} equivalent, "
         f"{t['duplicate']} duplicate, {t['no_compile']} not compiling: "
         f"score {t['score']:.1f} % of the non-equivalent, non-duplicate mutants that build.", "",
         f"95 % interval of the score (Wilson): {t['ci95']} %." if t.get("ci95") else "", "",
         (f"{t['carried']} of the results carried over from an older content of their file, their function "
          f"unchanged (docs/testing.md); the column *carried* per file." if t.get("carried") else ""), "",
         "| file | results of generated (carried) | killed | survived | equivalent | duplicate | not compiling | score | 95 % interval |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for f, c in s["per_file"].items():
        sc = f"{c['score']:.1f} %" if c["score"] is not None else "-"
        ci = f"{c['ci95'][0]:.0f}-{c['ci95'][1]:.0f} %" if c.get("ci95") else "-"
        L.append(f"| {f} | {c.get('results', '-')} of {c.get('generated') or '-'} ({c.get('carried', 0)}) | {c['killed']} | {c['survived']} | {c['equivalent']} | {c['duplicate']} | {c['no_compile']} | {sc} | {ci} |")
    L += ["", "## Survivors", ""]
    for m in s["survived"] or []:
        L += [f"- `{m['file']}:{m['line']}`{' (' + m['reason'] + ')' if m.get('reason') else ''}",
              f"  - `{m['original'].strip()}`", f"  + `{m['mutated'].strip()}`"]
    if not s["survived"]:
        L.append("None.")
    L += ["", "## Equivalent (scripts/mutation_equivalent.txt, or TCE: identical object code)", ""]
    for m in s["equivalent"] or []:
        L.append(f"- `{m['file']}:{m['line']}` `{m['mutated'].strip()}`: {m['reason']}")
    if not s["equivalent"]:
        L.append("None in this sample.")
    L += ["", "## Duplicates (TCE: the same object code as an earlier mutant; not scored)", ""]
    for m in s["duplicate"] or []:
        L.append(f"- `{m['file']}:{m['line']}` `{m['mutated'].strip()}` = `{m.get('of', '')}`")
    if not s["duplicate"]:
        L.append("None.")
    L += ["", "## Killed", ""]
    for m in s["killed"]:
        L.append(f"- `{m['file']}:{m['line']}` `{m['mutated'].strip()}` by {m['by']}")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
