#!/usr/bin/env python3
"""Keep the mutation lists (scripts/mutation_equivalent.txt, scripts/mutation_must_kill.txt) on
the lines they judge after the files they name were edited.

Both lists key a mutant by path:line:mutated line. An edit above a listed line moves it;
scripts/mutation.py then finds the entry's mutant by its text within 40 lines (must-kill: the
nearest), so the judgement follows, but the numbers drift: --remap puts them back.

  scripts/mutation_lists.py --remap BASE    move every entry of a file changed since the commit
                                            BASE to its line in the working tree (difflib on the
                                            file at BASE and now); an entry whose line itself was
                                            edited or removed is left as is and named: re-judge it
                                            (run it once per edit: a second run against the same
                                            BASE moves entries of similar neighbouring lines again)
  scripts/mutation_lists.py --check         name the entries whose line no longer looks like their
                                            mutated text: found within 40 lines (scripts/mutation.py
                                            finds them by text there: a note), or lost (stale: fails)

Exit status 1 when an entry needs a person (re-judge or stale), else 0.
"""
from __future__ import annotations

import argparse
import difflib
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LISTS = ("scripts/mutation_equivalent.txt", "scripts/mutation_must_kill.txt")
REACH = 40   # lines: as far as scripts/mutation.py looks for an entry's mutant by its text


def parse(raw: str) -> tuple[str, int, str] | None:
    """path, line, rest (the mutated text and, in the equivalence list, ' -> reason') of an entry."""
    if not raw.strip() or raw.lstrip().startswith("#"):
        return None
    f, line, rest = raw.split(":", 2)
    return f.strip(), int(line), rest


def line_map(old: list[str], new: list[str]) -> dict[int, int]:
    """1-based line of `old` -> its line in `new`, for the lines the edit left unchanged."""
    out = {}
    sm = difflib.SequenceMatcher(a=old, b=new, autojunk=False)
    for tag, i1, i2, j1, _ in sm.get_opcodes():
        if tag == "equal":
            for k in range(i2 - i1):
                out[i1 + k + 1] = j1 + k + 1
    return out


def at_commit(base: str, path: str) -> list[str] | None:
    r = subprocess.run(["git", "show", f"{base}:{path}"], cwd=ROOT, capture_output=True, text=True)
    return r.stdout.splitlines() if r.returncode == 0 else None


def looks_like(src_line: str, mutated: str) -> bool:
    """A one-line mutant keeps most of its line: a mutated text far from the source line at the
    entry's number means the entry is not on its line."""
    a, b = src_line.strip(), mutated.split(" -> ", 1)[0].strip()
    for const in ("(0==1)", "(1==1)"):   # a whole condition replaced: the text around it stays
        if const in b:
            pre, post = b.split(const, 1)
            if a.startswith(pre) and a.endswith(post):
                return True
    return difflib.SequenceMatcher(a=a, b=b, autojunk=False).ratio() >= 0.6


def remap(base: str) -> int:
    changed = set(subprocess.run(["git", "diff", "--name-only", base, "--"], cwd=ROOT, check=True,
                                 capture_output=True, text=True).stdout.split())
    changed |= set(subprocess.run(["git", "ls-files", "-mo", "--exclude-standard"], cwd=ROOT, check=True,
                                  capture_output=True, text=True).stdout.split())
    maps: dict[str, dict[int, int] | None] = {}
    need = 0
    for lst in LISTS:
        p = ROOT / lst
        if not p.exists():
            continue
        lines, moved = p.read_text().splitlines(), 0
        for k, raw in enumerate(lines):
            e = parse(raw)
            if not e or e[0] not in changed:
                continue
            f, ln, rest = e
            if f not in maps:
                old = at_commit(base, f)
                cur = ROOT / f
                maps[f] = line_map(old, cur.read_text().splitlines()) if old is not None and cur.exists() else None
            m = maps[f]
            old_src = at_commit(base, f) or []
            if not (1 <= ln <= len(old_src) and looks_like(old_src[ln - 1], rest)):
                continue   # not on its line at BASE: already moved (a second --remap) or stale (--check)
            if m is None or ln not in m:
                print(f"{lst}:{k + 1}: {f}:{ln}: the line was edited or removed since {base}: re-judge it")
                need += 1
            elif m[ln] != ln:
                lines[k] = f"{f}:{m[ln]}:{rest}"
                moved += 1
        if moved:
            p.write_text("\n".join(lines) + "\n")
        print(f"{lst}: {moved} entries moved")
    return 1 if need else 0


def check() -> int:
    bad = 0
    for lst in LISTS:
        p = ROOT / lst
        if not p.exists():
            continue
        for k, raw in enumerate(p.read_text().splitlines()):
            e = parse(raw)
            if not e:
                continue
            f, ln, rest = e
            src = ROOT / f
            text = src.read_text().splitlines() if src.exists() else []
            if 1 <= ln <= len(text) and looks_like(text[ln - 1], rest):
                continue
            near = [n for n in range(max(1, ln - REACH), min(len(text), ln + REACH) + 1) if looks_like(text[n - 1], rest)]
            if near:   # scripts/mutation.py finds it by its text: only the number is off
                n = min(near, key=lambda n: abs(n - ln))
                print(f"{lst}:{k + 1}: {f}:{ln} is on line {n} now (found by its text; tidy with --remap)")
            else:
                print(f"{lst}:{k + 1}: {f}:{ln}: no line within {REACH} looks like its mutated text: stale")
                bad += 1
    print(f"mutation lists: {bad} stale entries")
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--remap", metavar="BASE", help="move the entries of files changed since commit BASE")
    g.add_argument("--check", action="store_true", help="name the entries that are not on their line")
    a = ap.parse_args()
    return remap(a.remap) if a.remap else check()


if __name__ == "__main__":
    sys.exit(main())
