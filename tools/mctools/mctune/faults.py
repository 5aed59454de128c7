"""The drive's faults by name: tools/mctools/data/faults.json, generated with the EDS from the
firmware's fault table (mc/faults.h) by scripts/gen_docs.py."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path


def default_faults_path() -> Path:
    return Path(str(resources.files("mctools").joinpath("data", "faults.json")))


def load_faults(path: Path | None = None) -> dict[int, dict]:
    """bit -> the fault table's row (name, emcy, error_register, reaction, recoverable, doc)."""
    rows = json.loads((path or default_faults_path()).read_text())["faults"]
    return {int(r["bit"]): r for r in rows}


def fault_names(word: int, faults: dict[int, dict] | None = None) -> list[str]:
    """The names of the bits of a fault word (telem.faults, an EMCY's bytes 4..7), in bit order;
    a bit the table does not have as bit<N>."""
    faults = load_faults() if faults is None else faults
    return [faults[b]["name"] if b in faults else f"bit{b}" for b in range(32) if word >> b & 1]


def emcy_fault(code: int, data: bytes, faults: dict[int, dict] | None = None) -> str | None:
    """The drive fault an EMCY reports (docs/can.md: its manufacturer bytes are the fault's bit and
    the fault word), or None for the device's own EMCYs (parameters lost, a store, an RPDO, a
    refused parameter set) and the error reset. A refused parameter set's 0x6320 (bytes: the error
    kind, the parameter id) cannot always be told from the config fault's (the same code): it is
    named config when its bytes read as that fault's bit and a word with it."""
    faults = load_faults() if faults is None else faults
    if len(data) < 5:
        return None
    bit, word = data[0], int.from_bytes(bytes(data[1:5]), "little")
    row = faults.get(bit)
    if row is None or int(row["emcy"]) != code or not word >> bit & 1:
        return None
    others = [n for n in fault_names(word, faults) if n != row["name"]]
    return row["name"] + (f" (latched with {', '.join(others)})" if others else "")
