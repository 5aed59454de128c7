"""scripts/mutation_keys.py: mutation results carried over while the mutant's function is
unchanged (docs/testing.md)."""

import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from mutation_keys import Keys, blocks, file_hash, journal_fkeys  # noqa: E402

V1 = """/* a file */
#include "x.h"

static int f(int a)
{
    return a + 1;
}

int g(int b)
{
    return b * 2;
}
"""
# f edited (one more line), g moved down by it but unchanged
V2 = V1.replace("    return a + 1;", "    a += 2;\n    return a + 1;")


def test_blocks_end_at_column_zero_braces():
    b = blocks(V1)
    assert [(s, e) for s, e, _ in b] == [(1, 7), (8, 12), (13, 13)]


def test_key_follows_the_function_not_the_file():
    k1, k2 = Keys("f.c", V1), Keys("f.c", V2)
    # g's line 11 in V1 is line 12 in V2: same key; f's mutant differs (its block changed)
    assert k1.fkey(11, "    return b * 3;") == k2.fkey(12, "    return b * 3;") is not None
    assert k1.fkey(6, "    return a - 1;") != k2.fkey(7, "    return a - 1;")
    # the offset and the mutated text are part of the key
    assert k1.fkey(11, "    return b * 3;") != k1.fkey(11, "    return b / 2;")
    assert k1.fkey(10, "{ ") != k1.fkey(11, "{ ")


def test_journal_entries_mapped_through_the_history(tmp_path):
    def git(*a):
        subprocess.run(["git", *a], cwd=tmp_path, check=True, capture_output=True)
    git("init", "-q")
    git("config", "user.email", "t@t")
    git("config", "user.name", "t")
    src = tmp_path / "f.c"
    src.write_text(V1)
    git("add", "f.c")
    git("commit", "-qm", "v1")
    src.write_text(V2)
    git("commit", "-qam", "v2")
    h1 = file_hash(V1.encode())
    entries = [
        {"key": f"f.c@{h1}:11:    return b * 3;", "line": 11, "mutated": "    return b * 3;", "status": "killed"},
        {"key": f"f.c@{h1}:6:    return a - 1;", "line": 6, "mutated": "    return a - 1;", "status": "killed"},
        {"key": "f.c@0000000000000000:6:x", "line": 6, "mutated": "x", "status": "killed"},   # unknown content
        {"key": "whatever", "fkey": "f.c#abc:1:y", "line": 1, "mutated": "y", "status": "survived"},
    ]
    got = journal_fkeys(tmp_path, entries)
    k2 = Keys("f.c", V2)
    assert got[0] == k2.fkey(12, "    return b * 3;")        # carried over to the present content
    assert got[1] == Keys("f.c", V1).fkey(6, "    return a - 1;") != k2.fkey(7, "    return a - 1;")
    assert 2 not in got and got[3] == "f.c#abc:1:y"
