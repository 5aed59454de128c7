"""scripts/mc_bootimage.py, the AM263x boot image writer, on hand-made ELF files: the bytes it
writes against the layout TI documents (mcupsdk-core tools_boot.md, bootloader_priv.h: RPRC
file header 5 x u32, section header 5 x u32, multicore meta header MSTR/count/dev/rsvd, core
entries, rsvd/MEND), which sections it takes (allocated with contents, by address: elf2rprc.js),
and the ELF files it refuses (a load image at another address, misalignment, the SBL's memory)."""
import importlib.util
import pathlib
import struct

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("mc_bootimage", ROOT / "scripts" / "mc_bootimage.py")
mcb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mcb)

SHT_PROGBITS, SHT_NOBITS, SHT_STRTAB = 1, 8, 3
A, AX, WA = 0x2, 0x6, 0x3


def make_elf(path, sections, segments, entry=0):
    """sections: [(name, type, flags, addr, bytes or size)]; segments: [(vaddr, paddr, filesz, memsz)]."""
    names = b"\0" + b"".join(s[0].encode() + b"\0" for s in sections) + b".shstrtab\0"
    phoff = 52
    off = phoff + 32 * len(segments)
    body, shdrs, name_off = b"", [struct.pack("<10I", *([0] * 10))], 1
    for name, typ, flags, addr, data in sections:
        size = data if typ == SHT_NOBITS else len(data)
        shdrs.append(struct.pack("<10I", name_off, typ, flags, addr, off + len(body), size, 0, 0, 4, 0))
        if typ != SHT_NOBITS:
            body += data
        name_off += len(name) + 1
    shdrs.append(struct.pack("<10I", name_off, SHT_STRTAB, 0, 0, off + len(body), len(names), 0, 0, 1, 0))
    body += names
    shoff = off + len(body)
    hdr = b"\x7fELF" + bytes([1, 1, 1]) + bytes(9)
    hdr += struct.pack("<HHIIIIIHHHHHH", 2, 40, 1, entry, phoff, shoff, 0, 52, 32, len(segments), 40, len(shdrs),
                       len(shdrs) - 1)
    ph = b"".join(struct.pack("<8I", 1, 0, v, p, fs, ms, 7, 8) for v, p, fs, ms in segments)
    path.write_bytes(hdr + ph + body + b"".join(shdrs))
    return str(path)


VEC = bytes(range(16))
TEXT = bytes(range(100, 132))
DATA = b"\x11\x22\x33\x44\x55\x66\x77\x88"


def good_elf(tmp_path):
    return make_elf(tmp_path / "a.elf",
                    [(".vectors", SHT_PROGBITS, AX, 0x0, VEC),
                     (".text", SHT_PROGBITS, AX, 0x70080000, TEXT),
                     (".data", SHT_PROGBITS, WA, 0x80000, DATA),
                     (".bss", SHT_NOBITS, WA, 0x80008, 64),
                     (".comment", SHT_PROGBITS, 0, 0, b"gcc\0")],
                    [(0, 0, 16, 16), (0x70080000, 0x70080000, 32, 32), (0x80000, 0x80000, 8, 72)])


def test_the_bytes_follow_tis_documented_layout(tmp_path):
    elf = good_elf(tmp_path)
    out, rprc = tmp_path / "a.appimage", tmp_path / "a.rprc"
    assert mcb.main([elf, "--out", str(out), "--rprc", str(rprc)]) == 0
    r = rprc.read_bytes()
    # RPRC header: "RPRC", entry, rsvd, 3 sections (no .bss, no .comment), version 1
    assert r[:4] == b"RPRC"
    assert struct.unpack_from("<5I", r, 0)[1:] == (0, 0, 3, 1)
    p, got = 20, []
    for _ in range(3):
        addr, rsvd, size, crc, rsvd2 = struct.unpack_from("<5I", r, p)
        assert (rsvd, crc, rsvd2) == (0, 0, 0)
        got.append((addr, r[p + 20:p + 20 + size]))
        p += 20 + size
    assert p == len(r)
    assert got == [(0x0, VEC), (0x80000, DATA), (0x70080000, TEXT)]   # by address
    m = out.read_bytes()
    assert m[:4] == b"MSTR" and struct.unpack_from("<3I", m, 4) == (1, 55, 0)
    assert struct.unpack_from("<2I", m, 16) == (0, 32)                # core 0 at offset 32
    assert struct.unpack_from("<I", m, 24)[0] == 0 and m[28:32] == b"MEND"
    assert m[32:] == r


def test_two_cores_get_consecutive_offsets():
    img = mcb.multicore([(0, b"RPRC" + bytes(16)), (1, b"RPRC" + bytes(36))])
    assert struct.unpack_from("<4I", img, 16) == (0, 40, 1, 60)
    assert len(img) == 40 + 20 + 40


def test_a_load_image_at_another_address_is_refused(tmp_path):
    # .data run in BTCM, loaded from MSRAM (the AT> layout of issue 29): the SBL writes it at
    # 0x80000 only, so a startup copy from 0x70080020 would read what nobody wrote
    elf = make_elf(tmp_path / "b.elf",
                   [(".vectors", SHT_PROGBITS, AX, 0x0, VEC),
                    (".text", SHT_PROGBITS, AX, 0x70080000, TEXT),
                    (".data", SHT_PROGBITS, WA, 0x80000, DATA)],
                   [(0, 0, 16, 16), (0x70080000, 0x70080000, 32, 32), (0x80000, 0x70080020, 8, 8)])
    with pytest.raises(mcb.ImageError, match="loads from 0x70080020"):
        entry, secs, segs = mcb.read_elf(elf)
        mcb.check(mcb.loadable(secs), segs)
    assert mcb.main([elf, "--out", str(tmp_path / "b.appimage")]) == 1
    assert not (tmp_path / "b.appimage").exists()
    # what TI's converter would write anyway
    assert mcb.main([elf, "--out", str(tmp_path / "b.appimage"), "--allow-load-image"]) == 0


@pytest.mark.parametrize("addr,data,why", [
    (0x70080004, TEXT, "8-byte aligned"),
    (0x70080000, TEXT[:12], "8-byte aligned"),
    (0x70010000, TEXT, "SBL's memory"),
    (0x60100000, TEXT, "QSPI flash window"),
])
def test_sections_the_sbl_cannot_load_are_refused(tmp_path, addr, data, why):
    elf = make_elf(tmp_path / "c.elf", [(".text", SHT_PROGBITS, AX, addr, data)], [(addr, addr, len(data), len(data))])
    entry, secs, segs = mcb.read_elf(elf)
    with pytest.raises(mcb.ImageError, match=why):
        mcb.check(mcb.loadable(secs), segs)
