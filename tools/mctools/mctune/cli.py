"""mctune: tune and drive the IPMSM drive over CANopen (CiA 301 / CiA 402) from a PC.

Parameters by their dotted names (0x2000 + id), telemetry (0x2200 + channel), store / restore,
the CiA 402 state machine, speed and torque targets, live TPDOs and the drive's scope. Names,
types, units and ranges come from the EDS the firmware build generates
(tools/mctools/data/drive.eds; --eds for another); the drive's parameter-table hash (0x2FF0) is
compared with it on every connection.

Exit status: 0 done, 1 bus / communication error (no answer, a state not reached), 2 input
refused (by the tool or by the drive: an SDO abort)."""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

from mctools.mctune.bus import DEFAULT_BUS, DEFAULT_TIMEOUT_S, NMT_COMMANDS, NMT_STATES
from mctools.mctune.drive import (
    CONFIG_SOURCES, ERROR_REGISTER_BITS, MODE_NAMES, MODES, STORE_STATUS, Drive, describe_statusword,
    format_value, scope_channel,
)
from mctools.mctune.eds import INT_RANGES, Eds, check_range, default_eds_path, match_pattern
from mctools.mctune.errors import InputError, MctuneError
from mctools.mctune.faults import emcy_fault, fault_names

EXIT_INTERRUPTED = 130


def _err(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------
# commands

def cmd_info(args, drive: Drive) -> int:
    def opt(index, sub=0):
        try:
            return drive.read_obj(index, sub)
        except InputError as exc:  # an object this device does not have
            return f"({str(exc).split('refused by the drive: ')[-1]})"

    rows = [("node", f"{drive.node_id} on {drive.bus_spec}"), ("EDS", str(drive.eds.path))]
    dt = opt(0x1000)
    rows.append(("device type", f"0x{dt:08X}" + (" (CiA 402 drive profile)" if isinstance(dt, int) and
                                                 dt & 0xFFFF == 402 else "") if isinstance(dt, int) else dt))
    rows.append(("device name", str(opt(0x1008))))
    rows.append(("software version", str(opt(0x100A))))
    ident = []
    for sub, what in ((1, "vendor"), (2, "product"), (3, "revision"), (4, "serial")):
        v = opt(0x1018, sub)
        ident.append(f"{what} 0x{v:08X}" if isinstance(v, int) else f"{what} {v}")
    rows.append(("identity (0x1018)", ", ".join(ident)))
    er = opt(0x1001)
    if isinstance(er, int):
        bits = [name for bit, name in ERROR_REGISTER_BITS if er & (1 << bit)]
        rows.append(("error register", f"0x{er:02X} ({', '.join(bits) if bits else 'no error'})"))
    else:
        rows.append(("error register", er))
    hb = opt(0x1017)
    if isinstance(hb, int) and hb == 0:
        rows.append(("NMT state", "unknown: heartbeat off (0x1017 = 0)"))
    else:
        wait = min(5.0, 1.5 * hb / 1000.0 + 0.1) if isinstance(hb, int) else 1.5
        st = drive.nmt_state(wait)
        rows.append(("NMT state", f"{NMT_STATES.get(st, hex(st))} (heartbeat every {hb} ms)" if st is not None
                     else f"no heartbeat within {wait:.1f} s"))
    sw = opt(0x6041)
    rows.append(("CiA 402 state", describe_statusword(sw) if isinstance(sw, int) else sw))
    if isinstance(sw, int) and sw & 0x4F in (0x08, 0x0F):
        ec = opt(0x603F)
        rows.append(("error code (0x603F)", f"0x{ec:04X}" if isinstance(ec, int) else ec))
        word = opt(0x221B)   # telem.faults: the latched fault bits (REAL32)
        if isinstance(word, float):
            rows.append(("drive faults", ", ".join(fault_names(int(word))) or "none"))
    md = opt(0x6061)
    rows.append(("mode of operation", f"{MODE_NAMES.get(md, '?')} ({md})" if isinstance(md, int) else md))
    eds_h, dev_h = drive.table_hashes()
    if dev_h is None:
        rows.append(("table hash match", "unknown: the drive has no 0x2FF0"))
    elif eds_h is None:
        rows.append(("table hash match", f"unknown: the EDS has no 0x2FF0 default (drive 0x{dev_h:08X})"))
    else:
        rows.append(("table hash match", f"yes (0x{dev_h:08X})" if eds_h == dev_h else
                     f"NO: drive 0x{dev_h:08X}, EDS 0x{eds_h:08X}"))
    cs = opt(0x2FF1)
    rows.append(("configuration (0x2FF1)", f"{cs}: {CONFIG_SOURCES.get(cs, 'unknown')}" if isinstance(cs, int)
                 else cs))
    w = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{w}}  {v}")
    return 0


def _table(rows: list[list[str]], header: list[str]) -> None:
    widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
    line = lambda r: "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip()  # noqa: E731
    print(line(header))
    for r in rows:
        print(line(r))


def cmd_list(args, eds: Eds, drive: Drive | None) -> int:
    entries = eds.telemetry() if args.telem else eds.params()
    entries = [e for e in entries if match_pattern(e.name, args.pattern)]
    if not entries:
        raise InputError(f"list: nothing in the EDS matches {args.pattern!r}")
    rows = []
    for e in entries:
        if drive is None:
            value = format_value(e, e.default, with_unit=False) if e.default is not None else ""
        else:
            try:
                value = format_value(e, drive.read(e, f"list: {e.name}: "), with_unit=False)
            except InputError as exc:
                value = "(" + str(exc).split("refused by the drive: ")[-1] + ")"
        access = e.access or e.access_type
        if e.access == "INIT":
            access += " (ro)"
        rows.append([e.name, value, e.unit, e.range_text(), access])
    _table(rows, ["name", "default" if drive is None else "value", "unit", "range", "access"])
    return 0


def cmd_get(args, drive: Drive) -> int:
    for key in args.keys:
        for e, v in drive.get(key):
            print(f"{e.label} = {format_value(e, v)}")
    return 0


def cmd_set(args, drive: Drive) -> int:
    e, old, new = drive.set(args.name, args.value, force=args.force)
    was = f" (was {format_value(e, old)})" if old is not None else ""
    print(f"{e.label} = {format_value(e, new)}{was}")
    return 0


def cmd_save(args, drive: Drive) -> int:
    st = drive.save()
    print("saved: the drive's configuration is in its store (0x1010:1 = \"save\")"
          + (f"; store status {st}: {STORE_STATUS.get(st, 'unknown')}" if st is not None else ""))
    if st not in (None, 0, 7):
        return 1
    return 0


def cmd_restore(args, drive: Drive) -> int:
    st = drive.restore()
    print("restored: the stored set is erased (0x1011:1 = \"load\"); the defaults apply after the "
          "next restart of the drive (a reset node: mctune nmt reset, or power-on), until then the values in force stay"
          + (f"; store status {st}: {STORE_STATUS.get(st, 'unknown')}" if st not in (None, 0) else ""))
    return 0


def cmd_enable(args, drive: Drive) -> int:
    drive.enable(args.mode, timeout=args.wait)
    md = drive.mode_display("enable: ")
    if args.mode and md != MODES[args.mode]:
        _err(f"mctune: warning: mode of operation display 0x6061 = {md}, not {MODES[args.mode]} "
             f"({args.mode})")
    print(f"enabled; mode {MODE_NAMES.get(md, '?')} ({md})")
    return 0


def cmd_disable(args, drive: Drive) -> int:
    drive.disable(voltage=args.voltage, timeout=args.wait)
    return 0


def cmd_fault_reset(args, drive: Drive) -> int:
    drive.fault_reset(timeout=args.wait)
    return 0


def cmd_quick_stop(args, drive: Drive) -> int:
    drive.quick_stop(timeout=args.wait)
    return 0


def _mode_warning(drive: Drive, modes: tuple[int, ...], what: str) -> None:
    md = drive.mode_display(what)
    if md not in modes:
        want = "/".join(MODE_NAMES[m] for m in modes)
        _err(f"mctune: warning: the drive is in mode {MODE_NAMES.get(md, '?')} ({md}): the target "
             f"takes effect in {want} (mctune enable --mode {MODE_NAMES[modes[0]]})")


def cmd_speed(args, drive: Drive) -> int:
    what = f"speed {args.rpm}: "
    rpm = round(args.rpm)
    e = drive.entry(0x60FF)
    check_range(e, rpm, str(args.rpm), what.rstrip(": "))
    _mode_warning(drive, (3, 9), what)
    if drive.eds.get(0x6080) is not None:
        vmax = int(drive.read_obj(0x6080, 0, what))
        if abs(rpm) > vmax:
            _err(f"mctune: warning: {rpm} rpm is above the max motor speed 0x6080 = {vmax} rpm: "
                 f"the drive clamps it")
    drive.write(e, rpm, what)
    print(f"target velocity 0x60FF = {rpm} rpm")
    return 0


def cmd_torque(args, drive: Drive) -> int:
    what = f"torque {args.value}{' --nm' if args.nm else ''}: "
    e = drive.entry(0x6071)
    note = ""
    if args.nm:
        rated_mnm = int(drive.read_obj(0x6076, 0, what))
        if rated_mnm <= 0:
            raise InputError(f"{what}the drive's rated torque 0x6076 is {rated_mnm} mN m: cannot convert "
                             f"N m to per-mille")
        permille = round(args.value * 1e6 / rated_mnm)
        note = f" ({args.value:g} N m of {rated_mnm / 1000:g} N m rated)"
    else:
        permille = round(args.value)
    lo, hi = INT_RANGES[e.data_type] if e.data_type in INT_RANGES else (-32768, 32767)
    if not lo <= permille <= hi:
        raise InputError(f"{what}{permille} per-mille does not fit the target torque 0x6071 "
                         f"({lo} .. {hi})")
    check_range(e, permille, str(permille), what.rstrip(": "))
    _mode_warning(drive, (4, 10), what)
    if drive.eds.get(0x6072) is not None:
        tmax = int(drive.read_obj(0x6072, 0, what))
        if abs(permille) > tmax:
            _err(f"mctune: warning: {permille} per-mille is above the max torque 0x6072 = {tmax}: "
                 f"the drive limits it")
    drive.write(e, permille, what)
    print(f"target torque 0x6071 = {permille} per-mille{note}")
    return 0


def cmd_nmt(args, drive: Drive) -> int:
    st = drive.nmt(args.nmt_command)
    if st is None:
        print(f"NMT {args.nmt_command} sent to node {drive.node_id}; no heartbeat since")
    else:
        print(f"NMT {args.nmt_command} sent to node {drive.node_id}; heartbeat: {NMT_STATES.get(st, hex(st))}")
    return 0


def cmd_monitor(args, drive: Drive) -> int:
    from mctools.mctune.capture import LivePlot, TpdoRecorder, has_display, plot_series, write_csv

    what = "monitor: "
    maps = []
    for num, m in drive.node.tpdo.map.items():
        try:
            drive._sdo(m.read, None, f"{what}TPDO{num}: ")
        except KeyError as exc:
            _err(f"mctune: warning: TPDO{num} maps an object the EDS does not describe ({exc}); skipped")
            continue
        if m.enabled and len(m.map):
            maps.append((num, m))
    if not maps:
        raise InputError(f"{what}node {drive.node_id} has no valid TPDO with a mapping")
    rec = TpdoRecorder(drive, maps, args.signals)
    for num, m in maps:
        kind = ("event-driven" if (m.trans_type or 0) >= 254 else f"every {m.trans_type} SYNC"
                if m.trans_type else "acyclic SYNC")
        timer = f", event timer {m.event_timer} ms" if m.event_timer else ""
        print(f"TPDO{num} 0x{m.cob_id:03X} ({kind}{timer}): {', '.join(v.name for v in m.map)}")
    st = drive.nmt_state(0.3)
    if args.start and st != 0x05:
        st = drive.nmt("start")
        print(f"NMT start: {NMT_STATES.get(st, 'no heartbeat') if st is not None else 'sent'}")
    elif st is not None and st != 0x05:
        _err(f"mctune: warning: node {drive.node_id} is {NMT_STATES.get(st, hex(st))}: it sends PDOs only "
             f"in OPERATIONAL (monitor --start, or mctune nmt start)")
    if args.sync:
        drive.network.sync.start(args.sync / 1000.0)
    rec.attach()
    def on_emcy(e):
        fault = emcy_fault(e.code, bytes(e.data))
        _err(f"EMCY from node {drive.node_id}: error code 0x{e.code:04X} "
             f"({getattr(e, 'get_desc', lambda: '')() or 'unknown'}), error register "
             f"0x{e.register:02X}, data {bytes(e.data).hex(' ')}" + (f": drive fault {fault}" if fault else ""))
    drive.node.emcy.add_callback(on_emcy)
    live = None
    if args.plot:
        if has_display():
            try:
                live = LivePlot(rec, f"node {drive.node_id} TPDOs")
            except Exception as exc:  # noqa: BLE001 - no usable GUI toolkit / display
                _err(f"mctune: --plot: no live plot ({type(exc).__name__}: {exc}); writing the PNG "
                     f"at the end only")
        else:
            _err("mctune: --plot: no display; writing the PNG at the end only")
    tty = sys.stdout.isatty()
    t0 = time.monotonic()
    last_print = 0.0
    try:
        while args.duration <= 0 or time.monotonic() - t0 < args.duration:
            now = time.monotonic()
            if tty and now - last_print >= 0.2:
                print("\r" + rec.live_line(now - t0)[:200].ljust(100), end="", flush=True)
                last_print = now
            elif not tty and now - last_print >= 1.0:
                print(rec.live_line(now - t0), flush=True)
                last_print = now
            if live is not None:
                try:
                    if not live.update():
                        break   # the window was closed
                except Exception as exc:  # noqa: BLE001 - the GUI went away; keep recording
                    _err(f"mctune: --plot: {type(exc).__name__}: {exc}; live plot off")
                    live = None
            else:
                time.sleep(0.05)
    except KeyboardInterrupt:
        pass
    finally:
        if args.sync:
            drive.network.sync.stop()
        for _, m in maps:
            m.callbacks.clear()
    if tty:
        print()
    header, rows = rec.table()
    counts = ", ".join(f"TPDO{n} {c}" for n, c in sorted(rec.counts.items()))
    csv_path = write_csv(Path(f"{args.out}.csv"), header, rows)
    png_path = plot_series(Path(f"{args.out}.png"), rec.series(),
                           f"node {drive.node_id} TPDOs on {drive.bus_spec}")
    print(f"{len(rows)} PDOs ({counts}) -> {csv_path}, {png_path}")
    if not rows:
        _err(f"mctune: warning: no TPDO received from node {drive.node_id}")
    return 0


def cmd_scope(args, drive: Drive) -> int:
    from mctools.mctune.capture import fmt_period, run_scope, scope_outputs

    names = [n for c in args.channels for n in c.split(",") if n.strip()]
    channels = [scope_channel(drive.eds, n) for n in names]
    trigger = scope_channel(drive.eds, args.trigger) if args.trigger else None
    pre = args.pre
    tty = sys.stdout.isatty()
    progress = (lambda s: print("\r" + s.ljust(40), end="", flush=True)) if tty else None
    then = []
    for item in args.then:
        name, sep, value = item.partition("=")
        if not sep or not name or not value:
            raise InputError(f"scope --then {item!r}: expected NAME=VALUE (e.g. 0x60FF=600)")
        then.append((name.strip(), value.strip()))

    def after_arm():
        for name, value in then:
            e, _old, new = drive.set(name, value)
            print(f"  then {e.label} = {format_value(e, new)}")

    rec = run_scope(drive, channels, trigger=trigger, level=args.level, edge=args.edge, pre=pre,
                    length=args.length, decimation=args.decimation, timeout=args.scope_timeout,
                    progress=progress, after_arm=after_arm if then else None)
    if tty:
        print()
    title = (f"node {drive.node_id} scope: {rec.samples} samples every {fmt_period(rec.period)}"
             + (f", trigger {trigger.name} {args.edge} {args.level:g}" if trigger else ""))
    csv_path, png_path = scope_outputs(rec, Path(args.out), title, trigger, args.level)
    print(f"{rec.samples} samples x {len(channels)} channels every {fmt_period(rec.period)}, trigger at "
          f"sample {rec.trigger_index} -> {csv_path}, {png_path}")
    return 0


# ---------------------------------------------------------------------------------------------
# command line

def _node(text: str) -> int:
    try:
        n = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a node id: {text!r}") from None
    if not 1 <= n <= 127:
        raise argparse.ArgumentTypeError(f"node id {n} outside 1..127")
    return n


def _positive(text: str) -> float:
    v = float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"must be > 0: {text}")
    return v


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="mctune", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bus", metavar="SPEC", default=os.environ.get("MCTUNE_BUS", DEFAULT_BUS),
                    help="socketcand:HOST:PORT/CHANNEL, socketcan:CHANNEL, virtual:NAME or "
                         "INTERFACE:CHANNEL[,key=value...] for any python-can interface "
                         f"(default: env MCTUNE_BUS, else {DEFAULT_BUS})")
    ap.add_argument("--node", type=_node, default=1, metavar="N", help="node id (default 1)")
    ap.add_argument("--eds", metavar="PATH",
                    help="EDS of the drive's firmware (default: the packaged mctools/data/drive.eds)")
    ap.add_argument("--timeout", type=_positive, default=DEFAULT_TIMEOUT_S, metavar="S",
                    help=f"SDO response timeout (default {DEFAULT_TIMEOUT_S:g} s)")
    ap.add_argument("-v", "--verbose", action="count", default=0,
                    help="log the canopen / python-can traffic (-vv: debug)")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("info", help="device, identity, NMT and CiA 402 state, EDS match")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("list", help="the drive's parameters: name, value, unit, range, access")
    p.add_argument("pattern", nargs="?", metavar="PATTERN",
                   help="glob (control.*) or substring (bw) of the names")
    p.add_argument("--no-read", action="store_true",
                   help="the EDS only (defaults), without the bus")
    p.add_argument("--telem", action="store_true", help="the telemetry channels instead")
    p.set_defaults(func=cmd_list)

    p = sub.add_parser("get", help="read parameters or objects")
    p.add_argument("keys", nargs="+", metavar="NAME|0xIIII[:SS]",
                   help="dotted parameter name, telem.<channel>, an EDS object name, or index "
                        "(all sub-indices) / index:sub (SS decimal or 0x..)")
    p.set_defaults(func=cmd_get)

    p = sub.add_parser("set", help="write a parameter or object (checked against the EDS)")
    p.add_argument("name", metavar="NAME|0xIIII[:SS]")
    p.add_argument("value", metavar="VALUE",
                   help="number; ENUM: choice name or position; BOOL: true/false/1/0")
    p.add_argument("--force", action="store_true",
                   help="skip the EDS's range and access checks: the drive decides")
    p.set_defaults(func=cmd_set)

    p = sub.add_parser("save", help="store the configuration in the drive (0x1010, outputs off)")
    p.set_defaults(func=cmd_save)
    p = sub.add_parser("restore", help="erase the stored set (0x1011): defaults after a restart")
    p.set_defaults(func=cmd_restore)

    p = sub.add_parser("enable", help="CiA 402: shutdown -> switch on -> enable operation")
    p.add_argument("--mode", choices=list(MODES), help="mode of operation 0x6060 to set first")
    p.add_argument("--wait", type=_positive, default=2.0, metavar="S",
                   help="time each step may take (default 2 s)")
    p.set_defaults(func=cmd_enable)

    p = sub.add_parser("disable", help="CiA 402 shutdown 0x06 (outputs off), or --voltage 0x00")
    p.add_argument("--voltage", action="store_true",
                   help="disable voltage 0x00 (to SWITCH ON DISABLED) instead of shutdown 0x06")
    p.add_argument("--wait", type=_positive, default=2.0, metavar="S",
                   help="time the state change may take (default 2 s)")
    p.set_defaults(func=cmd_disable)

    p = sub.add_parser("fault-reset", help="CiA 402 fault reset: 0x80 rising edge, then 0x00")
    p.add_argument("--wait", type=_positive, default=2.0, metavar="S",
                   help="time the reset may take (default 2 s)")
    p.set_defaults(func=cmd_fault_reset)

    p = sub.add_parser("quick-stop", help="CiA 402 quick stop 0x02")
    p.add_argument("--wait", type=_positive, default=5.0, metavar="S",
                   help="time the stop may take (default 5 s)")
    p.set_defaults(func=cmd_quick_stop)

    p = sub.add_parser("speed", help="target velocity 0x60FF [rpm, mechanical]")
    p.add_argument("rpm", type=float, metavar="RPM")
    p.set_defaults(func=cmd_speed)

    p = sub.add_parser("torque", help="target torque 0x6071 [per-mille of rated], or --nm")
    p.add_argument("value", type=float, metavar="PERMILLE")
    p.add_argument("--nm", action="store_true",
                   help="VALUE in N m, converted with the rated torque 0x6076")
    p.set_defaults(func=cmd_torque)

    p = sub.add_parser("monitor", help="record the TPDOs: live line, PREFIX.csv and PREFIX.png")
    p.add_argument("--duration", type=float, default=10.0, metavar="S",
                   help="how long (default 10 s; 0: until Ctrl-C)")
    p.add_argument("--out", default="monitor", metavar="PREFIX", help="output files (default monitor)")
    p.add_argument("--signals", nargs="+", metavar="NAME",
                   help="only these mapped signals (names, globs; comma lists allowed)")
    p.add_argument("--plot", action="store_true", help="a live plot window (needs a display)")
    p.add_argument("--start", action="store_true",
                   help="NMT start the node first if it is not OPERATIONAL (PDOs need it)")
    p.add_argument("--sync", type=float, metavar="MS",
                   help="send SYNC every MS ms (for synchronous TPDOs)")
    p.set_defaults(func=cmd_monitor)

    p = sub.add_parser("scope", help="capture with the drive's scope: PREFIX.csv and PREFIX.png")
    p.add_argument("--channels", required=True, nargs="+", metavar="CH[,CH...]",
                   help="telemetry channels (i_q,i_q_ref or ids), up to 8")
    p.add_argument("--trigger", metavar="CH", help="trigger channel (default: trigger at once)")
    p.add_argument("--level", type=float, default=0.0, metavar="X",
                   help="trigger level in the channel's unit (default 0)")
    p.add_argument("--edge", choices=["rising", "falling", "either"], default="rising")
    p.add_argument("--pre", type=int, metavar="N",
                   help="samples before the trigger (default: a tenth of the record with a "
                        "trigger, else 0)")
    p.add_argument("--length", type=int, default=0, metavar="N",
                   help="samples per channel (default 0: as many as fit)")
    p.add_argument("--decimation", type=int, default=1, metavar="D",
                   help="one sample every D control periods (default 1)")
    p.add_argument("--out", default="scope", metavar="PREFIX", help="output files (default scope)")
    p.add_argument("--timeout", dest="scope_timeout", type=_positive, default=10.0, metavar="S",
                   help="wait for the trigger and the record at most S s (default 10)")
    p.add_argument("--then", action="append", default=[], metavar="NAME=VALUE",
                   help="after arming, write this (a parameter or object, as `set` does; e.g. "
                        "0x60FF=600 for a speed step): the event to capture, from the same SDO client "
                        "(a drive serves one SDO client at a time); repeatable")
    p.set_defaults(func=cmd_scope)

    p = sub.add_parser("nmt", help="NMT command to the node (no SDO)")
    p.add_argument("nmt_command", choices=list(NMT_COMMANDS), metavar="{" + ",".join(NMT_COMMANDS) + "}")
    p.set_defaults(func=cmd_nmt)
    return ap


def _logging(verbose: int) -> None:
    if verbose:
        for name in ("canopen", "can"):
            logging.getLogger(name).propagate = True
        logging.basicConfig(level=logging.DEBUG if verbose > 1 else logging.INFO,
                            format="%(asctime)s %(name)s %(levelname)s: %(message)s")
    else:
        # canopen logs timeouts and out-of-range writes itself; the tool says it in words
        for name in ("canopen", "can"):
            lg = logging.getLogger(name)
            lg.addHandler(logging.NullHandler())
            lg.propagate = False


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    _logging(args.verbose)
    try:
        import can  # noqa: F401
        import canopen  # noqa: F401
    except ImportError as exc:
        _err(f"mctune: {exc.name or exc} is not installed: pip install 'mctools[can]' "
             f"(python-can and canopen)")
        return 1
    try:
        eds = Eds(args.eds or default_eds_path(), args.node)
        if args.command == "list" and args.no_read:
            return cmd_list(args, eds, None)
        with Drive.open(args.bus, args.node, eds, args.timeout) as drive:
            if args.command != "nmt":
                warning = drive.eds_warning()   # also the first SDO: does the node answer?
                if warning:
                    _err(f"mctune: {warning}")
            if args.command == "list":
                return cmd_list(args, eds, drive)
            return args.func(args, drive)
    except MctuneError as exc:
        _err(f"mctune: {exc}")
        return exc.exit_code
    except KeyboardInterrupt:
        _err("mctune: interrupted")
        return EXIT_INTERRUPTED

