#!/usr/bin/env python3
"""Regenerate (or with --check, verify) the scenario key table in docs/simulator.md from
`mcsim keys`, the single source of truth."""
import subprocess
import sys
from pathlib import Path

BEGIN, END = "<!-- keys:begin -->", "<!-- keys:end -->"


def main():
    args = sys.argv[1:]
    check = "--check" in args
    args = [a for a in args if a != "--check"]
    mcsim = args[0] if args else "build/host/sim/app/mcsim"
    doc = Path(__file__).resolve().parent.parent / "docs" / "simulator.md"
    table = subprocess.run([mcsim, "keys"], check=True, capture_output=True, text=True).stdout
    text = doc.read_text()
    a, b = text.index(BEGIN) + len(BEGIN), text.index(END)
    new = text[:a] + "\n" + table + text[b:]
    if check:
        if new != text:
            print("docs/simulator.md: the key table differs from `mcsim keys`; run scripts/gen_docs.py")
            return 1
        print("docs/simulator.md: key table in sync")
        return 0
    doc.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main())
