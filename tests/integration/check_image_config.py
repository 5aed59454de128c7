#!/usr/bin/env python3
"""`mcsim image-config`: the scenario's configuration written into a firmware image's .mc_config
section. Checks the records in the patched ELF (magic, version, CRC-32 of each, the parameter
count, the model record's flux-map size), that nothing else in the file changed, and that bad
input exits 2 with the reason."""
import argparse
import os
import struct
import subprocess
import sys
import tempfile
import zlib


def section(objcopy, elf, name, out):
    subprocess.run([objcopy, "-O", "binary", f"--only-section={name}", elf, out], check=True)
    with open(out, "rb") as f:
        return f.read()




def fnv1a(b):
    h = 0x811C9DC5
    for c in b:
        h = ((h ^ c) * 0x01000193) & 0xFFFFFFFF
    return h


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--image", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--objcopy", default="arm-none-eabi-objcopy")
    a = ap.parse_args()
    bad = []
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "configured.elf")
        p = subprocess.run([a.mcsim, "image-config", a.scenario, "--image", a.image, "--out", out],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"check_image_config: image-config exited {p.returncode}: {p.stderr}")
        area = section(a.objcopy, out, ".mc_config", os.path.join(d, "area.bin"))
        blank = section(a.objcopy, a.image, ".mc_config", os.path.join(d, "blank.bin"))
        # mc_config_area_t: the records (erased: 0xFF), then the map in place (zero: none)
        records = 4096 + 14336
        if blank[:records] != b"\xff" * records or blank[records:] != b"\x00" * (len(blank) - records):
            bad.append("the built image's configuration area is not erased")
        if len(area) != len(blank):
            bad.append(f"area size {len(area)} != {len(blank)}")
        # parameter record at 0: magic "MCPB", version 2, table hash, n, n pairs (key by name and
        # type, value), CRC (mc/store.h)
        magic, ver, _hash, n = struct.unpack_from("<4I", area, 0)
        plen = 4 * (5 + 2 * n)
        if magic != 0x4250434D or ver != 2 or not (50 < n < 1000):
            bad.append(f"parameter record header {magic:#x} v{ver} n={n}")
        elif struct.unpack_from("<I", area, 16)[0] & ~0x8 != (fnv1a(b"motor.pole_pairs") & 0xFFFFFFF0) | 1:
            bad.append("the first entry's key is not motor.pole_pairs' (FNV-1a of the name, type I32)")
        elif struct.unpack_from("<I", area, plen - 4)[0] != zlib.crc32(area[:plen - 4]):
            bad.append("parameter record CRC")
        # model record at 4096: magic "MCMB", version, rs, ld, lq, psi, has_map, [n_d, n_q, ...], CRC
        m = area[4096:]
        magic, ver = struct.unpack_from("<2I", m, 0)
        has_map = struct.unpack_from("<I", m, 24)[0]
        nd, nq = struct.unpack_from("<2I", m, 28) if has_map else (0, 0)
        mlen = 4 * (14 + 2 * nd * nq) if has_map else 32
        if magic != 0x424D434D or ver != 1:
            bad.append(f"model record header {magic:#x} v{ver}")
        elif has_map != 1 or not (2 <= nd <= 41 and 2 <= nq <= 41):
            bad.append(f"the demo's estimator uses a flux map: has_map {has_map}, {nd} x {nq}")
        elif struct.unpack_from("<I", m, mlen - 4)[0] != zlib.crc32(m[:mlen - 4]):
            bad.append("model record CRC")
        else:   # the map in place (int n_d, n_q; float id0, did, iq0, diq, psi_d[41*41], psi_q[41*41])
            mp = area[records:]
            cells = nd * nq
            if (struct.unpack_from("<2i", mp, 0) != (nd, nq) or mp[8:24] != m[36:52]
                    or mp[24:24 + 4 * cells] != m[52:52 + 4 * cells]
                    or mp[24 + 4 * 41 * 41:24 + 4 * 41 * 41 + 4 * cells] != m[52 + 4 * cells:52 + 8 * cells]):
                bad.append("the map in place differs from the model record's map")
        with open(a.image, "rb") as f1, open(out, "rb") as f2:
            x, y = f1.read(), f2.read()
        changed = sum(1 for u, v in zip(x, y) if u != v)
        if len(x) != len(y) or changed > len(area):
            bad.append(f"{changed} bytes changed outside the configuration area")
        print(f"check_image_config: parameter record {n} entries, model record with a {nd} x {nq} flux map, "
              f"{changed} bytes of the ELF changed")
        txt = os.path.join(d, "x.elf")
        with open(txt, "w") as f:
            f.write("text")
        p = subprocess.run([a.mcsim, "image-config", a.scenario, "--image", txt, "--out", os.path.join(d, "y.elf")],
                           capture_output=True, text=True)
        if p.returncode != 2 or "not an ELF" not in p.stderr:
            bad.append(f"a text file as the image: rc {p.returncode}, {p.stderr.strip()}")
    for b in bad:
        print("check_image_config: FAIL: " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
