"""Recordings for `mctune`: TPDOs received (monitor) and the drive's scope record (scope),
written as CSV and PNG (matplotlib's Agg canvas: no display needed)."""

from __future__ import annotations

import csv
import math
import os
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from mctools.mctune.drive import EDGES, SCOPE_STATUS, Drive, ScopeChannel, ScopeRecord, decode_scope
from mctools.mctune.eds import TELEM_BASE, match_pattern
from mctools.mctune.errors import CommError, InputError


def col_label(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def write_csv(path: Path, header: list[str], rows) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for row in rows:
            w.writerow(["" if v is None else (f"{v:.9g}" if isinstance(v, float) else v) for v in row])
    return path


@dataclass
class Series:
    label: str
    unit: str
    t: list[float]
    y: list[float]
    steps: bool = False     # an integer signal: held between updates
    hex_axis: bool = False  # a bit field (statusword): hex ticks


def plot_series(path: Path, panels: list[list[Series]], title: str, *, vline: float | None = None,
                hlines: dict[int, float] | None = None, dpi: int = 100) -> Path:
    """Stacked panels sharing the time axis; each panel holds one or more series."""
    from matplotlib.figure import Figure   # the Agg canvas, whatever backend pyplot may use

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    n = max(1, len(panels))
    fig = Figure(figsize=(8.0, 0.8 + 1.9 * n), dpi=dpi, layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for k, (ax, panel) in enumerate(zip(axes, panels)):
        for s in panel:
            style = dict(marker=".", ms=3) if len(s.t) < 60 else {}
            if s.steps:
                style["drawstyle"] = "steps-post"
            ax.plot(s.t, s.y, lw=1.0, label=s.label, **style)
            if s.hex_axis and s.y:
                from matplotlib.ticker import FuncFormatter
                ticks = sorted({int(v) for v in s.y})
                if len(ticks) <= 8:   # the words that occurred, in hex
                    ax.set_yticks(ticks)
                    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"0x{int(round(v)):04X}"))
        if not any(len(s.t) for s in panel):
            ax.text(0.5, 0.5, "nothing received", transform=ax.transAxes, ha="center",
                    va="center", color="0.5")
        units = sorted({s.unit for s in panel if s.unit})
        ax.set_ylabel(", ".join(units) if units else "")
        ax.grid(True, lw=0.4, alpha=0.6)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
        if vline is not None:
            ax.axvline(vline, color="0.4", lw=0.8, ls="--")
        if hlines and k in hlines:
            ax.axhline(hlines[k], color="tab:red", lw=0.8, ls=":")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=dpi)
    return path


# ---------------------------------------------------------------------------------------------
# monitor: TPDOs

@dataclass
class Signal:
    label: str      # column name: "name [unit]"
    name: str
    unit: str
    pdo: int        # TPDO number 1..
    pos: int        # position in the PDO's mapping
    integer: bool = False
    bits: bool = False   # statusword / controlword: shown in hex

    def text(self, v) -> str:
        if v is None:
            return "-"
        if self.bits:
            return f"0x{int(v):04X}"
        return (f"{v:.4g}" if isinstance(v, float) else str(v)) + (f" {self.unit}" if self.unit else "")


class TpdoRecorder:
    """Collects every received TPDO as (t, pdo number, values) from canopen's PdoMap callbacks."""

    def __init__(self, drive: Drive, maps: list[tuple[int, object]], select: list[str] | None):
        self.lock = threading.Lock()
        self.rows: list[tuple[float, int, list]] = []
        self.counts: dict[int, int] = {num: 0 for num, _ in maps}
        self.t0: float | None = None
        self.signals: list[Signal] = []
        labels: set[str] = set()
        for num, m in maps:
            for pos, var in enumerate(m.map):
                e = drive.eds.get(var.index, var.subindex)
                unit = e.unit if e else ""
                label = col_label(var.name, unit)
                while label in labels:
                    label += "'"
                labels.add(label)
                integer = e is not None and not e.is_float
                bits = (var.index, var.subindex) in ((0x6040, 0), (0x6041, 0))
                self.signals.append(Signal(label, var.name, unit, num, pos, integer, bits))
        if select:
            want = [w for s in select for w in s.split(",") if w.strip()]
            chosen = []
            for w in want:
                hit = [s for s in self.signals
                       if s.name == w or s.name == "telem." + w or match_pattern(s.name, w)]
                if not hit:
                    raise InputError(f"monitor: no mapped signal {w!r} (the TPDOs carry: "
                                     f"{', '.join(s.name for s in self.signals)})")
                chosen += [s for s in hit if s not in chosen]
            self.signals = chosen
        self.maps = {num: m for num, m in maps if any(s.pdo == num for s in self.signals)}
        self.latest: dict[str, object] = {}

    def attach(self) -> None:
        for num, m in self.maps.items():
            m.add_callback(lambda m_, num=num: self._on_pdo(num, m_))

    def _on_pdo(self, num: int, m) -> None:
        ts = m.timestamp if m.timestamp is not None else time.time()
        try:
            vals = [v.raw for v in m.map]
        except Exception:  # noqa: BLE001 - a PDO shorter than its mapping
            vals = [None] * len(m.map)
        with self.lock:
            if self.t0 is None:
                self.t0 = ts
            self.rows.append((ts - self.t0, num, vals))
            self.counts[num] = self.counts.get(num, 0) + 1
            for s in self.signals:
                if s.pdo == num:
                    self.latest[s.label] = vals[s.pos]

    def table(self) -> tuple[list[str], list[list]]:
        header = ["t [s]"] + [s.label for s in self.signals]
        out = []
        with self.lock:
            rows = list(self.rows)
        for t, num, vals in rows:
            row: list = [t]
            for s in self.signals:
                row.append(vals[s.pos] if s.pdo == num else None)
            out.append(row)
        return header, out

    def live_line(self, elapsed: float) -> str:
        with self.lock:
            parts = []
            for s in self.signals:
                parts.append(f"{s.name}={s.text(self.latest.get(s.label))}")
            n = len(self.rows)
        return f"t={elapsed:5.1f}s  {n} PDOs  " + "  ".join(parts)

    def series(self) -> list[list[Series]]:
        header, rows = self.table()
        panels = []
        for k, s in enumerate(self.signals, start=1):
            pts = [(r[0], float(r[k])) for r in rows if r[k] is not None]
            panels.append([Series(s.label, s.unit, [p[0] for p in pts], [p[1] for p in pts],
                                  steps=s.integer, hex_axis=s.bits)])
        return panels


def has_display() -> bool:
    if sys.platform.startswith(("win", "darwin")):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class LivePlot:
    """A pyplot window redrawn from the recorder (only with a display)."""

    def __init__(self, rec: TpdoRecorder, title: str):
        import matplotlib
        import matplotlib.pyplot as plt

        if matplotlib.get_backend().lower() in ("agg", "pdf", "svg", "ps", "cairo", "template"):
            raise RuntimeError(f"matplotlib has no interactive backend here ({matplotlib.get_backend()})")
        self.plt, self.rec = plt, rec
        self.last = 0.0
        plt.ion()
        n = len(rec.signals)
        self.fig, axes = plt.subplots(n, 1, sharex=True, squeeze=False, figsize=(8, 0.8 + 1.7 * n))
        self.axes = axes[:, 0]
        self.lines = []
        for ax, s in zip(self.axes, rec.signals):
            (ln,) = ax.plot([], [], lw=1.0, label=s.label)
            ax.legend(loc="upper left", fontsize=8)
            ax.grid(True, lw=0.4, alpha=0.6)
            self.lines.append(ln)
        self.axes[-1].set_xlabel("time [s]")
        self.fig.suptitle(title, fontsize=10)

    def update(self) -> bool:
        if not self.plt.fignum_exists(self.fig.number):
            return False
        now = time.monotonic()
        if now - self.last < 0.3:
            self.plt.pause(0.05)
            return True
        self.last = now
        for ax, ln, panel in zip(self.axes, self.lines, self.rec.series()):
            s = panel[0]
            ln.set_data(s.t, s.y)
            ax.relim()
            ax.autoscale_view()
        self.plt.pause(0.05)
        return True


# ---------------------------------------------------------------------------------------------
# scope

def run_scope(drive: Drive, channels: list[ScopeChannel], *, trigger: ScopeChannel | None,
              level: float, edge: str, pre: int | None, length: int, decimation: int, timeout: float,
              report=print, progress=None, after_arm=None) -> ScopeRecord:
    """Configure (0x2300, 0x2301), arm (0x2302 = 1), wait for done (0x2303), read the record's
    size, trigger index and period (0x2304..0x2306) and upload it (0x2307). pre None: a tenth
    of the record with a trigger, else 0."""
    what = "scope: "
    cap = int(drive.read_obj(0x2308, 0, what)) if drive.eds.get(0x2308) is not None else None
    if pre is None:
        n = length or (cap // max(1, len(channels)) if cap else 0)
        pre = n // 10 if trigger else 0
    if not 1 <= len(channels) <= 8:
        raise InputError(f"{what}1 to 8 channels, got {len(channels)}")
    if decimation < 1 or decimation > 65535:
        raise InputError(f"{what}--decimation must be 1..65535, got {decimation}")
    if length < 0 or pre < 0:
        raise InputError(f"{what}--length and --pre cannot be negative")
    if length and pre >= length:
        raise InputError(f"{what}--pre {pre} must be below --length {length}")
    if cap is not None:
        if length and length * len(channels) > cap:
            raise InputError(f"{what}--length {length} x {len(channels)} channels = "
                             f"{length * len(channels)} values: the scope holds {cap} "
                             f"(at most {cap // len(channels)} samples with {len(channels)} channels)")
        if pre * len(channels) >= cap:
            raise InputError(f"{what}--pre {pre} x {len(channels)} channels does not fit the "
                             f"scope's {cap} values")
    for k in range(8):
        drive.write_obj(0x2300, k + 1, channels[k].id if k < len(channels) else 0, what)
    drive.write_obj(0x2301, 1, trigger.id if trigger else 0, what)
    drive.write_obj(0x2301, 2, float(level), what)
    drive.write_obj(0x2301, 3, EDGES[edge], what)
    drive.write_obj(0x2301, 4, decimation, what)
    drive.write_obj(0x2301, 5, pre, what)
    drive.write_obj(0x2301, 6, length, what)
    drive.write_obj(0x2302, 0, 1, what + "arm: ")
    trig_text = (f"{trigger.name} {edge} through {level:g}{(' ' + trigger.unit) if trigger.unit else ''}"
                 if trigger else "at once")
    report(f"scope armed: {', '.join(c.name for c in channels)}; trigger {trig_text}")
    if after_arm is not None:
        after_arm()   # the event to capture (a step), from this SDO client
    t0 = time.monotonic()
    last = None
    try:
        while True:
            status = int(drive.read_obj(0x2303, 0, what))
            el = time.monotonic() - t0
            if progress:
                progress(f"{SCOPE_STATUS.get(status, status)}  {el:4.1f} s")
            if status != last and status in (2, 3) and not progress:
                report(f"  {SCOPE_STATUS[status]} after {el:.2f} s")
            last = status
            if status == 3:
                break
            if status == 0:
                raise CommError(f"{what}the scope went idle before it was done (stopped by someone?)")
            if el > timeout:
                drive.write_obj(0x2302, 0, 0, what)
                state = "no trigger" if status == 1 else "not done"
                raise CommError(f"{what}{state} within {timeout:g} s (status "
                                f"{SCOPE_STATUS.get(status, status)}, trigger {trig_text}); the scope "
                                f"was stopped. A longer --timeout, another --level, or no --trigger?")
            time.sleep(0.05)
    except KeyboardInterrupt:
        drive.write_obj(0x2302, 0, 0, what)
        raise
    samples = int(drive.read_obj(0x2304, 0, what))
    trig = int(drive.read_obj(0x2305, 0, what))
    period = float(f"{float(drive.read_obj(0x2306, 0, what)):.7g}")   # float32's digits: 1e-4, not 9.99999975e-05
    data = upload_domain(drive, 0x2307, what, progress)
    cols, warn = decode_scope(data, len(channels), samples)
    if warn:
        report(f"warning: {warn}")
    return ScopeRecord(channels, len(cols[0]) if cols else 0, trig, period, cols)


def upload_domain(drive: Drive, index: int, what: str, progress=None) -> bytes:
    """Segmented SDO upload, with progress."""
    def go():
        out = bytearray()
        with drive.node.sdo.open(index, 0, "rb", buffering=0) as fp:
            size = getattr(fp, "size", None)
            last = 0.0
            while True:
                chunk = fp.read(7)
                if not chunk:
                    break
                out += chunk
                now = time.monotonic()
                if progress and now - last > 0.2:
                    last = now
                    progress(f"upload {len(out)}/{size or '?'} bytes")
        return bytes(out)

    return drive._sdo(go, drive.entry(index), what + "upload: ", idempotent=True)


def scope_outputs(rec: ScopeRecord, prefix: Path, title: str, trigger: ScopeChannel | None,
                  level: float) -> tuple[Path, Path]:
    header = ["t [s]"] + [col_label(c.name, c.unit) for c in rec.channels]
    t = rec.times()
    rows = [[t[k]] + [col[k] for col in rec.data] for k in range(rec.samples)]
    csv_path = write_csv(Path(f"{prefix}.csv"), header, rows)
    # channels sharing a unit share a panel
    panels: list[list[Series]] = []
    by_unit: dict[str, int] = {}
    hlines = {}
    for c, col in zip(rec.channels, rec.data):
        key = c.unit or f"#{c.id}"
        if key not in by_unit:
            by_unit[key] = len(panels)
            panels.append([])
        panels[by_unit[key]].append(Series(col_label(c.name, c.unit), c.unit, t, col))
        if trigger and c.id == trigger.id:
            hlines[by_unit[key]] = level
    png_path = plot_series(Path(f"{prefix}.png"), panels, title,
                           vline=0.0 if rec.samples else None, hlines=hlines)
    return csv_path, png_path


def fmt_period(s: float) -> str:
    if not math.isfinite(s) or s <= 0:
        return f"{s:g} s"
    for unit, k in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if s >= k:
            return f"{s / k:.4g} {unit}"
    return f"{s / 1e-9:.4g} ns"


__all__ = ["TpdoRecorder", "LivePlot", "run_scope", "scope_outputs", "write_csv", "plot_series",
           "has_display", "TELEM_BASE", "fmt_period"]
