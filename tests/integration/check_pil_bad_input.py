#!/usr/bin/env python3
"""Bad input to the PIL loader: `mcsim run S --pil FILE` must exit 2 with the reason, for a file
that is not an ELF, an ELF for another architecture, a missing file, and an ARM image whose vector
table was removed (made from a real image with objcopy when --image and --objcopy are given)."""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile


def expect_rc2(mcsim, scenario, image, words, what):
    p = subprocess.run([mcsim, "run", scenario, "--quiet", "--out", os.path.join(tempfile.gettempdir(), "pil_bad"),
                        "--pil", image], capture_output=True, text=True)
    msg = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    ok = p.returncode == 2 and all(w.lower() in msg.lower() for w in words)
    print(f"{'ok  ' if ok else 'FAIL'} {what}: rc {p.returncode}: {msg}")
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--image", help="a good ARM image (for the missing-vector case)")
    ap.add_argument("--objcopy", default="arm-none-eabi-objcopy")
    a = ap.parse_args()
    ok = True
    with tempfile.TemporaryDirectory() as d:
        txt = os.path.join(d, "notes.elf")
        with open(txt, "w") as f:
            f.write("not an image\n")
        ok &= expect_rc2(a.mcsim, a.scenario, txt, ["not an ELF"], "a text file")
        ok &= expect_rc2(a.mcsim, a.scenario, os.path.join(d, "missing.elf"), ["missing.elf"], "a missing file")
        host_elf = shutil.which("sh") or "/bin/sh"
        ok &= expect_rc2(a.mcsim, a.scenario, os.path.realpath(host_elf), ["not ARM"], "an x86-64 ELF")
        if a.image and shutil.which(a.objcopy):
            novec = os.path.join(d, "novec.elf")
            subprocess.run([a.objcopy, "--remove-section", ".vectors", a.image, novec], check=True)
            ok &= expect_rc2(a.mcsim, a.scenario, novec, ["vector"], "an image without its vector table")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
