"""Per-test line coverage and trivially-equivalent mutants for the mutation run (docs/testing.md).

Coverage: the copy of the tree is built once more with gcc's --coverage on the C code (-O0, so a
line's count is the line's), every test runs alone, and gcov says which lines of which firmware
source it executed. A mutant then runs only the tests that execute its line: a test that never
reaches the line runs the same program with and without the mutant, so it cannot kill it, and a
line no test executes is a survivor without a build. Lines gcov does not count (declarations,
initialisers, continuation lines) fall back to every test that executes the file, then the rest.

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
    """{test: {source file (repo-relative): set(lines executed)}}, executable lines, durations."""

    def __init__(self, data: dict):
        self.hits = {t: {f: set(ls) for f, ls in fs.items()} for t, fs in data["hits"].items()}
        self.executable = {f: set(ls) for f, ls in data["executable"].items()}
        self.seconds = data["seconds"]

    def tests_for(self, rel: str, line: int, tests: list[str]) -> tuple[str, list[str]]:
        """('line', tests executing the line) when gcov counts the line (maybe empty: not
        covered), else ('file', tests executing any line of the file)."""
        order = sorted(tests, key=lambda t: (self.seconds.get(t, 1e9), t))
        if line in self.executable.get(rel, ()):
            return "line", [t for t in order if line in self.hits.get(t, {}).get(rel, ())]
        return "file", [t for t in order if self.hits.get(t, {}).get(rel)]


def build_coverage(src: Path, work: Path, tests: list[str], sources: list[str], key: str,
                   log=print) -> Coverage:
    cache = work / f"coverage.{key}.json.gz"
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
    executable: dict[str, set[int]] = {}
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
        for f, ex, hit in gcov_lines(bdir, srcset):
            executable.setdefault(f, set()).update(ex)
            mine.setdefault(f, set()).update(hit)
        hits[t] = {f: sorted(ls) for f, ls in mine.items() if ls}
        log(f"mutation: coverage [{i + 1}/{len(tests)}] {t} ({seconds[t]:.1f} s, "
            f"{sum(len(v) for v in hits[t].values())} firmware lines; "
            f"{(time.monotonic() - t_all) / 60:.1f} min)")
    data = {"hits": hits, "executable": {f: sorted(v) for f, v in executable.items()},
            "seconds": seconds}
    cache.write_bytes(gzip.compress(json.dumps(data).encode()))
    return Coverage(data)


def gcov_lines(bdir: Path, srcset: dict[str, str]):
    """(repo-relative file, executable lines, executed lines) for every firmware source an
    object written since the last clean executed (its .gcda exists)."""
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
                ex = {ln["line_number"] for ln in f["lines"]}
                hit = {ln["line_number"] for ln in f["lines"] if ln["count"] > 0}
                yield rel, ex, hit


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
