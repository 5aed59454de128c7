"""`Drive`, a canopen RemoteNode with the drive's objects (docs/can.md, the object-dictionary
contract): parameters 0x2000 + id by their dotted names, telemetry 0x2200 + channel, the CiA 402
state machine, store / restore, and the scope 0x2300..0x2308; SDO aborts, states and values in
words."""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass

from mctools.mctune.bus import (
    DEFAULT_TIMEOUT_S, NMT_COMMANDS, NMT_STATES, HeartbeatWatch, close_network, open_network,
)
from mctools.mctune.eds import (
    INT_RANGES, OCTET_STRING, TELEM_BASE, UNSIGNED32, Eds, Entry, check_range, parse_value,
    unit_suffix,
)
from mctools.mctune.errors import CommError, InputError, MctuneError

SAVE_SIGNATURE = 0x65766173   # "save", 0x1010 sub 1 (CiA 301 7.5.2.13)
# 0x1010/0x1011 answer after the flash erase: on the LP-AM263's S25FL128S a 64 KiB sector takes
# ~130 ms typically and several times that at worst (hal/am263x/nvm.c waits up to ~2 s)
STORE_TIMEOUT_S = 5.0
LOAD_SIGNATURE = 0x64616F6C   # "load", 0x1011 sub 1 (7.5.2.14)


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
# CiA 402

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


def state_402(sw: int) -> str:
    for mask, value, name in _STATE_MASKS:
        if sw & mask == value:
            return name
    return f"unknown (statusword 0x{sw:04X})"


def describe_statusword(sw: int) -> str:
    flags = [name for bit, name in _STATUS_BITS if sw & (1 << bit)]
    return f"{state_402(sw)} (statusword 0x{sw:04X}{': ' + ', '.join(flags) if flags else ''})"


# ---------------------------------------------------------------------------------------------
# Values for people

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

    def _store_write(self, index: int, signature: int, what: str) -> None:
        sdo = self.node.sdo
        sdo.RESPONSE_TIMEOUT = max(self.timeout, STORE_TIMEOUT_S)
        try:
            self.write_obj(index, 1, signature, what)
        finally:
            sdo.RESPONSE_TIMEOUT = self.timeout

    def save(self) -> int | None:
        self._store_write(0x1010, SAVE_SIGNATURE, "save: ")
        return self._store_status()

    def restore(self) -> int | None:
        self._store_write(0x1011, LOAD_SIGNATURE, "restore: ")
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
