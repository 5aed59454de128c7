#!/usr/bin/env python3
"""The AM263x boot image from the firmware ELF: the per-core RPRC image and the multicore
application image (.appimage) that TI's secondary bootloader (SBL, e.g. sbl_qspi) reads from the
QSPI flash (offset 0x80000 in the SDK's sbl_qspi configuration). Our own writer of TI's documented
format (nothing of TI's code); the facts and where they come from (TexasInstruments/mcupsdk-core):

  RPRC (docs_src/docs/api_guide/components/tools/tools_boot.md "Out2RPRC";
        source/drivers/bootloader/bootloader_priv.h Bootloader_RprcFileHeader/SectionHeader;
        tools/boot/out2rprc/elf2rprc.js, which the SDK's makefiles run):
    file header, 5 little-endian u32: magic 0x43525052 ("RPRC"), entry (e_entry), reserved 0,
      section count, version 1
    per section, 5 u32: address (the section's sh_addr: its RUN address), reserved 0, size,
      reserved CRC 0, reserved 0; then the section's bytes (sizes 8-aligned, so the RPRC image is
      whole words: the C MulticoreImageGen copies size/4 words)
    which sections: SHF_ALLOC, not NOBITS (elf2rprc keeps sh_flags & 2, drops sh_type & 8), sorted
      by address; "RPRC mandates that the sections ... be 8-byte aligned" (tools_boot.md)
  Multicore image (tools_boot.md "Multi-core Image Gen"; bootloader_priv.h Bootloader_MetaHeader*;
        tools/boot/multicoreImageGen/src/MulticoreImageGen.c):
    u32 magic 0x5254534D ("MSTR"), number of files, device id (55: SBL_DEV_ID in the am263x
      examples' makefiles, BOOTLOADER_DEVICE_ID), reserved 0
    per file: u32 core id (the RPRC core id: r5fss0-0 = 0, BOOTIMAGE_CORE_ID_r5fss0-0), u32 offset
      of its RPRC image from the start of the file
    u32 reserved 0, u32 magic 0x444E454D ("MEND"); then the RPRC images, back to back
  The SBL (source/drivers/bootloader/bootloader.c Bootloader_parseMultiCoreAppImage,
  Bootloader_rprcImageLoad) copies each section to its address (R5FSS0-0's TCM addresses map to
  themselves, soc/am263x/bootloader_soc.c gAddrTranslateInfo) and refuses a section starting
  inside its own memory 0x70002000..0x70040000 (gResMemSection); nothing else is written.

Beyond what TI's converter does, this writer refuses an ELF that would not run from such an
image: a PT_LOAD segment whose load address differs from its run address (a startup copy from a
load image the image does not hold: issue 29), a section not 8-aligned, a section in the SBL's
memory or in the QSPI flash window (XIP, which the SDK splits off with xipGen).

  mc_bootimage.py IMAGE.elf [--rprc OUT.rprc] [--out OUT.appimage] [--core-id 0] [--dev-id 55]
                  [--allow-load-image]
"""
import argparse
import struct
import sys

RPRC_MAGIC = 0x43525052          # "RPRC"
META_START = 0x5254534D          # "MSTR"
META_END = 0x444E454D            # "MEND"
DEV_ID_AM263X = 55
SBL_RESERVED = (0x70002000, 0x70040000)   # soc/am263x/bootloader_soc.c gResMemSection
QSPI_XIP = (0x60000000, 0x68000000)       # EXT_FLASH0/1 up to GPMC0 (am263x cslr_soc_baseaddress.h)
SHF_ALLOC, SHT_NOBITS, PT_LOAD = 0x2, 8, 1


class ImageError(Exception):
    pass


def read_elf(path):
    """(entry, sections, segments): sections as (name, type, flags, addr, size, bytes)."""
    with open(path, "rb") as f:
        b = f.read()
    if b[:4] != b"\x7fELF" or b[4] != 1 or b[5] != 1:
        raise ImageError(f"{path}: not a 32-bit little-endian ELF")
    (e_type, e_machine, _, entry, phoff, shoff, _, _, phentsize, phnum, shentsize, shnum,
     shstrndx) = struct.unpack_from("<HHIIIIIHHHHHH", b, 16)
    if e_machine != 40 or e_type != 2:
        raise ImageError(f"{path}: not an ARM executable (e_machine {e_machine}, e_type {e_type})")
    shdrs = [struct.unpack_from("<IIIIIIIIII", b, shoff + k * shentsize) for k in range(shnum)]
    stroff = shdrs[shstrndx][4]

    def name(off):
        return b[stroff + off:b.index(b"\0", stroff + off)].decode()

    sections = []
    for (nm, typ, flags, addr, off, size, *_rest) in shdrs:
        data = b[off:off + size] if typ != SHT_NOBITS else b""
        sections.append((name(nm), typ, flags, addr, size, data))
    segments = []
    for k in range(phnum):
        typ, off, vaddr, paddr, filesz, memsz, flags, _ = struct.unpack_from("<IIIIIIII", b, phoff + k * phentsize)
        if typ == PT_LOAD:
            segments.append((vaddr, paddr, filesz, memsz))
    return entry, sections, segments


def loadable(sections):
    """The sections TI's converter writes: allocated, with contents, by address."""
    keep = [s for s in sections if (s[2] & SHF_ALLOC) and not (s[1] & SHT_NOBITS) and s[4] > 0]
    return sorted(keep, key=lambda s: s[3])


def check(sections, segments, allow_load_image=False):
    errors = []
    for nm, _, _, addr, size, _ in sections:
        if addr % 8 or size % 8:
            errors.append(f"{nm} at 0x{addr:08x}, {size} B: not 8-byte aligned in address and size (RPRC wants it)")
        if addr < SBL_RESERVED[1] and addr + size > SBL_RESERVED[0]:   # the SBL checks the start only
            errors.append(f"{nm} at 0x{addr:08x}: overlaps the SBL's memory 0x{SBL_RESERVED[0]:08x}..0x{SBL_RESERVED[1]:08x}")
        if QSPI_XIP[0] <= addr < QSPI_XIP[1]:
            errors.append(f"{nm} at 0x{addr:08x}: in the QSPI flash window (XIP), which the SBL does not load")
    if not allow_load_image:
        for vaddr, paddr, filesz, _ in segments:
            if filesz and vaddr != paddr:
                errors.append(f"segment run at 0x{vaddr:08x} loads from 0x{paddr:08x} ({filesz} B): the boot image "
                              f"holds it at its run address only, a startup copy from 0x{paddr:08x} would copy "
                              f"bytes the SBL never wrote (link it at its run address, no AT>)")
    if errors:
        raise ImageError("\n".join(errors))


def rprc(entry, sections):
    out = bytearray(struct.pack("<5I", RPRC_MAGIC, entry, 0, len(sections), 1))
    for _, _, _, addr, size, data in sections:
        out += struct.pack("<5I", addr, 0, size, 0, 0) + data
    return bytes(out)


def multicore(images, dev_id=DEV_ID_AM263X):
    """images: [(core_id, rprc bytes)]."""
    off = 16 + 8 * len(images) + 8
    head = bytearray(struct.pack("<4I", META_START, len(images), dev_id, 0))
    for core, img in images:
        head += struct.pack("<2I", core, off)
        off += len(img)
    head += struct.pack("<2I", 0, META_END)
    return bytes(head) + b"".join(img for _, img in images)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("elf")
    ap.add_argument("--rprc")
    ap.add_argument("--out")
    ap.add_argument("--core-id", type=int, default=0, help="RPRC core id (r5fss0-0 = 0)")
    ap.add_argument("--dev-id", type=int, default=DEV_ID_AM263X)
    ap.add_argument("--allow-load-image", action="store_true",
                    help="write the image even if a segment loads from elsewhere (as TI's converter would)")
    a = ap.parse_args(argv)
    try:
        entry, sections, segments = read_elf(a.elf)
        secs = loadable(sections)
        check(secs, segments, a.allow_load_image)
    except ImageError as e:
        print(f"mc_bootimage: {a.elf}:\n{e}", file=sys.stderr)
        return 1
    r = rprc(entry, secs)
    if a.rprc:
        with open(a.rprc, "wb") as f:
            f.write(r)
    if a.out:
        with open(a.out, "wb") as f:
            f.write(multicore([(a.core_id, r)], a.dev_id))
    print(f"mc_bootimage: {len(secs)} sections, entry 0x{entry:08x}, RPRC {len(r)} B"
          + "".join(f"\n   {s[0]:<12} 0x{s[3]:08x} {s[4]:>7} B" for s in secs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
