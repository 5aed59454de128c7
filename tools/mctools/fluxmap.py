"""Measured flux maps of machine presets (`[flux_map] file = "NAME.csv"`).

The second implementation of the simulator's reader (sim/src/fluxmap_file.cpp): the same checks in
the same order with the same messages, the same figures at i = 0 and the same reciprocity measure
(tools/tests/test_fluxmap.py runs both on the same files). docs/machine-models.md "Measured flux
maps" describes the format. The map psi(i) is interpolated bilinearly per grid cell; outside the
grid the edge cell's polynomial is continued (linear along each axis), as the simulator's tables do.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HEADER = "i_d_A,i_q_A,psi_d_Vs,psi_q_Vs"
COLUMNS = HEADER.split(",")
RECIPROCITY_WARN = 0.10        # relative mismatch above which loading warns
MAX_BYTES = 16 << 20
_DECIMAL = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\Z")


class FluxMapError(ValueError):
    """A map file refused: the message names the file, the line where there is one, and the reason."""


def _g(v: float) -> str:
    """C's %.10g (the simulator's number format in these messages)."""
    return f"{v:.10g}"


@dataclass
class Axis:
    lo: float
    hi: float
    n: int

    @property
    def step(self) -> float:
        return (self.hi - self.lo) / (self.n - 1)

    def at(self, k: int) -> float:
        return self.hi if k == self.n - 1 else self.lo + k * self.step


def _axis(rows: list, col: int, path: str) -> Axis:
    first_line: dict[float, int] = {}
    for r in rows:
        first_line.setdefault(r[0][col] + 0.0, r[1])
    vals = sorted(first_line)
    span = vals[-1] - vals[0]
    u: list[tuple[float, int]] = []
    for v in vals:
        if not u or v - u[-1][0] > 1e-9 * span:
            u.append((v, first_line[v]))
    if len(u) < 3:
        raise FluxMapError(f"{path}: column {COLUMNS[col]} has {len(u)} distinct value(s); "
                           "a map needs at least 3 grid points per axis")
    a = Axis(u[0][0], u[-1][0], len(u))
    for k, (v, line) in enumerate(u):
        if abs(v - a.at(k)) > 1e-6 * a.step:
            raise FluxMapError(f"{path}:{line}: {COLUMNS[col]} = {_g(v)} is off the equally spaced grid "
                               f"({_g(a.at(k))} expected: {a.n} points from {_g(a.lo)} to {_g(a.hi)}); "
                               "the grid must be rectangular and equally spaced")
    return a


@dataclass
class FluxMap:
    """psi(i) on a regular grid: psi_d[a, b], psi_q[a, b] at (x.at(a), y.at(b))."""

    file: str
    x: Axis
    y: Axis
    psi_d: np.ndarray
    psi_q: np.ndarray
    psi_pm: float = 0.0
    psi_q0: float = 0.0
    ld: float = 0.0
    lq: float = 0.0
    ldq: float = 0.0
    recip_rms: float = 0.0
    recip_max: float = 0.0
    recip_max_at: tuple = (0.0, 0.0)
    warnings: list = field(default_factory=list)

    # -- bilinear interpolation with edge-cell continuation (sim Table2D::eval / jacobian) --------
    def _locate(self, ax: Axis, v):
        u = (np.asarray(v, dtype=float) - ax.lo) / ax.step
        k = np.clip(np.floor(u), 0, ax.n - 2).astype(int)
        return k, u - k

    def flux(self, i_d, i_q):
        """psi_dq(i_dq); broadcasts over arrays."""
        i_d, i_q = np.broadcast_arrays(np.asarray(i_d, dtype=float), np.asarray(i_q, dtype=float))
        i, tx = self._locate(self.x, i_d)
        j, ty = self._locate(self.y, i_q)

        def bil(f):
            return ((1 - tx) * (1 - ty) * f[i, j] + tx * (1 - ty) * f[i + 1, j]
                    + (1 - tx) * ty * f[i, j + 1] + tx * ty * f[i + 1, j + 1])
        return bil(self.psi_d), bil(self.psi_q)

    def inductances(self, i_d, i_q):
        """(l_dd, l_dq, l_qq) = d psi_d/d i_d, d psi_d/d i_q, d psi_q/d i_q of the cell polynomial
        (on a grid line the upper cell, as the simulator's Jacobian)."""
        i_d, i_q = np.broadcast_arrays(np.asarray(i_d, dtype=float), np.asarray(i_q, dtype=float))
        i, tx = self._locate(self.x, i_d)
        j, ty = self._locate(self.y, i_q)
        hx, hy = self.x.step, self.y.step

        def ddx(f):
            return ((1 - ty) * (f[i + 1, j] - f[i, j]) + ty * (f[i + 1, j + 1] - f[i, j + 1])) / hx

        def ddy(f):
            return ((1 - tx) * (f[i, j + 1] - f[i, j]) + tx * (f[i + 1, j + 1] - f[i + 1, j])) / hy
        return ddx(self.psi_d), ddy(self.psi_d), ddy(self.psi_q)

    def small_signal(self):
        return self.psi_pm, self.ld, self.lq

    def in_grid(self, i_d: float, i_q: float) -> bool:
        return self.x.lo <= i_d <= self.x.hi and self.y.lo <= i_q <= self.y.hi


def read_flux_map(path) -> FluxMap:
    """Read and check a map file; raises FluxMapError (file, line, reason) as the simulator does."""
    path = str(path)
    p = Path(path)
    if not p.is_file():
        raise FluxMapError(f"{path}: no such flux-map file (or not a regular file)")
    size = p.stat().st_size
    if size > MAX_BYTES:
        raise FluxMapError(f"{path}: file of {size} bytes is larger than the 16 MiB limit for a flux map")
    rows: list = []
    have_header = False
    with open(path, "rb") as f:
        text = f.read().decode("latin-1")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    for lineno, line in enumerate(lines, start=1):
        s = "".join(c for c in line if c not in " \t\r")
        if not s or s[0] == "#":
            continue
        where = f"{path}:{lineno}: "
        if not have_header:
            if s != HEADER:
                raise FluxMapError(f"{where}header '{line[:80]}' is not '{HEADER}'")
            have_header = True
            continue
        cells = s.split(",")
        if len(cells) != 4:
            raise FluxMapError(f"{where}expected 4 columns ({HEADER}), got {len(cells)}")
        vals = []
        for k, c in enumerate(cells):
            v = float(c) if _DECIMAL.match(c) else math.nan
            if not math.isfinite(v):
                raise FluxMapError(f"{where}column {COLUMNS[k]}: '{c[:40]}' is not a finite number")
            vals.append(v)
        rows.append((vals, lineno))
    if not have_header:
        raise FluxMapError(f"{path}: empty file (no header line '{HEADER}')")
    if not rows:
        raise FluxMapError(f"{path}: no data rows after the header")
    ax, ay = _axis(rows, 0, path), _axis(rows, 1, path)
    pd = np.zeros((ax.n, ay.n))
    pq = np.zeros((ax.n, ay.n))
    line_of = np.zeros((ax.n, ay.n), dtype=int)
    for vals, line in rows:
        a = int(round((vals[0] - ax.lo) / ax.step))
        b = int(round((vals[1] - ay.lo) / ay.step))
        if line_of[a, b]:
            raise FluxMapError(f"{path}:{line}: duplicate grid point (i_d, i_q) = ({_g(ax.at(a))}, "
                               f"{_g(ay.at(b))}) A, first given on line {line_of[a, b]}")
        line_of[a, b] = line
        pd[a, b], pq[a, b] = vals[2], vals[3]
    for a in range(ax.n):
        for b in range(ay.n):
            if not line_of[a, b]:
                raise FluxMapError(f"{path}: no row for grid point (i_d, i_q) = ({_g(ax.at(a))}, "
                                   f"{_g(ay.at(b))}) A: the {ax.n} x {ay.n} grid needs {ax.n * ay.n} "
                                   f"rows, the file has {len(rows)}")
    for b in range(ay.n):
        for a in range(1, ax.n):
            if not pd[a, b] > pd[a - 1, b]:
                raise FluxMapError(
                    f"{path}:{line_of[a, b]}: psi_d_Vs = {_g(pd[a, b])} does not rise with i_d "
                    f"({_g(pd[a - 1, b])} at i_d = {_g(ax.at(a - 1))} A, line {line_of[a - 1, b]}; "
                    f"i_q = {_g(ay.at(b))} A): psi_d must increase strictly along i_d")
    for a in range(ax.n):
        for b in range(1, ay.n):
            if not pq[a, b] > pq[a, b - 1]:
                raise FluxMapError(
                    f"{path}:{line_of[a, b]}: psi_q_Vs = {_g(pq[a, b])} does not rise with i_q "
                    f"({_g(pq[a, b - 1])} at i_q = {_g(ay.at(b - 1))} A, line {line_of[a, b - 1]}; "
                    f"i_d = {_g(ax.at(a))} A): psi_q must increase strictly along i_q")
    if not (ax.lo <= 0 <= ax.hi and ay.lo <= 0 <= ay.hi):
        raise FluxMapError(f"{path}: the grid (i_d {_g(ax.lo)} .. {_g(ax.hi)} A, i_q {_g(ay.lo)} .. "
                           f"{_g(ay.hi)} A) does not contain i = 0: the PM flux cannot be read from it")
    m = FluxMap(path, ax, ay, pd, pq)
    psi0_d, psi0_q = (float(v) for v in m.flux(0.0, 0.0))
    if not psi0_d > 0:
        raise FluxMapError(
            f"{path}: psi_d(0, 0) = {_g(psi0_d)} Vs: no PM flux on +d (the convention: magnet flux "
            "along +d; rotate a map with the magnets on -q by i_d' = -i_q, i_q' = i_d, "
            "psi_d' = -psi_q, psi_q' = psi_d)")
    m.psi_pm, m.psi_q0 = psi0_d, psi0_q
    hd, hq = ax.step, ay.step

    def ev(i_d, i_q):
        return tuple(float(v) for v in m.flux(i_d, i_q))
    m.ld = (ev(hd, 0.0)[0] - ev(-hd, 0.0)[0]) / (2 * hd)
    m.lq = (ev(0.0, hq)[1] - ev(0.0, -hq)[1]) / (2 * hq)
    m.ldq = (ev(0.0, hq)[0] - ev(0.0, -hq)[0]) / (2 * hq)
    l_dd = (pd[1:, :-1] - pd[:-1, :-1] + pd[1:, 1:] - pd[:-1, 1:]) / (2 * hd)
    l_qq = (pq[:-1, 1:] - pq[:-1, :-1] + pq[1:, 1:] - pq[1:, :-1]) / (2 * hq)
    l_dq = (pd[:-1, 1:] - pd[:-1, :-1] + pd[1:, 1:] - pd[1:, :-1]) / (2 * hq)
    l_qd = (pq[1:, :-1] - pq[:-1, :-1] + pq[1:, 1:] - pq[:-1, 1:]) / (2 * hd)
    rel = np.abs(l_dq - l_qd) / np.sqrt(l_dd * l_qq)
    m.recip_rms = float(np.sqrt(np.mean(rel**2)))
    m.recip_max = float(rel.max())
    a, b = np.unravel_index(int(np.argmax(rel)), rel.shape)   # first maximum, row-major as in C++
    m.recip_max_at = (ax.at(int(a)) + hd / 2, ay.at(int(b)) + hq / 2)
    if m.recip_max > RECIPROCITY_WARN:
        m.warnings.append(
            f"{path}: reciprocity: d psi_d/d i_q and d psi_q/d i_d differ by up to "
            f"{_g(100 * m.recip_max)} % of sqrt(l_dd l_qq) (rms {_g(100 * m.recip_rms)} %, worst in "
            f"the cell around ({_g(m.recip_max_at[0])}, {_g(m.recip_max_at[1])}) A); above "
            f"{_g(100 * RECIPROCITY_WARN)} % the map is not energy-consistent: the plant creates or "
            "loses energy on closed current paths")
    if abs(m.psi_q0) > 0.05 * m.psi_pm:
        m.warnings.append(f"{path}: psi_q(0, 0) = {_g(m.psi_q0)} Vs is more than 5 % of psi_d(0, 0) = "
                          f"{_g(m.psi_pm)} Vs: is the PM on +d (rotor angle offset)?")
    return m


def write_flux_map(path, i_d_axis, i_q_axis, flux_fn) -> int:
    """Tabulate flux_fn(i_d, i_q) -> (psi_d, psi_q) on the grid and write a map CSV (17 digits,
    i_d varying slowest). Returns the number of rows."""
    idg, iqg = np.meshgrid(np.asarray(i_d_axis, dtype=float), np.asarray(i_q_axis, dtype=float),
                           indexing="ij")
    psi_d, psi_q = flux_fn(idg, iqg)
    with open(path, "w", encoding="ascii") as f:
        f.write(HEADER + "\n")
        for a in range(idg.shape[0]):
            for b in range(idg.shape[1]):
                f.write(f"{idg[a, b]:.17g},{iqg[a, b]:.17g},{psi_d[a, b]:.17g},{psi_q[a, b]:.17g}\n")
    return idg.size
