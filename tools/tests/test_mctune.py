"""mctune against a drive emulated on python-can's virtual bus: canopen's own SDO server
(LocalNode with tests/data/fixture.eds, the EDS format the firmware's co-gen writes), heartbeats,
a minimal CiA 402 state machine on controlword writes, a scope that fills its DOMAIN, and TPDOs
sent by the test."""

from __future__ import annotations

import csv
import re
import struct
import threading
import time
import uuid
from pathlib import Path

import pytest

canopen = pytest.importorskip("canopen")
pytest.importorskip("can")

from mctools import mctune  # noqa: E402
from mctools.mctune.bus import parse_bus_spec  # noqa: E402
from mctools.mctune.drive import ENABLED, FAULT, READY, SWITCH_ON_DISABLED, SWITCHED_ON  # noqa: E402
from mctools.mctune.eds import Eds  # noqa: E402
from mctools.mctune.errors import InputError  # noqa: E402

FIXTURE = Path(__file__).parent / "data" / "fixture.eds"
FIXTURE_HASH = 0x1F2E3D4C
NODE = 3

SW = {SWITCH_ON_DISABLED: 0x0250, READY: 0x0231, SWITCHED_ON: 0x0233, ENABLED: 0x4237,
      FAULT: 0x0218, "QUICK STOP ACTIVE": 0x0217}


class EmulatedDrive:
    """The drive as far as mctune sees it."""

    def __init__(self, channel: str, node_id: int = NODE, heartbeat_ms: int = 50):
        self.net = canopen.Network()
        self.net.NOTIFIER_CYCLE = 0.05
        self.net.NOTIFIER_SHUTDOWN_TIMEOUT = 1.0
        self.net.connect(interface="virtual", channel=channel)
        self.node = canopen.LocalNode(node_id, str(FIXTURE))
        self.net.add_node(self.node)
        self.writes: list[tuple[int, int, bytes]] = []
        self.controlwords: list[int] = []
        self.state = SWITCH_ON_DISABLED
        self.scope_polls = 0
        self.refuse: dict[int, tuple] = {}   # index -> (predicate(value bytes), abort code)
        for (idx, sub), v in {
            (0x1000, 0): 0x00020192, (0x1001, 0): 0, (0x1018, 1): 0, (0x1018, 2): 1,
            (0x1018, 3): 0x00020000, (0x1018, 4): 0x1234, (0x2FF1, 0): 0, (0x2FF2, 0): 0,
            (0x603F, 0): 0, (0x6061, 0): 3, (0x6075, 0): 13290, (0x6076, 0): 29700,
            (0x2303, 0): 0, (0x2308, 0): 4096, (0x2304, 0): 0, (0x2305, 0): 0, (0x2306, 0): 0.0,
            (0x6041, 0): SW[self.state],
            (0x2207, 0): 1.25, (0x220A, 0): 3.5, (0x2201, 0): 2.0,
        }.items():
            self.put(idx, sub, v)
        self.node.add_write_callback(self._on_write)
        self.node.add_read_callback(self._on_read)
        self.node.nmt._state = 0x7F   # pre-operational
        self.node.nmt.start_heartbeat(heartbeat_ms)

    def put(self, index, sub, value):
        od = self.node.object_dictionary[index]
        var = od if sub == 0 and not hasattr(od, "subindices") else od[sub]
        self.node.data_store.setdefault(index, {})[sub] = var.encode_raw(value)

    def value(self, index, sub=0):
        od = self.node.object_dictionary[index]
        var = od if sub == 0 and not hasattr(od, "subindices") else od[sub]
        return var.decode_raw(self.node.get_data(index, sub))

    def set_state(self, st):
        self.state = st
        self.node.data_store.setdefault(0x6041, {})[0] = struct.pack("<H", SW[st])

    def _on_write(self, index, subindex, od, data):
        self.writes.append((index, subindex, bytes(data)))
        if index in self.refuse:
            pred, code = self.refuse[index]
            if pred(bytes(data)):
                raise canopen.SdoAbortedError(code)
        if index == 0x6040:
            cw = struct.unpack("<H", bytes(data))[0]
            prev = self.controlwords[-1] if self.controlwords else 0
            self.controlwords.append(cw)
            self._step_402(cw, prev)
        elif index == 0x6060:
            self.put(0x6061, 0, struct.unpack("<b", bytes(data))[0])
        elif index == 0x2302 and data[0] == 1:
            self.scope_polls = 0

    def _step_402(self, cw, prev):
        st = self.state
        if st == FAULT:
            if cw & 0x80 and not prev & 0x80:
                self.set_state(SWITCH_ON_DISABLED)
            return
        if cw & 0x82 == 0x00:
            self.set_state(SWITCH_ON_DISABLED)
        elif cw & 0x86 == 0x02:
            self.set_state("QUICK STOP ACTIVE" if st == ENABLED else SWITCH_ON_DISABLED)
        elif cw & 0x87 == 0x06:
            if st in (SWITCH_ON_DISABLED, SWITCHED_ON, ENABLED):
                self.set_state(READY)
        elif cw & 0x8F == 0x07:
            if st in (READY, ENABLED):
                self.set_state(SWITCHED_ON)
        elif cw & 0x8F == 0x0F:
            if st == SWITCHED_ON:
                self.set_state(ENABLED)

    def _on_read(self, index, subindex, od):
        if index == 0x2303:   # armed, triggered, done on successive polls
            if self.value(0x2302) != 1:
                return 0
            self.scope_polls += 1
            return min(3, self.scope_polls)
        return None

    def send(self, cob_id, data: bytes):
        self.net.send_message(cob_id, data)

    def close(self):
        self.node.nmt.stop_heartbeat()
        self.net.disconnect()


@pytest.fixture
def bus():
    return f"virtual:mctune-{uuid.uuid4().hex[:8]}"


@pytest.fixture
def drive(bus):
    d = EmulatedDrive(bus.split(":", 1)[1])
    time.sleep(0.06)   # a heartbeat on the bus
    yield d
    d.close()


def run(capsys, bus, *args, node=NODE, timeout="0.5"):
    rc = mctune.main(["--bus", bus, "--node", str(node), "--eds", str(FIXTURE), "--timeout", timeout,
                      *args])
    out, err = capsys.readouterr()
    return rc, out, err


# ---------------------------------------------------------------------------------------------

def test_bus_spec_and_eds_extras():
    assert parse_bus_spec("socketcand:127.0.0.1:29536/can0") == dict(
        interface="socketcand", host="127.0.0.1", port=29536, channel="can0")
    assert parse_bus_spec("socketcan:can0") == dict(interface="socketcan", channel="can0")
    assert parse_bus_spec("pcan:PCAN_USBBUS1,bitrate=500000") == dict(
        interface="pcan", channel="PCAN_USBBUS1", bitrate=500000)
    with pytest.raises(InputError, match="HOST:PORT/CHANNEL"):
        parse_bus_spec("socketcand:localhost")
    eds = Eds(FIXTURE)
    e = eds.resolve("control.current_bw_hz")[0]
    assert (e.index, e.unit, e.low, e.high, e.access) == (0x2018, "Hz", 10.0, 5000.0, "RUNTIME")
    assert eds.resolve("control.angle_source")[0].choices == ["encoder", "unop"]   # trailing bar
    assert eds.resolve("control.decouple")[0].is_bool
    assert eds.resolve("i_q")[0].name == "telem.i_q"
    assert eds.table_hash == FIXTURE_HASH
    assert [x.sub for x in eds.resolve("0x1018")] == [0, 1, 2, 3, 4]
    with pytest.raises(InputError, match="current_bw_hz"):
        eds.resolve("control.current_bw")   # a suggestion


def test_list_no_read_needs_no_bus(capsys):
    rc, out, err = run(capsys, "socketcand:127.0.0.1:1/can0", "list", "--no-read", "injection.*")
    assert rc == 0, err
    lines = out.splitlines()
    assert lines[0].split() == ["name", "default", "unit", "range", "access"]
    assert any(ln.split()[:2] == ["injection.kind", "sine"] and "off|sine|rect" in ln for ln in lines)
    assert any(ln.startswith("injection.f_hz") and "1 .. 10000" in ln for ln in lines)
    assert not any("control." in ln for ln in lines)


def test_bus_open_failure_names_the_spec(capsys):
    rc, out, err = run(capsys, "socketcand:127.0.0.1:1/can0", "info")
    assert rc == 1
    assert "cannot open bus socketcand:127.0.0.1:1/can0" in err
    rc, out, err = run(capsys, "socketcand:nohostport", "info")
    assert rc == 2 and "socketcand:HOST:PORT/CHANNEL" in err


def test_info(capsys, bus, drive):
    rc, out, err = run(capsys, bus, "info")
    assert rc == 0, err
    assert "0x00020192 (CiA 402 drive profile)" in out
    assert "ipmsm-sensorless-drive" in out and "0.3.0-fixture" in out
    assert "serial 0x00001234" in out
    assert "PRE-OPERATIONAL" in out
    assert "SWITCH ON DISABLED" in out
    assert "pv (3)" in out
    assert re.search(rf"table hash match +yes \(0x{FIXTURE_HASH:08X}\)", out)
    assert "0: the stored set" in out
    assert err == ""


def test_get_set_round_trip_ranges_and_enums(capsys, bus, drive):
    rc, out, err = run(capsys, bus, "get", "control.current_bw_hz", "injection.kind", "control.decouple",
                       "motor.rs_ohm", "telem.theta", "0x1018:4")
    assert rc == 0, err
    assert out.splitlines() == ["control.current_bw_hz = 250 Hz", "injection.kind = sine",
                                "control.decouple = true", "motor.rs_ohm = 0.4 ohm", "telem.theta = 1.25 rad",
                                "0x1018:4 Identity object / Serial number = 0x00001234"]

    rc, out, err = run(capsys, bus, "set", "control.current_bw_hz", "400")
    assert rc == 0, err
    assert out.strip() == "control.current_bw_hz = 400 Hz (was 250 Hz)"
    assert drive.value(0x2018) == 400.0
    rc, out, err = run(capsys, bus, "get", "control.current_bw_hz")
    assert out.strip() == "control.current_bw_hz = 400 Hz"

    # ENUM by name and by position; BOOL as false
    assert run(capsys, bus, "set", "injection.kind", "rect")[0] == 0
    assert drive.value(0x202E) == 2
    assert run(capsys, bus, "get", "injection.kind")[1].strip() == "injection.kind = rect"
    assert run(capsys, bus, "set", "injection.kind", "0")[0] == 0 and drive.value(0x202E) == 0
    assert run(capsys, bus, "set", "control.decouple", "false")[0] == 0 and drive.value(0x201A) == 0
    rc, out, err = run(capsys, bus, "set", "injection.kind", "square")
    assert rc == 2 and "off|sine|rect" in err

    # the EDS's range, checked before any write (float32 limits: 0.49f is allowed)
    n = len(drive.writes)
    rc, out, err = run(capsys, bus, "set", "control.current_bw_hz", "1e6")
    assert rc == 2
    assert "out of range: control.current_bw_hz (0x2018) must be within 10 .. 5000 Hz" in err
    assert "1000000 Hz" in err
    rc, out, err = run(capsys, bus, "set", "injection.kind", "3")
    assert rc == 2 and "positions 0..2" in err
    rc, out, err = run(capsys, bus, "set", "motor.pole_pairs", "4")
    assert rc == 2 and "read-only" in err and "INIT" in err
    assert len(drive.writes) == n
    assert run(capsys, bus, "set", "control.i_headroom", "0.49")[0] == 0


def test_abort_decoded_exit_2(capsys, bus, drive):
    # the drive refuses above 2000 Hz (its own cross-check) with "value too high"
    drive.refuse[0x2018] = (lambda d: struct.unpack("<f", d)[0] > 2000, 0x06090031)
    rc, out, err = run(capsys, bus, "set", "control.current_bw_hz", "3000")
    assert rc == 2
    assert "set control.current_bw_hz 3000: refused by the drive: value too high (SDO abort 0x06090031)" in err
    rc, out, err = run(capsys, bus, "set", "control.current_bw_hz", "1e6", "--force")
    assert rc == 2
    assert "set control.current_bw_hz 1e6: refused by the drive: value too high (SDO abort 0x06090031)" in err
    # a STANDSTILL parameter while the outputs are on
    drive.refuse[0x202E] = (lambda d: True, 0x08000022)
    rc, out, err = run(capsys, bus, "set", "injection.kind", "off")
    assert rc == 2
    assert "not in the present device state (SDO abort 0x08000022)" in err
    assert "STANDSTILL: disable the outputs first" in err
    # an object the device does not have
    rc, out, err = run(capsys, bus, "get", "0x5000")
    assert rc == 2 and "no such object (SDO abort 0x06020000)" in err


def test_wrong_node_names_the_nodes_there(capsys, bus, drive):
    t0 = time.monotonic()
    rc, out, err = run(capsys, bus, "get", "control.current_bw_hz", node=5, timeout="0.2")
    assert rc == 1
    assert f"node 5 does not answer on {bus} (heartbeats seen from nodes [{NODE}]" in err
    assert f"try --node {NODE}" in err
    assert time.monotonic() - t0 < 3


def test_eds_mismatch_warns(capsys, bus, drive):
    drive.put(0x2FF0, 0, 0xDEADBEEF)
    rc, out, err = run(capsys, bus, "get", "control.current_bw_hz")
    assert rc == 0 and "250 Hz" in out
    assert "does not match" in err and "0x1F2E3D4C" in err and "0xDEADBEEF" in err
    assert "gen_docs.py" in err
    rc, out, err = run(capsys, bus, "info")
    assert "NO: drive 0xDEADBEEF, EDS 0x1F2E3D4C" in out


def test_enable_walks_the_state_machine(capsys, bus, drive):
    rc, out, err = run(capsys, bus, "enable", "--mode", "tq")
    assert rc == 0, err
    assert drive.controlwords == [0x06, 0x07, 0x0F]
    assert drive.value(0x6060) == 4
    assert [w[0] for w in drive.writes if w[0] in (0x6060, 0x6040)] == [0x6060, 0x6040, 0x6040, 0x6040]
    for st in ("READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED"):
        assert st in out
    assert "RUN" in out and "enabled; mode tq (4)" in out

    rc, out, err = run(capsys, bus, "disable")
    assert rc == 0 and drive.controlwords[-1] == 0x06 and drive.state == READY
    rc, out, err = run(capsys, bus, "disable", "--voltage")
    assert rc == 0 and drive.controlwords[-1] == 0x00 and drive.state == SWITCH_ON_DISABLED

    drive.set_state(FAULT)
    rc, out, err = run(capsys, bus, "enable")
    assert rc == 1 and "fault-reset" in err
    drive.controlwords.clear()
    rc, out, err = run(capsys, bus, "fault-reset")
    assert rc == 0, err
    assert drive.controlwords == [0x80, 0x00]   # rising edge of bit 7, then back to 0
    assert drive.state == SWITCH_ON_DISABLED and "SWITCH ON DISABLED" in out

    # a drive that never gets there: the step times out, naming the state
    drive._step_402 = lambda cw, prev: None
    rc, out, err = run(capsys, bus, "enable", "--wait", "0.2")
    assert rc == 1 and "still in SWITCH ON DISABLED" in err and "READY TO SWITCH ON" in err


def test_fault_reset_makes_its_own_rising_edge(capsys, bus, drive):
    """A drive in FAULT whose controlword already has bit 7 set (a master that left it high):
    only a rising edge of bit 7 resets the fault (CiA 402), so mctune writes 0x00 first, then
    0x80, then 0x00 again; the drive leaves FAULT."""
    drive.set_state(FAULT)
    drive.put(0x6040, 0, 0x80)
    drive.controlwords[:] = [0x80]
    rc, out, err = run(capsys, bus, "fault-reset")
    assert rc == 0, err
    assert drive.controlwords == [0x80, 0x00, 0x80, 0x00]
    assert drive.state == SWITCH_ON_DISABLED and "SWITCH ON DISABLED" in out


def test_speed_torque_save_restore(capsys, bus, drive):
    rc, out, err = run(capsys, bus, "speed", "1500")
    assert rc == 0, err
    assert drive.value(0x60FF) == 1500 and "1500 rpm" in out
    rc, out, err = run(capsys, bus, "torque", "14.85", "--nm")
    assert rc == 0
    assert drive.value(0x6071) == 500 and "500 per-mille" in out
    assert "mode pv (3)" in err   # a torque target in pv: warned
    rc, out, err = run(capsys, bus, "torque", "40000")
    assert rc == 2 and "-32768 .. 32767" in err

    rc, out, err = run(capsys, bus, "save")
    assert rc == 0, err
    assert drive.value(0x1010, 1) == 0x65766173
    rc, out, err = run(capsys, bus, "restore")
    assert rc == 0 and drive.value(0x1011, 1) == 0x64616F6C
    assert "after the next restart" in out
    drive.refuse[0x1010] = (lambda d: True, 0x08000022)
    rc, out, err = run(capsys, bus, "save")
    assert rc == 2 and "outputs are on" in err


def test_scope_upload_and_csv(capsys, bus, drive, tmp_path):
    samples, trig, period = 300, 30, 2e-4
    # i_q (ch 10) and i_q_ref (ch 12), sample-major float32: the DOMAIN the drive would fill
    values = []
    for k in range(samples):
        values += [0.01 * k, 5.0]
    drive.node.data_store[0x2307] = {0: struct.pack(f"<{len(values)}f", *values)}
    drive.put(0x2304, 0, samples)
    drive.put(0x2305, 0, trig)
    drive.put(0x2306, 0, period)
    prefix = tmp_path / "cap"
    rc, out, err = run(capsys, bus, "scope", "--channels", "i_q,i_q_ref", "--trigger", "i_q", "--level",
                       "1.5", "--edge", "falling", "--length", str(samples), "--decimation", "2",
                       "--out", str(prefix))
    assert rc == 0, err
    # the configuration the drive received
    assert [drive.value(0x2300, s) for s in range(1, 9)] == [10, 12, 0, 0, 0, 0, 0, 0]
    assert [drive.value(0x2301, s) for s in range(1, 7)] == [10, 1.5, 1, 2, 30, 300]
    assert (0x2302, 0, b"\x01") in drive.writes
    assert "triggered" in out and "done" in out
    assert f"{samples} samples x 2 channels" in out
    rows = list(csv.reader(open(f"{prefix}.csv")))
    assert rows[0] == ["t [s]", "i_q [A]", "i_q_ref [A]"]
    assert len(rows) == samples + 1
    assert float(rows[1 + trig][0]) == 0.0
    assert float(rows[1][0]) == pytest.approx(-trig * period)
    assert float(rows[-1][0]) == pytest.approx((samples - 1 - trig) * period)
    assert float(rows[101][1]) == pytest.approx(1.0) and float(rows[101][2]) == 5.0
    assert Path(f"{prefix}.png").stat().st_size > 1000

    # no trigger: the scope is stopped after --timeout
    drive._on_read = lambda index, subindex, od: 1 if index == 0x2303 else None
    drive.node._read_callbacks[:] = [drive._on_read]
    rc, out, err = run(capsys, bus, "scope", "--channels", "13", "--trigger", "i_q", "--timeout", "0.3")
    assert rc == 1 and "no trigger within 0.3 s" in err and "stopped" in err
    assert drive.writes[-1] == (0x2302, 0, b"\x00")
    assert drive.value(0x2300, 1) == 13   # a channel by id

    # --then: the step written after the arm, by the same client
    drive._on_read = lambda index, subindex, od: 3 if index == 0x2303 else None
    drive.node._read_callbacks[:] = [drive._on_read]
    n0 = len(drive.writes)
    rc, out, err = run(capsys, bus, "scope", "--channels", "i_q", "--length", "100",
                       "--then", "0x60FF=600", "--out", str(tmp_path / "then"))
    assert rc == 0, err
    w = drive.writes[n0:]
    arm = w.index((0x2302, 0, b"\x01"))
    assert (0x60FF, 0, struct.pack("<i", 600)) in w[arm + 1:]
    assert "then 0x60FF" in out
    rc, out, err = run(capsys, bus, "scope", "--channels", "i_q", "--then", "600")
    assert rc == 2 and "NAME=VALUE" in err

    rc, out, err = run(capsys, bus, "scope", "--channels", "i_q", "--length", "5000")
    assert rc == 2 and "holds 4096" in err
    rc, out, err = run(capsys, bus, "scope", "--channels", "nope")
    assert rc == 2 and "no telemetry channel 'nope'" in err


def test_monitor_csv_from_tpdos(capsys, bus, drive, tmp_path, monkeypatch):
    stop = threading.Event()

    def sender():
        k = 0
        while not stop.is_set():
            drive.send(0x180 + NODE, struct.pack("<Hb", 0x4237, 3))
            drive.send(0x280 + NODE, struct.pack("<ih", 1500, 250))
            drive.send(0x380 + NODE, struct.pack("<ff", 0.01 * k, 100.0))
            drive.send(0x480 + NODE, struct.pack("<fI", 0.5, 300000))
            if k == 20:   # an over-current EMCY: error code, register, fault bit, fault word
                drive.send(0x80 + NODE, struct.pack("<HBBI", 0x2310, 0x03, 0, 1))
            k += 1
            time.sleep(0.01)

    th = threading.Thread(target=sender, daemon=True)
    th.start()
    prefix = tmp_path / "mon"
    try:
        rc, out, err = run(capsys, bus, "monitor", "--duration", "0.6", "--out", str(prefix))
    finally:
        stop.set()
        th.join()
    assert rc == 0, err
    assert "TPDO3 0x383" in out and "telem.theta" in out
    assert "PRE-OPERATIONAL" in err   # the node would need an NMT start to send them
    assert "EMCY from node 3: error code 0x2310 (Current), error register 0x03" in err
    assert "00 01 00 00 00: drive fault overcurrent\n" in err   # named from faults.json
    rows = list(csv.DictReader(open(f"{prefix}.csv")))
    header = list(rows[0])
    assert header == ["t [s]", "Statusword", "Modes of operation display", "Velocity actual value [rpm]",
                      "Torque actual value [per-mille]", "telem.theta [rad]", "telem.omega [rad/s]",
                      "telem.est_cost", "DC link circuit voltage [mV]"]
    assert len(rows) > 20
    t = [float(r["t [s]"]) for r in rows]
    assert t[0] == 0.0 and t == sorted(t)
    thetas = [float(r["telem.theta [rad]"]) for r in rows if r["telem.theta [rad]"]]
    assert len(thetas) > 5 and thetas == sorted(thetas)
    for r in rows:
        if r["telem.omega [rad/s]"]:
            assert float(r["telem.omega [rad/s]"]) == 100.0 and r["Velocity actual value [rpm]"] == ""
        if r["Velocity actual value [rpm]"]:
            assert int(r["Velocity actual value [rpm]"]) == 1500
            assert int(r["Torque actual value [per-mille]"]) == 250
        if r["Statusword"]:
            assert int(r["Statusword"]) == 0x4237
        if r["DC link circuit voltage [mV]"]:
            assert int(r["DC link circuit voltage [mV]"]) == 300000
    assert Path(f"{prefix}.png").stat().st_size > 1000

    # only some signals, NMT start first; nothing received; --plot without a display
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    rc, out, err = run(capsys, bus, "monitor", "--duration", "0.2", "--out", str(prefix),
                       "--signals", "theta,omega", "--start", "--plot")
    assert rc == 0, err
    assert drive.node.nmt.state == "OPERATIONAL"
    assert "no display" in err and "no TPDO received" in err
    assert next(csv.reader(open(f"{prefix}.csv"))) == ["t [s]", "telem.theta [rad]", "telem.omega [rad/s]"]
    assert Path(f"{prefix}.png").is_file()
    rc, out, err = run(capsys, bus, "monitor", "--duration", "0.1", "--signals", "nope")
    assert rc == 2 and "no mapped signal 'nope'" in err and "telem.theta" in err


def test_nmt_and_list_reads(capsys, bus, drive):
    rc, out, err = run(capsys, bus, "nmt", "start")
    assert rc == 0 and "heartbeat: OPERATIONAL" in out
    rc, out, err = run(capsys, bus, "list", "bw")
    assert rc == 0, err
    names = [ln.split()[0] for ln in out.splitlines()[1:]]
    assert names == ["control.current_bw_hz", "control.speed_bw_hz"]
    assert out.splitlines()[0].split() == ["name", "value", "unit", "range", "access"]
    rc, out, err = run(capsys, bus, "list", "--telem", "i_q*")
    assert rc == 0 and "telem.i_q " in out and "3.5" in out


def test_fault_names_from_the_generated_table():
    """mctune names faults from tools/mctools/data/faults.json (generated from mc/faults.h)."""
    from mctools.mctune.faults import emcy_fault, fault_names, load_faults
    faults = load_faults()
    assert faults[0]["name"] == "overcurrent" and faults[11]["name"] == "loss_of_lock"
    assert fault_names(0x0801) == ["overcurrent", "loss_of_lock"]
    assert fault_names(1 << 30, faults) == ["bit30"]
    word = (1 << 8) | (1 << 10)   # over-speed latched, then tracking in its reaction
    assert emcy_fault(0x8300, struct.pack("<BI", 10, word)) == "tracking (latched with overspeed)"
    assert emcy_fault(0x8400, struct.pack("<BI", 8, 1 << 8)) == "overspeed"
    # the device's own EMCYs are not faults: a refused parameter set (kind, id), an error reset
    assert emcy_fault(0x6320, bytes([3, 17, 0, 0, 0])) is None
    assert emcy_fault(0x0000, bytes(5)) is None
    assert emcy_fault(0x2310, bytes([0])) is None


def test_save_waits_for_the_flash_erase(capsys, bus, drive):
    """A store answers after the flash erase (S25FL128S: ~130 ms typical, several times that at
    worst): mctune waits for it longer than for the 1 s of other SDOs."""
    drive.refuse[0x1010] = (lambda d: time.sleep(1.5), 0)   # answers after 1.5 s, never refuses
    rc, out, err = run(capsys, bus, "save")
    assert rc == 0, err
    assert drive.value(0x1010, 1) == 0x65766173
