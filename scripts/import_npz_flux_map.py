#!/usr/bin/env python3
"""Convert a motulator-style flux map (.npz with complex arrays i_s_dq, psi_s_dq) to a preset map CSV.

Used once for presets/baldor-5p6kw-pmsyrm.csv (docs/machine-models.md "Measured flux maps"):
  python3 scripts/import_npz_flux_map.py baldor_400rpm_map.npz presets/baldor-5p6kw-pmsyrm.csv \
      --comment "source: ..."
Stdlib only (the .npy format is read directly). The arrays hold peak-value rotor-frame space vectors
i = i_d + j i_q [A], psi = psi_d + j psi_q [Vs]. --rotate-syrm converts a map with the magnets on -q
(SyRM convention: d = high-permeance axis) to ours (PM on +d): i_d' = -i_q, i_q' = i_d,
psi_d' = -psi_q, psi_q' = psi_d (a rotation of the frame by -90 degrees). The map is checked by
`mctools preset` / mcsim when a preset loads it, not here.
"""
from __future__ import annotations

import argparse
import ast
import struct
import zipfile


def read_npy_complex(blob: bytes) -> list[list[complex]]:
    if blob[:6] != b"\x93NUMPY":
        raise ValueError("not a .npy array")
    major = blob[6]
    hl_size = 2 if major == 1 else 4
    hl = int.from_bytes(blob[8:8 + hl_size], "little")
    header = ast.literal_eval(blob[8 + hl_size:8 + hl_size + hl].decode("latin1"))
    if header["descr"] != "<c16" or len(header["shape"]) != 2:
        raise ValueError(f"expected a 2-D complex128 array, got {header}")
    rows, cols = header["shape"]
    data = blob[8 + hl_size + hl:]
    vals = [complex(*struct.unpack_from("<dd", data, 16 * k)) for k in range(rows * cols)]
    if header["fortran_order"]:
        return [[vals[r + c * rows] for c in range(cols)] for r in range(rows)]
    return [[vals[r * cols + c] for c in range(cols)] for r in range(rows)]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("npz")
    ap.add_argument("csv")
    ap.add_argument("--rotate-syrm", action="store_true", help="magnets on -q in the input: rotate to PM on +d")
    ap.add_argument("--comment", action="append", default=[], help="a '#' line at the top (repeatable)")
    a = ap.parse_args()
    z = zipfile.ZipFile(a.npz)
    cur = read_npy_complex(z.read("i_s_dq.npy"))
    psi = read_npy_complex(z.read("psi_s_dq.npy"))
    with open(a.csv, "w", encoding="ascii") as f:
        for c in a.comment:
            f.write(f"# {c}\n")
        f.write("i_d_A,i_q_A,psi_d_Vs,psi_q_Vs\n")
        for row_i, row_p in zip(cur, psi):
            for i, p in zip(row_i, row_p):
                if a.rotate_syrm:
                    i, p = complex(-i.imag, i.real), complex(-p.imag, p.real)
                # -0.0 from the source prints as 0 (same grid point)
                f.write(f"{i.real + 0.0!r},{i.imag + 0.0!r},{p.real!r},{p.imag!r}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
