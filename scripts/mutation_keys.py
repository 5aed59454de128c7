"""Keys of mutation results that survive edits elsewhere in a file (docs/testing.md, "Results
carried over").

A result is keyed by the file, the hash of the top-level block that holds the mutated line (a
function, a table: the text from after the previous column-0 `}` to the next one, its comment
included), the line's offset in that block and the mutated text. An edit to one function leaves
the results of every other function's mutants standing, as incremental mutation tools do per
class (PIT's history) or per function (mutmut); a survivor is re-tested with
--retest-survivors once tests change. The journal's older entries (keyed by the whole file's
hash) are mapped by finding that content in the repository's history."""

from __future__ import annotations

import hashlib
import subprocess
from pathlib import Path


def blocks(text: str) -> list[tuple[int, int, str]]:
    """(first line, last line, hash) of each top-level block, 1-based lines; a block ends at a
    line starting with `}` in column 0, the text after the last one is a block of its own."""
    lines = text.split("\n")
    out, start = [], 1
    for i, ln in enumerate(lines, 1):
        if ln.startswith("}") or i == len(lines):
            body = "\n".join(lines[start - 1:i])
            out.append((start, i, hashlib.sha256(body.encode()).hexdigest()[:16]))
            start = i + 1
    return out


class Keys:
    """Block keys of one file's content: fkey(line, mutated)."""

    def __init__(self, rel: str, text: str):
        self.rel = rel
        self.blocks = blocks(text)

    def fkey(self, line: int, mutated: str) -> str | None:
        for a, b, h in self.blocks:
            if a <= line <= b:
                return f"{self.rel}#{h}:{line - a}:{mutated}"
        return None


def file_hash(data: bytes) -> str:
    """The whole-file hash of the journal's older keys (`file@hash:line:mutated`)."""
    return hashlib.sha256(data).hexdigest()[:16]


def history_contents(root: Path, rel: str, wanted: set[str]) -> dict[str, str]:
    """{file hash: text} for the versions of `rel` in the repository's history (every branch)
    whose hash is wanted."""
    found: dict[str, str] = {}
    if not wanted:
        return found
    revs = subprocess.run(["git", "rev-list", "--all", "--", rel], cwd=root, capture_output=True,
                          text=True).stdout.split()
    seen_blobs: set[str] = set()
    for rev in revs:
        blob = subprocess.run(["git", "rev-parse", f"{rev}:{rel}"], cwd=root, capture_output=True,
                              text=True).stdout.strip()
        if not blob or blob in seen_blobs:
            continue
        seen_blobs.add(blob)
        data = subprocess.run(["git", "cat-file", "blob", blob], cwd=root, capture_output=True).stdout
        h = file_hash(data)
        if h in wanted and h not in found:
            found[h] = data.decode(errors="replace")
            if len(found) == len(wanted):
                break
    return found


def journal_fkeys(root: Path, entries: list[dict]) -> dict[int, str]:
    """{index in entries: block key} for journal entries: their own `fkey`, else derived from the
    older `file@hash:line:mutated` key where that content is found in the history."""
    out: dict[int, str] = {}
    wanted: dict[str, set[str]] = {}
    for i, r in enumerate(entries):
        if r.get("fkey"):
            out[i] = r["fkey"]
            continue
        k = r.get("key", "")
        if "@" in k:
            rel, rest = k.split("@", 1)
            wanted.setdefault(rel, set()).add(rest.split(":", 1)[0])
    keys: dict[tuple[str, str], Keys] = {}
    for rel, hashes in wanted.items():
        for h, text in history_contents(root, rel, hashes).items():
            keys[(rel, h)] = Keys(rel, text)
    for i, r in enumerate(entries):
        if i in out:
            continue
        k = r.get("key", "")
        if "@" not in k:
            continue
        rel, rest = k.split("@", 1)
        h = rest.split(":", 1)[0]
        kk = keys.get((rel, h))
        if kk is not None:
            fk = kk.fkey(int(r["line"]), r["mutated"])
            if fk is not None:
                out[i] = fk
    return out
