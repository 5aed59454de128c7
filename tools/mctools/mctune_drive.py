"""The drive on the CAN bus for `mctune`: the bus, the EDS and its extra keys, and `Drive`, a
canopen RemoteNode with the drive's objects (docs/can.md, the object-dictionary contract):
parameters 0x2000 + id by their dotted names, telemetry 0x2200 + channel, the CiA 402 state
machine, store / restore, and the scope 0x2300..0x2308.

Errors are `MctuneError`s with the exit status the command line gives them: `InputError` (2) for
input the tool or the drive refuses, `CommError` (1) for a bus or a drive that does not answer."""

from __future__ import annotations

import configparser
import difflib
import fnmatch
import json
import logging
import math
import socket
import struct
import threading
import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

EXIT_COMM = 1
EXIT_INPUT = 2

DEFAULT_BUS = "socketcand:127.0.0.1:29536/can0"
DEFAULT_TIMEOUT_S = 1.0

SAVE_SIGNATURE = 0x65766173   # "save", 0x1010 sub 1 (CiA 301 7.5.2.13)
LOAD_SIGNATURE = 0x64616F6C   # "load", 0x1011 sub 1 (7.5.2.14)

PARAM_BASE, PARAM_END = 0x2000, 0x21FF
TELEM_BASE, TELEM_END = 0x2200, 0x22FF

log = logging.getLogger("mctools.mctune")


class MctuneError(Exception):
    exit_code = EXIT_COMM


class InputError(MctuneError):
    """Input the tool refuses, or the drive refused (SDO abort): exit status 2."""
    exit_code = EXIT_INPUT


class CommError(MctuneError):
    """The bus cannot be opened, the drive does not answer or does not reach a state: 1."""
    exit_code = EXIT_COMM


# ---------------------------------------------------------------------------------------------
# SDO abort codes (CiA 301 7.2.4.3.17), in words

SDO_ABORTS = {
    0x05030000: "toggle bit not alternated",
    0x05040000: "SDO protocol timed out",
    0x05040001: "client/server command specifier not valid or unknown",
    0x05040002: "invalid block size",
    0x05040003: "invalid sequence number",
    0x05040004: "CRC error",
    0x05040005: "out of memory",
    0x06010000: "unsupported access to the object",
    0x06010001: "the object is write-only",
    0x06010002: "the object is read-only",
    0x06020000: "no such object",
    0x06040041: "the object cannot be mapped to a PDO",
    0x06040042: "the mapped objects would exceed the PDO length",
    0x06040043: "general parameter incompatibility",
    0x06040047: "general internal incompatibility in the device",
    0x06060000: "access failed due to a hardware error",
    0x06070010: "data type does not match: length of the value does not match",
    0x06070012: "data type does not match: value too long",
    0x06070013: "data type does not match: value too short",
    0x06090011: "no such sub-index",
    0x06090030: "invalid value (value range exceeded)",
    0x06090031: "value too high",
    0x06090032: "value too low",
    0x06090036: "maximum value is less than minimum value",
    0x060A0023: "resource not available",
    0x08000000: "general error",
    0x08000020: "the data cannot be transferred or stored",
    0x08000021: "the data cannot be transferred or stored because of local control",
    0x08000022: "not in the present device state",
    0x08000023: "no object dictionary present",
    0x08000024: "no data available",
}


def abort_text(code: int) -> str:
    return SDO_ABORTS.get(code, "unknown abort code")


def is_protocol_abort(code: int) -> bool:
    """Aborts of the transfer itself (0x0503xxxx, 0x0504xxxx): a communication problem."""
    return (code >> 16) in (0x0503, 0x0504)


# ---------------------------------------------------------------------------------------------
# NMT and CiA 402

NMT_STATES = {0x00: "INITIALISING (boot-up)", 0x04: "STOPPED", 0x05: "OPERATIONAL",
              0x7F: "PRE-OPERATIONAL"}
NMT_COMMANDS = {"start": (0x01, 0x05), "stop": (0x02, 0x04), "pre-op": (0x80, 0x7F),
                "reset": (0x81, 0x00), "reset-comm": (0x82, 0x00)}

NOT_READY = "NOT READY TO SWITCH ON"
SWITCH_ON_DISABLED = "SWITCH ON DISABLED"
READY = "READY TO SWITCH ON"
SWITCHED_ON = "SWITCHED ON"
ENABLED = "OPERATION ENABLED"
QUICK_STOP = "QUICK STOP ACTIVE"
FAULT_REACTION = "FAULT REACTION ACTIVE"
FAULT = "FAULT"

_STATE_MASKS = ((0x4F, 0x00, NOT_READY), (0x4F, 0x40, SWITCH_ON_DISABLED), (0x6F, 0x21, READY),
                (0x6F, 0x23, SWITCHED_ON), (0x6F, 0x27, ENABLED), (0x6F, 0x07, QUICK_STOP),
                (0x4F, 0x0F, FAULT_REACTION), (0x4F, 0x08, FAULT))
_STATUS_BITS = ((4, "voltage enabled"), (7, "warning"), (9, "remote"), (10, "target reached"),
                (11, "internal limit"), (14, "RUN"), (15, "start-up in progress"))

CW_SHUTDOWN, CW_SWITCH_ON, CW_ENABLE, CW_DISABLE_VOLTAGE, CW_QUICK_STOP, CW_FAULT_RESET = (
    0x06, 0x07, 0x0F, 0x00, 0x02, 0x80)

MODES = {"pv": 3, "tq": 4, "csv": 9, "cst": 10}
MODE_NAMES = {v: k for k, v in MODES.items()}

CONFIG_SOURCES = {0: "the stored set", 1: "nothing stored: defaults", 2: "the older stored copy "
                  "(the newer was corrupt)", 3: "stored set corrupt: defaults", 4: "NVM error: defaults",
                  8: "the stored set of another table version: some values at defaults (0x1003)"}
STORE_STATUS = {0: "ok", 4: "NVM error", 5: "too large for the store", 7: "saved without the flux map"}
ERROR_REGISTER_BITS = ((0, "generic"), (1, "current"), (2, "voltage"), (3, "temperature"),
                       (4, "communication"), (5, "device profile"), (7, "manufacturer"))


# ---------------------------------------------------------------------------------------------
# The drive's faults: tools/mctools/data/faults.json, generated with the EDS from the firmware's
# fault table (mc/faults.h) by scripts/gen_docs.py

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


def state_402(sw: int) -> str:
    for mask, value, name in _STATE_MASKS:
        if sw & mask == value:
            return name
    return f"unknown (statusword 0x{sw:04X})"


def describe_statusword(sw: int) -> str:
    flags = [name for bit, name in _STATUS_BITS if sw & (1 << bit)]
    return f"{state_402(sw)} (statusword 0x{sw:04X}{': ' + ', '.join(flags) if flags else ''})"


# ---------------------------------------------------------------------------------------------
# The bus

def parse_bus_spec(spec: str) -> dict:
    """python-can keyword arguments for SPEC: socketcand:HOST:PORT/CHANNEL, socketcan:CHANNEL,
    virtual:NAME or INTERFACE:CHANNEL, each optionally followed by ,key=value options
    (e.g. pcan:PCAN_USBBUS1,bitrate=500000)."""
    head, *opts = spec.split(",")
    interface, sep, rest = head.partition(":")
    if not sep or not interface or not rest:
        raise InputError(f"bus {spec!r}: expected INTERFACE:CHANNEL (socketcand:HOST:PORT/CHANNEL, "
                         f"socketcan:can0, virtual:NAME)")
    kwargs: dict = {"interface": interface}
    if interface == "socketcand":
        hostport, slash, channel = rest.partition("/")
        host, colon, port = hostport.rpartition(":")
        if not slash or not colon or not host or not channel or not port.isdigit():
            raise InputError(f"bus {spec!r}: expected socketcand:HOST:PORT/CHANNEL, "
                             f"e.g. {DEFAULT_BUS}")
        kwargs.update(host=host.strip("[]"), port=int(port), channel=channel)
    else:
        kwargs["channel"] = rest
    for opt in opts:
        key, eq, value = opt.partition("=")
        if not eq or not key:
            raise InputError(f"bus {spec!r}: option {opt!r} is not key=value")
        try:
            kwargs[key] = int(value, 0)
        except ValueError:
            kwargs[key] = {"true": True, "false": False}.get(value.lower(), value)
    return kwargs


class HeartbeatWatch:
    """A python-can listener remembering the last heartbeat / boot-up (0x700 + id) per node."""

    def __init__(self):
        self.nodes: dict[int, tuple[int, float]] = {}
        self.cond = threading.Condition()
        self.started = time.monotonic()

    def on_message_received(self, msg):
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            return
        if 0x701 <= msg.arbitration_id <= 0x77F and len(msg.data) >= 1:
            with self.cond:
                self.nodes[msg.arbitration_id - 0x700] = (msg.data[0] & 0x7F, time.monotonic())
                self.cond.notify_all()

    def __call__(self, msg):  # can.Listener protocol of some python-can versions
        self.on_message_received(msg)

    def stop(self):
        pass

    def on_error(self, exc):
        pass

    def wait(self, node: int | None, timeout: float) -> bool:
        """Wait until node (None: any node) has been heard, at most timeout s."""
        def heard():
            return (node in self.nodes) if node is not None else bool(self.nodes)

        with self.cond:
            return self.cond.wait_for(heard, timeout)

    def state(self, node: int) -> int | None:
        with self.cond:
            return self.nodes[node][0] if node in self.nodes else None

    def seen(self) -> list[int]:
        with self.cond:
            return sorted(self.nodes)


def open_network(spec: str, timeout: float = DEFAULT_TIMEOUT_S):
    """A connected canopen.Network on SPEC and its HeartbeatWatch."""
    import can
    import canopen

    kwargs = parse_bus_spec(spec)
    if kwargs["interface"] == "socketcand":
        # python-can retries a refused connection for 10 s: find out at once.
        try:
            socket.create_connection((kwargs["host"], kwargs["port"]), timeout=max(timeout, 1.0)).close()
        except OSError as exc:
            raise CommError(f"cannot open bus {spec}: {kwargs['host']}:{kwargs['port']}: "
                            f"{exc.strerror or exc} (is socketcand, or mcsim --can, running there?)") from None
    watch = HeartbeatWatch()
    network = canopen.Network()
    network.NOTIFIER_CYCLE = 0.1   # a quick disconnect (the notifier thread wakes this often)
    network.NOTIFIER_SHUTDOWN_TIMEOUT = 1.0
    network.listeners.append(watch)
    try:
        network.connect(**kwargs)
    except (can.CanError, OSError, ValueError, TypeError, ImportError, NotImplementedError) as exc:
        raise CommError(f"cannot open bus {spec}: {exc}") from None
    return network, watch


def close_network(network) -> None:
    try:
        network.disconnect()
    except Exception as exc:  # noqa: BLE001 - closing must not hide the command's result
        log.debug("disconnect: %s", exc)


# ---------------------------------------------------------------------------------------------
# The EDS

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
              REAL32: "REAL32", VISIBLE_STRING: "VISIBLE_STRING", DOMAIN: "DOMAIN"}


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
# Values: parse, check, format

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


def format_value(e: Entry, v, with_unit: bool = True) -> str:
    """A read value for people: ENUM by choice name, BOOL as true/false, floats with 7
    significant digits, statusword and modes decoded."""
    unit = unit_suffix(e.unit) if with_unit else ""
    if v is None:
        return "-"
    if isinstance(v, (bytes, bytearray)):
        if e.data_type == OCTET_STRING and 1 <= len(v) <= 4:
            n = int.from_bytes(v, "little")
            return f"0x{n:0{2 * len(v)}X} ({n}; raw bytes {v.hex(' ')})"
        return f"{len(v)} bytes" + (f": {bytes(v[:16]).hex(' ')}{' ...' if len(v) > 16 else ''}" if v else "")
    if isinstance(v, str):
        return v
    if e.choices:
        iv = int(v)
        return e.choices[iv] if 0 <= iv < len(e.choices) else f"{iv} (not one of {'|'.join(e.choices)})"
    if e.is_bool:
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.7g}{unit}"
    if not e.parent and e.index in (0x6041,):
        return describe_statusword(int(v))
    if not e.parent and e.index in (0x6060, 0x6061):
        return f"{v} ({MODE_NAMES[v]})" if v in MODE_NAMES else str(v)
    if not e.parent and e.index in (0x6040,):
        return f"0x{int(v):04X}"
    if e.data_type == UNSIGNED32 and not e.unit:
        return f"0x{int(v):08X}"
    return f"{v}{unit}"


# ---------------------------------------------------------------------------------------------
# The drive

class Drive:
    """A drive on the bus: canopen.RemoteNode for node_id with the EDS, the SDO wrapped so
    that aborts and silence become MctuneErrors worded for people."""

    def __init__(self, network, watch: HeartbeatWatch, node_id: int, eds: Eds, bus_spec: str = "",
                 timeout: float = DEFAULT_TIMEOUT_S):
        import canopen

        self.network, self.watch, self.node_id, self.eds = network, watch, node_id, eds
        self.bus_spec = bus_spec
        self.timeout = timeout
        self.node = canopen.RemoteNode(node_id, eds.od, load_od=False)
        self.node.sdo.RESPONSE_TIMEOUT = timeout
        self.node.sdo.MAX_RETRIES = 1
        network.add_node(self.node)

    @classmethod
    def open(cls, bus_spec: str, node_id: int, eds: Eds, timeout: float = DEFAULT_TIMEOUT_S) -> Drive:
        network, watch = open_network(bus_spec, timeout)
        return cls(network, watch, node_id, eds, bus_spec, timeout)

    def close(self) -> None:
        close_network(self.network)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- SDO with the errors in words ---------------------------------------------------------
    def _no_answer(self, what: str) -> CommError:
        if not self.watch.seen():
            self.watch.wait(None, 1.2)   # listen briefly: who is there?
        seen = self.watch.seen()
        bus = self.bus_spec or "the bus"
        if self.node_id in seen:
            st = self.watch.state(self.node_id)
            hint = " (SDO is not served in STOPPED: `mctune nmt pre-op`)" if st == 0x04 else ""
            return CommError(f"{what}node {self.node_id} does not answer SDO on {bus} although its "
                             f"heartbeat says {NMT_STATES.get(st, hex(st))}{hint}")
        if seen:
            hint = f"; wrong --node? try --node {seen[0]}" if len(seen) == 1 else "; wrong --node?"
            return CommError(f"{what}node {self.node_id} does not answer on {bus} (heartbeats seen from "
                             f"nodes {seen}{hint})")
        return CommError(f"{what}node {self.node_id} does not answer on {bus} (heartbeats seen from "
                         f"nodes []: is the drive powered, on this bus, at this bit rate?)")

    def _sdo(self, fn, e: Entry | None, what: str, *args, idempotent: bool = False):
        """One SDO transfer. idempotent (reads): when another SDO client's answer got in the way
        (CiA 301 has one SDO channel per server: a second mctune, a PLC), drop the queued answers
        and try again, at most 3 times; writes are never repeated."""
        from canopen.sdo import SdoAbortedError, SdoCommunicationError

        for attempt in range(4):
            try:
                return self._sdo_once(fn, *args)
            except SdoCommunicationError as exc:
                if not (idempotent and "another SDO client" in str(exc) and attempt < 3):
                    raise self._sdo_error(exc, e, what) from None
                responses = getattr(self.node.sdo, "responses", None)
                time.sleep(0.02)
                while responses is not None and not responses.empty():
                    responses.get_nowait()
            except SdoAbortedError as exc:
                raise self._sdo_error(exc, e, what) from None
            except Exception as exc:  # python-can send errors (bus off, socket closed)
                import can

                if isinstance(exc, (can.CanError, OSError)):
                    raise CommError(f"{what}bus {self.bus_spec}: {exc}") from None
                raise

    @staticmethod
    def _sdo_once(fn, *args):
        return fn(*args)

    def _sdo_error(self, exc, e: Entry | None, what: str) -> Exception:
        from canopen.sdo import SdoAbortedError

        if isinstance(exc, SdoAbortedError):
            return self.abort_error(exc.code, e, what)
        if "No SDO response" in str(exc) or "timeout" in str(exc).lower():
            return self._no_answer(what)
        return CommError(f"{what}SDO transfer failed: {exc}")

    def abort_error(self, code: int, e: Entry | None, what: str) -> MctuneError:
        text = f"{what}refused by the drive: {abort_text(code)} (SDO abort 0x{code:08X})"
        if code == 0x08000022 and e is not None:
            if e.access == "STANDSTILL":
                text += f"; {e.name} is STANDSTILL: disable the outputs first (mctune disable)"
            elif e.access == "INIT":
                text += f"; {e.name} is INIT: set only at initialisation"
            elif e.index in (0x1010, 0x1011):
                text += "; the store is refused while the outputs are on (mctune disable)"
        cls = CommError if is_protocol_abort(code) else InputError
        return cls(text)

    def read(self, e: Entry, what: str = ""):
        data = self._sdo(self.node.sdo.upload, e, what, e.index, e.sub, idempotent=True)
        if e.var is None:
            return bytes(data)
        try:
            return e.var.decode_raw(data)
        except Exception:  # noqa: BLE001 - a length the EDS does not expect
            return bytes(data)

    def write(self, e: Entry, value, what: str = "") -> None:
        if e.var is None:
            data = value if isinstance(value, (bytes, bytearray)) else bytes(value)
        else:
            if e.data_type in INT_RANGES:
                value = int(value)
            data = e.var.encode_raw(value)
        self._sdo(self.node.sdo.download, e, what, e.index, e.sub, data)

    def entry(self, index: int, sub: int = 0) -> Entry:
        e = self.eds.get(index, sub)
        return e if e is not None else self.eds._unknown(index, sub)

    def read_obj(self, index: int, sub: int = 0, what: str = ""):
        e = self.entry(index, sub)
        v = self.read(e, what)
        if e.var is None and isinstance(v, (bytes, bytearray)) and len(v) <= 4:
            return int.from_bytes(v, "little")
        return v

    def write_obj(self, index: int, sub: int, value, what: str = "") -> None:
        e = self.entry(index, sub)
        if e.var is None:
            value = int(value).to_bytes(4, "little", signed=value < 0)
        self.write(e, value, what)

    # --- parameters ------------------------------------------------------------------------
    def get(self, key: str) -> list[tuple[Entry, object]]:
        return [(e, self.read(e, f"get {key}: ")) for e in self.eds.resolve(key)]

    def set(self, key: str, text: str, force: bool = False):
        """Parse, check against the EDS (unless force), write; returns (entry, old, new)."""
        cmd = f"set {key} {text}"
        found = self.eds.resolve(key)
        if len(found) != 1:
            raise InputError(f"{cmd}: {key} has sub-indices: name one as {key}:SUB")
        e = found[0]
        try:
            value = parse_value(e, text)
        except InputError as exc:
            raise InputError(f"{cmd}: {exc}") from None
        if not force:
            if not e.writable:
                why = " (Access=INIT: set only at initialisation)" if e.access == "INIT" else ""
                raise InputError(f"{cmd}: {e.ref} is read-only{why}")
            check_range(e, value, text, cmd)
        old = None
        if e.readable and e.var is not None:
            try:
                old = self.read(e, f"{cmd}: ")
            except InputError:
                old = None
        self.write(e, value, f"{cmd}: ")
        new = value
        if e.readable and e.var is not None:
            try:
                new = self.read(e, f"{cmd}: ")
            except InputError:
                pass
        return e, old, new

    def table_hashes(self) -> tuple[int | None, int | None]:
        """(the EDS's 0x2FF0 default, the drive's 0x2FF0); the drive's is None if it has none."""
        e = self.entry(0x2FF0)
        try:
            dev = self.read(e, "")
        except InputError:
            dev = None
        if isinstance(dev, (bytes, bytearray)):
            dev = int.from_bytes(dev, "little") if len(dev) == 4 else None
        return self.eds.table_hash, dev

    def eds_warning(self) -> str | None:
        """None if the EDS matches the firmware (or cannot be compared), else a warning."""
        eds_h, dev_h = self.table_hashes()
        if dev_h is None:
            return (f"warning: node {self.node_id} has no parameter-table hash (0x2FF0): is it this "
                    f"drive? Names and ranges come from {self.eds.path} unchecked")
        if eds_h is None:
            return (f"warning: the EDS {self.eds.path} carries no parameter-table hash (0x2FF0 "
                    f"DefaultValue): it cannot be checked against the firmware (0x{dev_h:08X})")
        if eds_h != dev_h:
            return (f"warning: the EDS does not match the drive's firmware: parameter-table hash "
                    f"0x{eds_h:08X} in {self.eds.path}, 0x{dev_h:08X} on node {self.node_id}; names, "
                    f"ranges and units may be wrong. Regenerate the EDS from the firmware the drive "
                    f"runs (build it, then `scripts/gen_docs.py BUILD/sim/app/mcsim` writes "
                    f"tools/mctools/data/drive.eds) or pass --eds FILE")
        return None

    def save(self) -> int | None:
        self.write_obj(0x1010, 1, SAVE_SIGNATURE, "save: ")
        return self._store_status()

    def restore(self) -> int | None:
        self.write_obj(0x1011, 1, LOAD_SIGNATURE, "restore: ")
        return self._store_status()

    def _store_status(self) -> int | None:
        if self.eds.get(0x2FF2) is None:
            return None
        try:
            return int(self.read_obj(0x2FF2))
        except InputError:
            return None

    # --- NMT -------------------------------------------------------------------------------
    def nmt(self, command: str, wait: float = 1.5) -> int | None:
        """Send an NMT command; the state of the next heartbeat, if one comes within wait s."""
        code, expect = NMT_COMMANDS[command]
        with self.watch.cond:
            self.watch.nodes.pop(self.node_id, None)
        self.node.nmt.send_command(code)
        end = time.monotonic() + wait
        while time.monotonic() < end:
            st = self.watch.state(self.node_id)
            if st is not None and (st == expect or (expect == 0x00 and st == 0x7F)):
                return st
            time.sleep(0.01)
        return self.watch.state(self.node_id)

    def nmt_state(self, wait: float) -> int | None:
        self.watch.wait(self.node_id, wait)
        return self.watch.state(self.node_id)

    # --- CiA 402 -----------------------------------------------------------------------------
    def statusword(self, what: str = "") -> int:
        return int(self.read_obj(0x6041, 0, what))

    def controlword(self, cw: int, what: str = "") -> None:
        self.write_obj(0x6040, 0, cw, what)

    def wait_state(self, targets: set[str], timeout: float, what: str = "") -> int:
        """Poll the statusword until its state is one of targets; returns it. Raises on a fault
        (unless FAULT is a target) and on timeout."""
        end = time.monotonic() + timeout
        while True:
            sw = self.statusword(what)
            st = state_402(sw)
            if st in targets:
                return sw
            if st in (FAULT, FAULT_REACTION) and not targets & {FAULT, FAULT_REACTION}:
                raise CommError(f"{what}the drive went to {describe_statusword(sw)}"
                                f"{self._fault_text()}")
            if time.monotonic() >= end:
                raise CommError(f"{what}still in {describe_statusword(sw)} after {timeout:g} s, "
                                f"waiting for {' or '.join(sorted(targets))}")
            time.sleep(0.02)

    def _fault_text(self) -> str:
        try:
            code = int(self.read_obj(0x603F))
        except MctuneError:
            return ""
        return f", error code 0x{code:04X} (0x603F)" if code else ""

    def set_mode(self, mode: str, what: str = "") -> None:
        self.write_obj(0x6060, 0, MODES[mode], what)

    def enable(self, mode: str | None = None, timeout: float = 2.0, report=print) -> int:
        """Mode of operation (0x6060), then shutdown 0x06 -> switch on 0x07 -> enable operation
        0x0F, checking the statusword after each step. Returns the final statusword."""
        what = "enable: "
        if mode:
            self.set_mode(mode, what)
            report(f"mode of operation 0x6060 = {MODES[mode]} ({mode})")
        sw = self.statusword(what)
        st = state_402(sw)
        report(f"state: {describe_statusword(sw)}")
        if st in (FAULT, FAULT_REACTION):
            raise CommError(f"{what}the drive is in {st}{self._fault_text()}: "
                            f"`mctune fault-reset` first")
        if st == ENABLED:
            report("already enabled")
            return sw
        if st == NOT_READY:
            sw = self.wait_state({SWITCH_ON_DISABLED}, timeout, what)
        if st == QUICK_STOP:
            self.controlword(CW_DISABLE_VOLTAGE, what)
            sw = self.wait_state({SWITCH_ON_DISABLED}, timeout, what)
            report(f"controlword 0x00 (disable voltage) -> {describe_statusword(sw)}")
        for cw, name, target in ((CW_SHUTDOWN, "shutdown", READY), (CW_SWITCH_ON, "switch on", SWITCHED_ON),
                                 (CW_ENABLE, "enable operation", ENABLED)):
            self.controlword(cw, what)
            sw = self.wait_state({target}, timeout, f"{what}controlword 0x{cw:02X} ({name}): ")
            report(f"controlword 0x{cw:02X} ({name}) -> {describe_statusword(sw)}")
        return sw

    def disable(self, voltage: bool = False, timeout: float = 2.0, report=print) -> int:
        cw, name, target = ((CW_DISABLE_VOLTAGE, "disable voltage", SWITCH_ON_DISABLED) if voltage
                            else (CW_SHUTDOWN, "shutdown", READY))
        what = "disable: "
        sw = self.statusword(what)
        if state_402(sw) in (FAULT, FAULT_REACTION):
            report(f"state: {describe_statusword(sw)} (outputs off)")
            return sw
        self.controlword(cw, what)
        targets = {target, SWITCH_ON_DISABLED}
        sw = self.wait_state(targets, timeout, f"{what}controlword 0x{cw:02X} ({name}): ")
        report(f"controlword 0x{cw:02X} ({name}) -> {describe_statusword(sw)}")
        return sw

    def fault_reset(self, timeout: float = 2.0, report=print) -> int:
        """Rising edge of controlword bit 7 (0x80), then back to 0x00 (CiA 402)."""
        what = "fault-reset: "
        sw = self.statusword(what)
        st = state_402(sw)
        if st not in (FAULT, FAULT_REACTION):
            report(f"not in FAULT: {describe_statusword(sw)}; nothing to reset")
            return sw
        report(f"state: {describe_statusword(sw)}{self._fault_text()}")
        cw = int(self.read_obj(0x6040, 0, what))
        if cw & 0x80:
            self.controlword(0x00, what)   # bit 7 low first, else there is no rising edge
        self.controlword(CW_FAULT_RESET, what)
        try:
            sw = self.wait_state({SWITCH_ON_DISABLED, NOT_READY}, timeout, what + "controlword 0x80: ")
        finally:
            self.controlword(0x00, what)
        report(f"controlword 0x80 (fault reset), 0x00 -> {describe_statusword(sw)}")
        return sw

    def quick_stop(self, timeout: float = 5.0, report=print) -> int:
        what = "quick-stop: "
        self.controlword(CW_QUICK_STOP, what)
        sw = self.wait_state({QUICK_STOP, SWITCH_ON_DISABLED}, timeout, what)
        report(f"controlword 0x02 (quick stop) -> {describe_statusword(sw)}")
        return sw

    def mode_display(self, what: str = "") -> int:
        return int(self.read_obj(0x6061, 0, what))


# ---------------------------------------------------------------------------------------------
# The scope (0x2300..0x2308)

SCOPE_STATUS = {0: "idle", 1: "armed", 2: "triggered", 3: "done"}
EDGES = {"rising": 0, "falling": 1, "either": 2}


@dataclass
class ScopeChannel:
    id: int
    name: str
    unit: str


@dataclass
class ScopeRecord:
    channels: list[ScopeChannel]
    samples: int
    trigger_index: int
    period: float
    data: list[list[float]]   # per channel

    def times(self) -> list[float]:
        return [(k - self.trigger_index) * self.period for k in range(self.samples)]


def scope_channel(eds: Eds, text: str) -> ScopeChannel:
    """A telemetry channel by name (i_q, telem.i_q) or id (1..)."""
    t = text.strip()
    if t.isdigit():
        ch = int(t)
        e = eds.get(TELEM_BASE + ch)
        if ch < 1 or ch > 0xFF:
            raise InputError(f"scope: channel {ch} out of range (1..)")
        return ScopeChannel(ch, e.name.removeprefix("telem.") if e else f"ch{ch}", e.unit if e else "")
    name = t if t.startswith("telem.") else "telem." + t
    for e in eds.telemetry():
        if e.name == name or e.name.lower() == name.lower():
            return ScopeChannel(e.index - TELEM_BASE, e.name.removeprefix("telem."), e.unit)
    have = ", ".join(e.name.removeprefix("telem.") for e in eds.telemetry())
    raise InputError(f"scope: no telemetry channel {t!r} in the EDS (channels: {have})")


def decode_scope(data: bytes, n_channels: int, samples: int) -> tuple[list[list[float]], str | None]:
    """Little-endian float32, sample-major -> one list per channel; a warning if the length
    does not match samples x channels."""
    n = len(data) // 4
    vals = struct.unpack(f"<{n}f", data[:4 * n])
    warn = None
    if n != samples * n_channels:
        full = n // n_channels
        warn = (f"scope: the record has {n} values, expected {samples} samples x {n_channels} "
                f"channels = {samples * n_channels}; using {min(full, samples)} samples")
        samples = min(full, samples)
    return [[vals[k * n_channels + c] for k in range(samples)] for c in range(n_channels)], warn
