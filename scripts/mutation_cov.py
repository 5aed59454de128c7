"""Per-test line coverage and trivially-equivalent mutants for the mutation run (docs/testing.md).

Coverage: the copy of the tree is built once more with gcc's --coverage on the C code (-O0), every
test runs alone, and gcov says which functions and lines of which firmware source it executed. A
mutant then runs only the tests that enter the function holding its line (those that execute the
line first): a test that never enters the function runs the same program with and without the
mutant, so it cannot kill it, and a function no test enters holds survivors that need no build.
The function, not the line, decides, because gcov books some lines to others (a static table's
declaration line counted only where another object was built). A line outside every function (a
file-scope table) runs the tests that execute the file, then all the others.

TCE (trivial compiler equivalence, Papadakis et al., ICSE 2015): the mutated file is compiled
alone with its library's own command; a mutant whose object code is byte-identical to the
original's is equivalent, one identical to an earlier mutant's is a duplicate of it.
"""
from __future__ import annotations

import gzip
import hashlib
import json
import os
import re
import shlex
import subprocess
import time
from pathlib import Path


def tree_key(src: Path, files: list[str]) -> str:
    h = hashlib.sha256()
    for f in sorted(files):
        p = src / f
        if p.is_file():
            h.update(f.encode() + b"\0" + p.read_bytes())
    return h.hexdigest()[:20]


class Coverage:
    """{test: {source file (repo-relative): set(lines executed)}}, the functions (first and last
    line) each test entered, the functions of each file, the tests' durations."""

    def __init__(self, data: dict):
        self.hits = {t: {f: set(ls) for f, ls in fs.items()} for t, fs in data["hits"].items()}
        self.fhits = {t: {f: set(ls) for f, ls in fs.items()} for t, fs in data["fhits"].items()}
        self.functions = {f: [tuple(x) for x in fs] for f, fs in data["functions"].items()}
        self.seconds = data["seconds"]

    def tests_for(self, rel: str, line: int, tests: list[str]) -> tuple[str, list[str]]:
        """('function', the tests that enter the function holding the line: first those gcov says
        execute the line, then the others, each group fastest first; empty: no test enters it),
        or ('file', the tests that execute any line of the file) for a line outside every
        function (a file-scope table, a declaration). The function, not the line, decides: gcov
        books some lines (a static table's declaration, a wrapped condition) to another line."""
        order = sorted(tests, key=lambda t: (self.seconds.get(t, 1e9), t))
        fn = next((f for f in self.functions.get(rel, ()) if f[0] <= line <= f[1]), None)
        if fn is None:
            return "file", [t for t in order if self.hits.get(t, {}).get(rel)]
        enter = [t for t in order if fn[0] in self.fhits.get(t, {}).get(rel, ())]
        first = [t for t in enter if line in self.hits.get(t, {}).get(rel, ())]
        return "function", first + [t for t in enter if t not in first]


def build_coverage(src: Path, work: Path, tests: list[str], sources: list[str], key: str,
                   log=print) -> Coverage:
    cache = work / f"coverage.{key}.v2.json.gz"   # v2: functions
    if cache.exists():
        return Coverage(json.loads(gzip.decompress(cache.read_bytes())))
    bdir = work / "cov"
    if not (bdir / "build.ninja").exists():
        subprocess.run(["cmake", "-S", str(src), "-B", str(bdir), "-G", "Ninja",
                        "-DCMAKE_BUILD_TYPE=Release", "-DMC_BUILD_IMAGES=OFF",
                        "-DCMAKE_C_FLAGS_RELEASE=-O0 -DNDEBUG", "-DCMAKE_C_FLAGS=--coverage",
                        "-DCMAKE_EXE_LINKER_FLAGS=--coverage", "-DCMAKE_SHARED_LINKER_FLAGS=--coverage"],
                       check=True, stdout=subprocess.DEVNULL)
    log("mutation: building the coverage copy (gcc --coverage -O0)")
    subprocess.run(["ninja", "-C", str(bdir)], check=True, stdout=subprocess.DEVNULL)
    srcset = {str((src / f).resolve()): f for f in sources}
    hits: dict[str, dict[str, list[int]]] = {}
    fhits: dict[str, dict[str, list[int]]] = {}
    functions: dict[str, set[tuple[int, int]]] = {}
    seconds: dict[str, float] = {}
    t_all = time.monotonic()
    for i, t in enumerate(tests):
        for g in bdir.rglob("*.gcda"):
            g.unlink()
        t0 = time.monotonic()
        r = subprocess.run(["ctest", "--test-dir", str(bdir), "-R", f"^{re.escape(t)}$",
                            "--timeout", "1800"], capture_output=True, text=True)
        seconds[t] = round(time.monotonic() - t0, 2)
        if r.returncode != 0:
            raise SystemExit(f"mutation: {t} fails in the coverage build:\n{r.stdout[-2000:]}")
        mine: dict[str, set[int]] = {}
        fmine: dict[str, set[int]] = {}
        for f, hit, fns in gcov_lines(bdir, srcset):
            mine.setdefault(f, set()).update(hit)
            for (a, b, n) in fns:
                functions.setdefault(f, set()).add((a, b))
                if n > 0:
                    fmine.setdefault(f, set()).add(a)
        hits[t] = {f: sorted(ls) for f, ls in mine.items() if ls}
        fhits[t] = {f: sorted(ls) for f, ls in fmine.items() if ls}
        log(f"mutation: coverage [{i + 1}/{len(tests)}] {t} ({seconds[t]:.1f} s, "
            f"{sum(len(v) for v in hits[t].values())} firmware lines; "
            f"{(time.monotonic() - t_all) / 60:.1f} min)")
    data = {"hits": hits, "fhits": fhits, "functions": {f: sorted(v) for f, v in functions.items()},
            "seconds": seconds}
    cache.write_bytes(gzip.compress(json.dumps(data).encode()))
    return Coverage(data)


def gcov_lines(bdir: Path, srcset: dict[str, str]):
    """(repo-relative file, executed lines, [(first line, last line, calls) a function]) for
    every firmware source an object written since the last clean executed (its .gcda exists)."""
    by_dir: dict[Path, list[Path]] = {}
    for g in bdir.rglob("*.gcda"):
        by_dir.setdefault(g.parent, []).append(g)
    for d, gs in by_dir.items():
        r = subprocess.run(["gcov", "--json-format", "--stdout", *[g.name for g in gs]], cwd=d,
                           capture_output=True, text=True)
        for doc in r.stdout.splitlines():
            doc = doc.strip()
            if not doc.startswith("{"):
                continue
            j = json.loads(doc)
            for f in j.get("files", []):
                path = f["file"]
                if not os.path.isabs(path):
                    path = str((Path(j.get("current_working_directory", str(d))) / path).resolve())
                rel = srcset.get(path)
                if rel is None:
                    continue
                hit = {ln["line_number"] for ln in f["lines"] if ln["count"] > 0}
                fns = [(fn["start_line"], fn["end_line"], fn["execution_count"]) for fn in f.get("functions", [])]
                yield rel, hit, fns


class TCE:
    """Compiles one mutated source with the command its firmware library uses."""

    def __init__(self, build: Path, src: Path):
        cc = json.loads((build / "compile_commands.json").read_text())
        self.cmd: dict[str, list[str]] = {}
        self.cwd: dict[str, str] = {}
        for e in cc:
            f = str(Path(e["file"]).resolve())
            # the firmware library's object (not a test target that compiles the file again)
            out = e.get("output", "")
            if f in self.cmd and "/firmware/" not in out:
                continue
            args = e["arguments"] if "arguments" in e else shlex.split(e["command"])
            args = [a for a in args if a != "ccache" and not a.endswith("/ccache")]
            clean, skip = [], False
            for a in args:
                if skip:
                    skip = False
                    continue
                if a in ("-o", "-MT", "-MF"):
                    skip = True
                    continue
                if a == "-MD":
                    continue
                clean.append(a)
            self.cmd[f] = clean
            self.cwd[f] = e["directory"]
        self.src = src

    def object_hash(self, rel: str, out: Path) -> str | None:
        f = str((self.src / rel).resolve())
        if f not in self.cmd:
            return "no-command"
        r = subprocess.run(self.cmd[f] + ["-o", str(out)], cwd=self.cwd[f], capture_output=True)
        if r.returncode != 0:
            return None
        return hashlib.sha256(out.read_bytes()).hexdigest()
