#!/usr/bin/env python3
"""Section sizes of a firmware image and its size budget (build step of firmware/image).

Code = every allocated read-only section (vectors, text, read-only data, unwind tables) except the
configuration area .mc_config (data a tool writes, reported on its own); RAM = every allocated
writable section (.data, .bss, the stacks). Exits 1 with the excess when a budget is exceeded."""
import argparse
import re
import subprocess
import sys


def sections(elf, readelf):
    out = subprocess.run([readelf, "-S", "-W", elf], check=True, capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        m = re.match(r"\s*\[\s*\d+\]\s+(\S+)\s+(\S+)\s+([0-9a-f]+)\s+[0-9a-f]+\s+([0-9a-f]+)\s+\S+\s+(\S*)", line)
        if not m:
            continue
        name, typ, addr, size, flags = m.group(1), m.group(2), int(m.group(3), 16), int(m.group(4), 16), m.group(5)
        if "A" in flags and size > 0:
            rows.append((name, typ, addr, size, flags))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("elf")
    ap.add_argument("--code", type=int, required=True, help="code budget [bytes]")
    ap.add_argument("--ram", type=int, required=True, help="RAM budget [bytes]")
    ap.add_argument("--size", default="arm-none-eabi-size", help="the size tool (its readelf is used)")
    a = ap.parse_args()
    readelf = a.size[: -len("size")] + "readelf" if a.size.endswith("size") else "arm-none-eabi-readelf"
    rows = sections(a.elf, readelf)
    code = sum(r[3] for r in rows if "W" not in r[4] and r[0] != ".mc_config")
    config = sum(r[3] for r in rows if r[0] == ".mc_config")
    ram = sum(r[3] for r in rows if "W" in r[4])
    print(f"-- image {a.elf}")
    for name, typ, addr, size, flags in rows:
        print(f"   {name:<16} 0x{addr:08x} {size:>7} B  {'RAM' if 'W' in flags else 'config' if name == '.mc_config' else 'code'}")
    print(f"-- code {code} B of {a.code} B ({100.0 * code / a.code:.0f} %), RAM {ram} B of {a.ram} B "
          f"({100.0 * ram / a.ram:.0f} %), configuration area {config} B")
    bad = []
    if code > a.code:
        bad.append(f"code {code} B exceeds the budget of {a.code} B by {code - a.code} B")
    if ram > a.ram:
        bad.append(f"RAM {ram} B exceeds the budget of {a.ram} B by {ram - a.ram} B")
    if bad:
        print("image_budget: " + "; ".join(bad), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
