#!/usr/bin/env python3
"""The AM263x image booted the way TI's SBL boots it, against the ELF load: the same scenario run
twice under processor-in-the-loop, once with `--pil IMAGE.elf` (every PT_LOAD segment at its load
address, .bss zeroed: what a debugger's load does) and once with `--pil IMAGE.appimage` (only
the boot image's sections at their run addresses: mcsim's boot mode). Passes when the traces
are identical byte for byte at every period and every metric is equal (but the image's name and
the wall-clock figures). First, boot images the loader must refuse (exit 2 with the reason):
without its ELF beside it, truncated inside a section, for another core.

  check_pil_boot.py --mcsim build/host/sim/app/mcsim --elf IMAGE.elf --boot IMAGE.appimage
                    --scenario S.toml [--set key=value]... [--out DIR]
"""
import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

NOT_COMPARED = {"pil_image", "wall_time_s", "realtime_factor"}


def run(mcsim, scenario, out, sets, image):
    cmd = [mcsim, "run", scenario, "--quiet", "--out", out, "--set", "output.decimation=1", "--pil", image]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None, None, f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr.strip()}"
    with open(os.path.join(out, "metrics.json")) as f:
        m = json.load(f)
    with open(os.path.join(out, "trace.csv"), "rb") as f:
        t = f.read().splitlines()
    return m, t, None


def refused(mcsim, scenario, image, words, what):
    p = subprocess.run([mcsim, "run", scenario, "--quiet", "--out", os.path.join(tempfile.gettempdir(), "pil_boot_bad"),
                        "--pil", image], capture_output=True, text=True)
    msg = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    ok = p.returncode == 2 and all(w in msg for w in words)
    print(f"{'ok  ' if ok else 'FAIL'} {what}: rc {p.returncode}: {msg}")
    return ok


def bad_images(mcsim, scenario, elf, boot):
    ok = True
    with open(boot, "rb") as f:
        good = f.read()
    with tempfile.TemporaryDirectory() as d:
        alone = os.path.join(d, "alone.appimage")
        with open(alone, "wb") as f:
            f.write(good)
        ok &= refused(mcsim, scenario, alone, ["alone.elf", "does not exist"], "a boot image without its ELF")
        for name, data, words, what in (
                ("cut", good[:len(good) // 2], ["runs past the end of the file"], "a truncated boot image"),
                ("core1", good[:16] + struct.pack("<I", 1) + good[20:], ["R5FSS0-0"], "a boot image for core 1")):
            with open(os.path.join(d, name + ".appimage"), "wb") as f:
                f.write(data)
            shutil.copy(elf, os.path.join(d, name + ".elf"))
            ok &= refused(mcsim, scenario, os.path.join(d, name + ".appimage"), words, what)
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--boot", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--out", default="out/check_pil_boot")
    a = ap.parse_args()
    for f in (a.elf, a.boot):
        if not os.path.exists(f):
            sys.exit(f"check_pil_boot: {f} not found (the host build cross-builds it)")
    bad_ok = bad_images(a.mcsim, a.scenario, a.elf, a.boot)
    me, te, err = run(a.mcsim, a.scenario, os.path.join(a.out, "elf"), a.set, a.elf)
    if err:
        sys.exit(f"check_pil_boot: the ELF load failed: {err}")
    mb, tb, err = run(a.mcsim, a.scenario, os.path.join(a.out, "boot"), a.set, a.boot)
    bad = [] if bad_ok else ["a bad boot image was not refused with its reason"]
    if err:
        bad.append(f"the boot image did not run: {err}")
    else:
        if len(te) != len(tb):
            bad.append(f"trace lengths differ: ELF {len(te)} rows, boot image {len(tb)}")
        diff = [k for k, (x, y) in enumerate(zip(te, tb)) if x != y]
        if diff:
            k = diff[0]
            bad.append(f"traces differ in {len(diff)} rows, first at row {k}:\n  ELF  {te[k].decode()}\n  boot {tb[k].decode()}")
        for k in sorted(set(me) | set(mb)):
            if k not in NOT_COMPARED and me.get(k) != mb.get(k):
                bad.append(f"metric {k}: ELF {me.get(k)}, boot image {mb.get(k)}")
    print(f"check_pil_boot: {os.path.basename(a.scenario)}: ELF {a.elf} and boot image {a.boot}: "
          f"{len(te) - 1} periods, " + ("identical" if not bad else "NOT identical"))
    for b in bad:
        print("check_pil_boot: FAIL: " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
