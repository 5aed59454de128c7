"""The drive's EDS for `mctune`: its objects through the canopen library plus the keys the
firmware's generator adds and canopen ignores (Unit, Description, Choices, Access; limits in float
for REAL32), lookup by name or index, and values parsed and range-checked against an entry."""

from __future__ import annotations

import configparser
import difflib
import fnmatch
import math
import struct
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from mctools.mctune.errors import InputError

PARAM_BASE, PARAM_END = 0x2000, 0x21FF
TELEM_BASE, TELEM_END = 0x2200, 0x22FF


def default_eds_path() -> Path:
    return Path(str(resources.files("mctools").joinpath("data", "drive.eds")))


def f32(x: float) -> float:
    """x rounded to float32, as the drive stores it."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


# CiA 301 data types (Table 44)
BOOLEAN, INTEGER8, INTEGER16, INTEGER32, UNSIGNED8, UNSIGNED16, UNSIGNED32, REAL32 = 1, 2, 3, 4, 5, 6, 7, 8
VISIBLE_STRING, OCTET_STRING, DOMAIN = 9, 10, 0x0F
INT_RANGES = {BOOLEAN: (0, 1), INTEGER8: (-2**7, 2**7 - 1), INTEGER16: (-2**15, 2**15 - 1),
              INTEGER32: (-2**31, 2**31 - 1), UNSIGNED8: (0, 2**8 - 1), UNSIGNED16: (0, 2**16 - 1),
              UNSIGNED32: (0, 2**32 - 1), 0x15: (-2**63, 2**63 - 1), 0x1B: (0, 2**64 - 1)}
TYPE_NAMES = {BOOLEAN: "BOOLEAN", INTEGER8: "INTEGER8", INTEGER16: "INTEGER16", INTEGER32: "INTEGER32",
              UNSIGNED8: "UNSIGNED8", UNSIGNED16: "UNSIGNED16", UNSIGNED32: "UNSIGNED32",
              REAL32: "REAL32", VISIBLE_STRING: "VISIBLE_STRING", DOMAIN: "DOMAIN",
              0x15: "INTEGER64", 0x1B: "UNSIGNED64"}   # every INT_RANGES type: check_range names it


@dataclass
class Entry:
    """One object (index, sub) of the EDS with the drive's extra keys."""
    index: int
    sub: int
    name: str           # ParameterName (of the sub-index for a record member)
    parent: str         # the object's name for a record member, else ""
    var: object         # canopen ODVariable
    data_type: int
    access_type: str    # ro, rw, rww, rwr, wo, const
    unit: str = ""
    description: str = ""
    low: float | int | None = None
    high: float | int | None = None
    default: object = None
    choices: list[str] = field(default_factory=list)
    access: str = ""    # INIT | STANDSTILL | RUNTIME (parameters)

    @property
    def key(self) -> str:
        return f"0x{self.index:04X}" + (f":{self.sub}" if self.parent else "")

    @property
    def label(self) -> str:
        """How the tool names it: the dotted name of a parameter / telemetry channel, else the
        index with the EDS name."""
        if self.is_param or self.is_telem:
            return self.name
        return f"{self.key} {self.parent + ' / ' if self.parent else ''}{self.name}"

    @property
    def ref(self) -> str:
        """The label with the index where the label does not carry it."""
        return f"{self.name} ({self.key})" if self.is_param or self.is_telem else self.label

    @property
    def is_param(self) -> bool:
        return PARAM_BASE <= self.index <= PARAM_END and not self.parent

    @property
    def is_telem(self) -> bool:
        return TELEM_BASE <= self.index <= TELEM_END and not self.parent

    @property
    def is_bool(self) -> bool:
        """BOOLEAN, or a parameter the EDS carries as INTEGER32 0..1 without choices or unit
        (the contract maps BOOL parameters to INTEGER32 and names no type key)."""
        if self.data_type == BOOLEAN:
            return True
        return (self.is_param and self.data_type in INT_RANGES and not self.choices and not self.unit
                and self.low == 0 and self.high == 1)

    @property
    def is_float(self) -> bool:
        return self.data_type == REAL32 or self.data_type == 0x11

    @property
    def readable(self) -> bool:
        return "r" in self.access_type or self.access_type == "const"

    @property
    def writable(self) -> bool:
        return "w" in self.access_type

    def range_text(self) -> str:
        if self.choices:
            return "|".join(self.choices)
        if self.is_bool:
            return "false|true"
        if self.low is None and self.high is None:
            return ""
        return f"{fmt_num(self.low) if self.low is not None else ''} .. " \
               f"{fmt_num(self.high) if self.high is not None else ''}"


def unit_suffix(unit: str) -> str:
    """" Hz" for a value's unit; nothing for none or the dimensionless "1"."""
    return f" {unit}" if unit and unit != "1" else ""


def fmt_num(v) -> str:
    if isinstance(v, float):
        if math.isfinite(v) and v == int(v) and abs(v) < 1e15:
            return str(int(v))
        return f"{v:.7g}"
    return str(v)


class Eds:
    """The EDS through the canopen library, plus the keys it ignores (Unit, Description,
    Choices, Access) and limits in float for REAL32 objects."""

    def __init__(self, path, node_id: int = 1):
        import canopen

        self.path = Path(path)
        if not self.path.is_file():
            hint = (" (the firmware build generates it: scripts/gen_docs.py writes "
                    "tools/mctools/data/drive.eds; or pass --eds FILE)"
                    if self.path == default_eds_path() else "")
            raise InputError(f"EDS {self.path}: no such file{hint}")
        raw = configparser.RawConfigParser(inline_comment_prefixes=(";",), strict=False)
        raw.optionxform = str
        try:
            with open(self.path, encoding="utf-8", errors="replace") as f:
                raw.read_file(f)
            self.od = canopen.import_od(str(self.path), node_id)
        except (configparser.Error, ValueError, KeyError) as exc:
            raise InputError(f"EDS {self.path}: cannot read it: {exc}") from None
        self.entries: list[Entry] = []
        self._by_key: dict[tuple[int, int], Entry] = {}
        self._by_name: dict[str, Entry] = {}
        for obj in self.od.values():
            subs = [obj] if not hasattr(obj, "subindices") else list(obj.subindices.values())
            for var in subs:
                parent = obj.name if hasattr(obj, "subindices") else ""
                section = f"{var.index:04X}sub{var.subindex:X}" if parent else f"{var.index:04X}"
                sec = raw[section] if raw.has_section(section) else {}
                e = Entry(index=var.index, sub=var.subindex, name=var.name, parent=parent, var=var,
                          data_type=var.data_type or 0, access_type=(var.access_type or "rw").lower(),
                          unit=sec.get("Unit", "") or "", description=sec.get("Description", "") or "",
                          default=var.default, access=(sec.get("Access", "") or "").upper())
                ch = sec.get("Choices", "") or ""
                e.choices = [c.strip() for c in ch.split("|")]
                while e.choices and not e.choices[-1]:
                    e.choices.pop()   # "encoder|unop|": a trailing bar is ignored
                e.low = _limit(sec.get("LowLimit"), e.data_type)
                e.high = _limit(sec.get("HighLimit"), e.data_type)
                self.entries.append(e)
                self._by_key[(e.index, e.sub)] = e
                if not parent:
                    self._by_name.setdefault(e.name, e)
        self.entries.sort(key=lambda e: (e.index, e.sub))
        self._by_lower = {}
        for name, e in self._by_name.items():
            self._by_lower.setdefault(name.lower(), e)

    # lookups
    def params(self) -> list[Entry]:
        return [e for e in self.entries if e.is_param]

    def telemetry(self) -> list[Entry]:
        return [e for e in self.entries if e.is_telem]

    def get(self, index: int, sub: int = 0) -> Entry | None:
        return self._by_key.get((index, sub))

    def subs(self, index: int) -> list[Entry]:
        return [e for e in self.entries if e.index == index]

    @property
    def table_hash(self) -> int | None:
        e = self.get(0x2FF0)
        return e.default if e is not None and isinstance(e.default, int) else None

    def resolve(self, key: str) -> list[Entry]:
        """NAME (a dotted parameter or telem.* name, or any object name), 0xIIII (every
        sub-index of a record) or 0xIIII:SS (SS decimal or 0x hex)."""
        k = key.strip()
        if k.lower().startswith("0x"):
            idx_text, _, sub_text = k.partition(":")
            try:
                index = int(idx_text, 16)
                sub = int(sub_text, 0) if sub_text else None
            except ValueError:
                raise InputError(f"{key!r}: expected 0xIIII or 0xIIII:SS") from None
            if sub is None:
                return self.subs(index) or [self._unknown(index, 0)]
            e = self.get(index, sub)
            return [e if e is not None else self._unknown(index, sub)]
        e = self._by_name.get(k) or self._by_lower.get(k.lower())
        if e is None and not k.startswith("telem."):
            e = self._by_name.get("telem." + k)
        if e is None:
            names = list(self._by_name)
            close = difflib.get_close_matches(k, names, n=4, cutoff=0.6)
            close += [n for n in names if k.lower() in n.lower() and n not in close][:4]
            hint = f"; did you mean {', '.join(close[:5])}?" if close else \
                "; `mctune list` shows the parameters"
            raise InputError(f"{key!r}: no such parameter or object in the EDS {self.path.name}{hint}")
        return [e]

    def _unknown(self, index: int, sub: int) -> Entry:
        """An object the EDS does not describe: read and written as raw bytes."""
        return Entry(index=index, sub=sub, name="(not in the EDS)", parent="", var=None,
                     data_type=OCTET_STRING, access_type="rw")


def _limit(text, data_type):
    if text is None or str(text).strip() == "":
        return None
    t = str(text).strip()
    try:
        if data_type in (REAL32, 0x11):
            return float(t)
        v = int(t, 0)
        if data_type in (INTEGER8, INTEGER16, INTEGER32) and t.lower().startswith("0x"):
            bits = {INTEGER8: 8, INTEGER16: 16, INTEGER32: 32}[data_type]
            if v >= 1 << (bits - 1):
                v -= 1 << bits
        return v
    except ValueError:
        try:
            return float(t)
        except ValueError:
            return None


def match_pattern(name: str, pattern: str | None) -> bool:
    """A glob (with * ? [) or else a case-insensitive substring."""
    if not pattern:
        return True
    names = (name.lower(), name.lower().removeprefix("telem."))
    if any(c in pattern for c in "*?["):
        return any(fnmatch.fnmatchcase(n, pattern.lower()) for n in names)
    return pattern.lower() in names[0]


# ---------------------------------------------------------------------------------------------
# Values: parse and check against an entry (format_value, which decodes the drive's CiA 402
# objects, is in mctools.mctune.drive)

_TRUE = {"true", "1", "on", "yes"}
_FALSE = {"false", "0", "off", "no"}


def parse_value(e: Entry, text: str):
    """The value `text` means for entry e (raw: an ENUM's position, a BOOL as 0/1)."""
    t = text.strip()
    if e.choices:
        low = [c.lower() for c in e.choices]
        if t.lower() in low:
            return low.index(t.lower())
        try:
            return int(t, 0)
        except ValueError:
            raise InputError(f"{text!r} is not one of the choices {'|'.join(e.choices)} "
                             f"(or their positions 0..{len(e.choices) - 1})") from None
    if e.is_bool:
        if t.lower() in _TRUE:
            return 1
        if t.lower() in _FALSE:
            return 0
        raise InputError(f"{text!r} is not a boolean (true/false, 1/0, on/off)")
    if e.is_float:
        try:
            v = float(t)
        except ValueError:
            raise InputError(f"{text!r} is not a number") from None
        if not math.isfinite(v):
            raise InputError(f"{text!r} is not a finite number")
        return v
    if e.data_type in INT_RANGES:
        if t.lower() in _TRUE | _FALSE and not t.isdigit():
            return 1 if t.lower() in _TRUE else 0
        try:
            return int(t, 0)
        except ValueError:
            pass
        try:
            v = float(t)
        except ValueError:
            raise InputError(f"{text!r} is not an integer") from None
        if not math.isfinite(v) or v != int(v):
            raise InputError(f"{text!r} is not an integer ({TYPE_NAMES[e.data_type]})")
        return int(v)
    if e.data_type == VISIBLE_STRING:
        return t
    if e.data_type == OCTET_STRING:  # an object the EDS does not know: an integer or hex bytes
        try:
            return int(t, 0).to_bytes(4, "little", signed=t.startswith("-"))
        except (ValueError, OverflowError):
            pass
        try:
            return bytes.fromhex(t)
        except ValueError:
            raise InputError(f"{e.ref} is not in the EDS: give a 32-bit integer or raw bytes as hex ('e8 03')") from None
    raise InputError(f"{e.ref}: cannot write a {TYPE_NAMES.get(e.data_type, hex(e.data_type))}")


def check_range(e: Entry, value, text: str, cmd: str) -> None:
    """Refuse a value outside the data type or the EDS's LowLimit / HighLimit (before any
    write), naming the key, the value and the range."""
    if isinstance(value, (bytes, str)):
        return
    unit = unit_suffix(e.unit)
    if e.data_type in INT_RANGES:
        lo_t, hi_t = INT_RANGES[e.data_type]
        if not lo_t <= value <= hi_t:
            raise InputError(f"{cmd}: {value} does not fit {e.ref} "
                             f"({TYPE_NAMES[e.data_type]}: {lo_t} .. {hi_t})")
    lo, hi = e.low, e.high
    if lo is None and hi is None:
        return
    v = f32(value) if e.is_float else value
    if e.is_float:
        lo = f32(lo) if lo is not None else None
        hi = f32(hi) if hi is not None else None
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        if e.choices:
            rng = f"positions 0..{len(e.choices) - 1} ({'|'.join(e.choices)})"
        else:
            rng = f"{fmt_num(lo) if lo is not None else '-inf'} .. {fmt_num(hi) if hi is not None else 'inf'}{unit}"
        raise InputError(f"{cmd}: out of range: {e.ref} must be within {rng} "
                         f"(EDS LowLimit/HighLimit), got {fmt_num(value)}{unit}")
