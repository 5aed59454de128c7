#!/usr/bin/env python3
"""Regenerate (or with --check, verify) the generated parts of the docs, each from one source:
the scenario key table in docs/simulator.md (`mcsim keys`, the schema), the drive's parameter
table in docs/parameters.md (`mcsim params`, the firmware's params_table.h), the CANopen object
tables in docs/can.md and the EDS tools/mctools/data/drive.eds (`co-gen`, the firmware's object
dictionary), and the fault tables of docs/protection.md (`mcsim faults`) and docs/can.md with
tools/mctools/data/faults.json (`co-gen faults`, the firmware's mc/faults.h). co-gen is looked for
beside mcsim's build tree (BUILD/sim/tools/co-gen)."""
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def splice(text, table, tag="keys"):
    """text with the part between <!-- TAG:begin --> and <!-- TAG:end --> replaced by table."""
    begin, end = f"<!-- {tag}:begin -->", f"<!-- {tag}:end -->"
    a, b = text.index(begin) + len(begin), text.index(end)
    return text[:a] + "\n" + table + text[b:]


def run(*cmd):
    return subprocess.run([str(c) for c in cmd], check=True, capture_output=True, text=True).stdout


def main():
    args = sys.argv[1:]
    check = "--check" in args
    args = [a for a in args if a != "--check"]
    mcsim = Path(args[0] if args else "build/host/sim/app/mcsim")
    co_gen = mcsim.resolve().parent.parent / "tools" / "co-gen"
    docs = ROOT / "docs"
    status = 0
    outputs = []   # (path, new text, what it comes from)
    for name, cmd in (("simulator.md", "keys"), ("parameters.md", "params")):
        doc = docs / name
        outputs.append((doc, splice(doc.read_text(), run(mcsim, cmd)), f"`mcsim {cmd}`"))
    doc = docs / "protection.md"
    outputs.append((doc, splice(doc.read_text(), run(mcsim, "faults"), "faults"), "`mcsim faults`"))
    doc = docs / "can.md"
    text = splice(doc.read_text(), run(co_gen, "md"))
    outputs.append((doc, splice(text, run(co_gen, "faults", "md"), "faults"), "`co-gen md`, `co-gen faults md`"))
    outputs.append((ROOT / "tools" / "mctools" / "data" / "faults.json", run(co_gen, "faults", "json"),
                    "`co-gen faults json`"))
    with tempfile.TemporaryDirectory() as tmp:
        eds = Path(tmp) / "drive.eds"
        subprocess.run([str(co_gen), "eds", str(eds)], check=True)
        outputs.append((ROOT / "tools" / "mctools" / "data" / "drive.eds", eds.read_text(), "`co-gen eds`"))
    for path, new, source in outputs:
        rel = path.relative_to(ROOT)
        old = path.read_text() if path.exists() else ""
        if check:
            if new != old:
                print(f"{rel}: differs from {source}; run scripts/gen_docs.py {mcsim}")
                status = 1
            else:
                print(f"{rel}: in sync with {source}")
        elif new != old:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(new)
            print(f"{rel}: regenerated from {source}")
    return status


if __name__ == "__main__":
    sys.exit(main())
