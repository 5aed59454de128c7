#!/usr/bin/env python3
"""The AM263x boot image read back as TI's SBL reads it, against the ELF: the multicore header
(MSTR, one file, device 55, core 0 = R5FSS0-0, MEND), the RPRC header (RPRC, the ELF's entry,
version 1), and every loadable section of the ELF (allocated, with contents: what
arm-none-eabi-readelf lists, independent of the writer's ELF reader) present once, at its run
address, with its size and every byte equal; nothing else in the image, no byte after the last
section. Then the load addresses: every PT_LOAD segment with contents must be loaded where it
runs (or its bytes at its load address must be in the image), else the startup would read bytes
the SBL never wrote.

  check_boot_image.py --elf IMAGE.elf --image IMAGE.appimage [--readelf arm-none-eabi-readelf]
"""
import argparse
import re
import struct
import subprocess
import sys

# bootloader_priv.h (mcupsdk-core): BOOTLOADER_META_HDR_MAGIC_STR/END, BOOTLOADER_RPRC_MAGIC_NUMBER
MSTR, MEND, RPRC = 0x5254534D, 0x444E454D, 0x43525052


def parse_appimage(b):
    """{core_id: (entry, [(addr, bytes)])}, following Bootloader_parseMultiCoreAppImage and
    Bootloader_rprcImageLoad; raises ValueError on anything they would not accept."""
    magic, nfiles, dev, _ = struct.unpack_from("<4I", b, 0)
    if magic != MSTR:
        raise ValueError(f"meta header magic 0x{magic:08x}, not MSTR")
    if dev != 55:
        raise ValueError(f"device id {dev}, not 55 (AM263x)")
    if not 1 <= nfiles <= 10:   # BOOTLOADER_MAX_INPUT_FILES
        raise ValueError(f"{nfiles} files")
    cores = [struct.unpack_from("<2I", b, 16 + 8 * k) for k in range(nfiles)]
    rsvd, end = struct.unpack_from("<2I", b, 16 + 8 * nfiles)
    if end != MEND:
        raise ValueError(f"meta header end 0x{end:08x}, not MEND")
    out, last = {}, 0
    for core, off in cores:
        magic, entry, _, nsec, version = struct.unpack_from("<5I", b, off)
        if magic != RPRC:
            raise ValueError(f"core {core}: RPRC magic 0x{magic:08x} at offset {off}")
        if version != 1:
            raise ValueError(f"core {core}: RPRC version {version}")
        p, secs = off + 20, []
        for _ in range(nsec):
            addr, _, size, _, _ = struct.unpack_from("<5I", b, p)
            if p + 20 + size > len(b):
                raise ValueError(f"core {core}: section at 0x{addr:08x} runs past the end of the file")
            secs.append((addr, b[p + 20:p + 20 + size]))
            p += 20 + size
        out[core] = (entry, secs)
        last = max(last, p)
    if last != len(b):
        raise ValueError(f"{len(b) - last} bytes after the last section")
    return out


def elf_sections(readelf, elf):
    """[(name, addr, bytes)] of the allocated sections with contents, from readelf -S."""
    txt = subprocess.run([readelf, "-S", "-W", elf], capture_output=True, text=True, check=True).stdout
    with open(elf, "rb") as f:
        data = f.read()
    out = []
    for m in re.finditer(r"\]\s+(\S+)\s+(\S+)\s+([0-9a-f]{8})\s+([0-9a-f]{6,})\s+([0-9a-f]{6,})\s+[0-9a-f]{2}\s+(\S*)\s", txt):
        name, typ, addr, off, size, flags = m.groups()
        if "A" in flags and typ != "NOBITS" and int(size, 16) > 0:
            o, n = int(off, 16), int(size, 16)
            out.append((name, int(addr, 16), data[o:o + n]))
    return out


def elf_segments(readelf, elf):
    txt = subprocess.run([readelf, "-l", "-W", elf], capture_output=True, text=True, check=True).stdout
    return [(int(v, 16), int(p, 16), int(fs, 16)) for v, p, fs in
            re.findall(r"^\s*LOAD\s+0x[0-9a-f]+\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)", txt, re.M)]


def entry_of(readelf, elf):
    txt = subprocess.run([readelf, "-h", elf], capture_output=True, text=True, check=True).stdout
    return int(re.search(r"Entry point address:\s+0x([0-9a-f]+)", txt).group(1), 16)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--image", required=True)
    ap.add_argument("--readelf", default="arm-none-eabi-readelf")
    a = ap.parse_args()
    with open(a.image, "rb") as f:
        img = parse_appimage(f.read())
    bad = []
    if list(img) != [0]:
        bad.append(f"cores {list(img)}, expected [0] (R5FSS0-0)")
    entry, secs = img.get(0, (None, []))
    if entry != entry_of(a.readelf, a.elf):
        bad.append(f"entry 0x{entry:08x}, the ELF's is 0x{entry_of(a.readelf, a.elf):08x}")
    want = elf_sections(a.readelf, a.elf)
    got = {addr: data for addr, data in secs}
    if len(got) != len(secs):
        bad.append("two sections at one address")
    for name, addr, data in want:
        g = got.pop(addr, None)
        if g is None:
            bad.append(f"{name} (0x{addr:08x}, {len(data)} B) not in the image")
        elif g != data:
            diff = next((k for k in range(min(len(g), len(data))) if g[k] != data[k]), min(len(g), len(data)))
            bad.append(f"{name} at 0x{addr:08x}: {len(g)} B in the image, {len(data)} B in the ELF, first difference at +{diff}")
    for addr, data in got.items():
        bad.append(f"a section at 0x{addr:08x} ({len(data)} B) that the ELF does not have")
    # what the memory holds after the SBL: every segment's file bytes at its load address
    mem = {}
    for addr, data in secs:
        for k, v in enumerate(data):
            mem[addr + k] = v
    for vaddr, paddr, filesz in elf_segments(a.readelf, a.elf):
        if filesz and vaddr != paddr and any(paddr + k not in mem for k in range(filesz)):
            bad.append(f"segment run at 0x{vaddr:08x} is loaded from 0x{paddr:08x} ({filesz} B), where the image writes nothing")
    n = sum(len(d) for _, _, d in want)
    print(f"check_boot_image: {a.image}: {len(secs)} sections, {n} B, against {a.elf}")
    for b in bad:
        print("check_boot_image: FAIL: " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
