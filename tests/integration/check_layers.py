#!/usr/bin/env python3
"""The firmware's layers (docs/architecture.md): core <- control, estimators <- app <- comms, and the
image on top. Each layer's CMake target exports only its own include folder and links the layers
below, so an upward include does not compile; this check says the same from the sources, with
the file and the line, and also covers headers that no translation unit of their own layer
includes yet. Exit 1 on any upward or sideways include, or a header outside the layer folders."""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FW = ROOT / "firmware"
# what each layer may include besides itself
BELOW = {
    "core": set(),
    "control": {"core"},
    "estimators": {"core"},
    "app": {"core", "control", "estimators"},
    "comms": {"core", "control", "estimators", "app"},
    "image": {"core", "control", "estimators", "app", "comms"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"mc/([A-Za-z0-9_]+\.h)"', re.M)


def main() -> int:
    owner = {}
    for layer in BELOW:
        for h in (FW / layer / "include" / "mc").glob("*.h"):
            if h.name in owner:
                print(f"mc/{h.name} is in two layers: {owner[h.name]} and {layer}")
                return 1
            owner[h.name] = layer
    stray = [p for p in FW.rglob("*.h") if "include" in p.parts and p.parent.name == "mc"
             and p.parts[len(FW.parts)] not in BELOW]
    if (FW / "include").exists() or stray:
        print("headers outside the layer folders:", [str(p.relative_to(ROOT)) for p in stray] or "firmware/include")
        return 1
    bad = 0
    n = 0
    for layer, allowed in BELOW.items():
        for src in sorted((FW / layer).rglob("*.[ch]")):
            text = src.read_text()
            for m in INCLUDE.finditer(text):
                n += 1
                hdr = m.group(1)
                to = owner.get(hdr)
                line = text.count("\n", 0, m.start()) + 1
                where = f"{src.relative_to(ROOT)}:{line}"
                if to is None:
                    print(f"{where}: mc/{hdr} is in no layer")
                    bad += 1
                elif to != layer and to not in allowed:
                    print(f"{where}: {layer} includes mc/{hdr} of layer {to} (allowed: {sorted(allowed) or 'none'})")
                    bad += 1
    print(f"layers: {n} includes in {len(BELOW)} layers checked, {bad} against the layering")
    return 1 if bad or n == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
