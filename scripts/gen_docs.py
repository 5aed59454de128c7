#!/usr/bin/env python3
"""Regenerate (or with --check, verify) the generated tables of the docs: the scenario key table in
docs/simulator.md from `mcsim keys`, and the drive's parameter table in docs/parameters.md from
`mcsim params` (both come from one source each: the schema and the firmware's params_table.h)."""
import subprocess
import sys
from pathlib import Path

BEGIN, END = "<!-- keys:begin -->", "<!-- keys:end -->"


def main():
    args = sys.argv[1:]
    check = "--check" in args
    args = [a for a in args if a != "--check"]
    mcsim = args[0] if args else "build/host/sim/app/mcsim"
    docs = Path(__file__).resolve().parent.parent / "docs"
    status = 0
    for name, cmd in (("simulator.md", "keys"), ("parameters.md", "params")):
        doc = docs / name
        table = subprocess.run([mcsim, cmd], check=True, capture_output=True, text=True).stdout
        text = doc.read_text()
        a, b = text.index(BEGIN) + len(BEGIN), text.index(END)
        new = text[:a] + "\n" + table + text[b:]
        if check:
            if new != text:
                print(f"docs/{name}: the table differs from `mcsim {cmd}`; run scripts/gen_docs.py")
                status = 1
            else:
                print(f"docs/{name}: table in sync with `mcsim {cmd}`")
        else:
            doc.write_text(new)
    return status


if __name__ == "__main__":
    sys.exit(main())
