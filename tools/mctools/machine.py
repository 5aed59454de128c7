"""Machine model shared by the tools: flux linkage <-> current, torque, MTPA.

Conventions follow docs (machines.md): peak-value space vectors in the rotor
frame, SI units, electrical angles. The analytic saturation model gives the
current map i(psi) in closed form; psi(i) is found by Newton iteration on it,
the same direction the simulator uses (it integrates flux, never inverts a
flux map by differentiation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class SaturationModel:
    """Energy-consistent saturation model (machines.md).

    i_d = G_d psi_d - i_f,  i_q = G_q psi_q
    G_d = a_d0 + a_dd |psi_d|^S + a_dq/(V+2) |psi_d|^U |psi_q|^(V+2)
    G_q = a_q0 + a_qq |psi_q|^T + a_dq/(U+2) |psi_d|^(U+2) |psi_q|^V
    """

    a_d0: float
    a_q0: float
    i_f: float
    a_dd: float = 0.0
    a_qq: float = 0.0
    a_dq: float = 0.0
    S: float = 2.0
    T: float = 2.0
    U: float = 1.0
    V: float = 0.0

    @classmethod
    def linear(cls, ld: float, lq: float, psi_pm: float) -> "SaturationModel":
        """Constant-parameter model psi_d = Ld i_d + psi_pm, psi_q = Lq i_q."""
        return cls(a_d0=1.0 / ld, a_q0=1.0 / lq, i_f=psi_pm / ld)

    @classmethod
    def from_mapping(cls, m: dict) -> "SaturationModel":
        names = {f.name for f in fields(cls)}
        unknown = set(m) - names
        if unknown:
            raise ValueError(f"unknown saturation parameter(s): {', '.join(sorted(unknown))}")
        missing = {"a_d0", "a_q0", "i_f"} - set(m)
        if missing:
            raise ValueError(f"missing saturation parameter(s): {', '.join(sorted(missing))}")
        return cls(**{k: float(v) for k, v in m.items()})

    # -- current map and its Jacobian -------------------------------------------------
    def current(self, psi_d, psi_q):
        """i_dq(psi_dq); broadcasts over arrays."""
        pd = np.abs(np.asarray(psi_d, dtype=float))
        pq = np.abs(np.asarray(psi_q, dtype=float))
        g_d = self.a_d0 + self.a_dd * pd**self.S + self.a_dq / (self.V + 2) * pd**self.U * pq ** (self.V + 2)
        g_q = self.a_q0 + self.a_qq * pq**self.T + self.a_dq / (self.U + 2) * pd ** (self.U + 2) * pq**self.V
        return g_d * np.asarray(psi_d, dtype=float) - self.i_f, g_q * np.asarray(psi_q, dtype=float)

    def jacobian(self, psi_d, psi_q):
        """(di_d/dpsi_d, di_d/dpsi_q = di_q/dpsi_d, di_q/dpsi_q).

        Inverse differential inductances. The off-diagonal is returned once because the
        model derives from an energy function, so it is symmetric by construction.
        """
        psi_d = np.asarray(psi_d, dtype=float)
        psi_q = np.asarray(psi_q, dtype=float)
        pd, pq = np.abs(psi_d), np.abs(psi_q)
        S, T, U, V = self.S, self.T, self.U, self.V
        g_dd = (self.a_d0 + (S + 1) * self.a_dd * pd**S
                + (U + 1) * self.a_dq / (V + 2) * pd**U * pq ** (V + 2))
        g_qq = (self.a_q0 + (T + 1) * self.a_qq * pq**T
                + (V + 1) * self.a_dq / (U + 2) * pd ** (U + 2) * pq**V)
        g_dq = self.a_dq * np.sign(psi_d) * np.sign(psi_q) * pd ** (U + 1) * pq ** (V + 1)
        return g_dd, g_dq, g_qq

    def energy(self, psi_d, psi_q):
        """Magnetic energy minus magnet term; its gradient is i_dq (used to test reciprocity)."""
        pd = np.abs(np.asarray(psi_d, dtype=float))
        pq = np.abs(np.asarray(psi_q, dtype=float))
        S, T, U, V = self.S, self.T, self.U, self.V
        return (0.5 * self.a_d0 * pd**2 + self.a_dd * pd ** (S + 2) / (S + 2)
                + 0.5 * self.a_q0 * pq**2 + self.a_qq * pq ** (T + 2) / (T + 2)
                + self.a_dq / ((U + 2) * (V + 2)) * pd ** (U + 2) * pq ** (V + 2)
                - self.i_f * np.asarray(psi_d, dtype=float))

    # -- flux map by inversion ----------------------------------------------------------
    def flux(self, i_d, i_q, *, tol: float = 1e-10, max_iter: int = 60):
        """psi_dq(i_dq) by damped Newton on the current map; broadcasts over arrays.

        Raises RuntimeError if some point does not converge (far outside the fitted range
        the energy function may stop being convex and there is no unique solution).
        """
        i_d, i_q = np.broadcast_arrays(np.asarray(i_d, dtype=float), np.asarray(i_q, dtype=float))
        # Start from the small-signal linearisation at i = 0: it is close over the
        # whole rated range, so Newton rarely needs damping.
        pd0 = self._psi_pm_newton()
        g_dd0, _, g_qq0 = self.jacobian(pd0, 0.0)
        psi_d = pd0 + i_d / g_dd0
        psi_q = i_q / g_qq0
        scale = max(abs(self.i_f), 1.0)
        for _ in range(max_iter):
            e_d, e_q = self.current(psi_d, psi_q)
            e_d, e_q = e_d - i_d, e_q - i_q
            err = np.hypot(e_d, e_q)
            if np.all(err <= tol * scale):
                return psi_d, psi_q
            g_dd, g_dq, g_qq = self.jacobian(psi_d, psi_q)
            det = g_dd * g_qq - g_dq * g_dq
            step_d = -(g_qq * e_d - g_dq * e_q) / det
            step_q = -(-g_dq * e_d + g_dd * e_q) / det
            # Backtrack per point so one hard point does not slow the others.
            alpha = np.ones_like(psi_d)
            for _ in range(12):
                n_d, n_q = self.current(psi_d + alpha * step_d, psi_q + alpha * step_q)
                bad = np.hypot(n_d - i_d, n_q - i_q) > err
                if not np.any(bad):
                    break
                alpha = np.where(bad, alpha * 0.5, alpha)
            psi_d = psi_d + alpha * step_d
            psi_q = psi_q + alpha * step_q
        e_d, e_q = self.current(psi_d, psi_q)
        worst = float(np.max(np.hypot(e_d - i_d, e_q - i_q)))
        if worst > 1e3 * tol * scale:
            raise RuntimeError(f"flux inversion did not converge (residual {worst:.3g} A)")
        return psi_d, psi_q

    def _psi_pm_newton(self) -> float:
        """psi_d at i = 0 from the d-axis equation alone (psi_q = 0 decouples it)."""
        x = self.i_f / self.a_d0
        for _ in range(60):
            f = float(self.current(x, 0.0)[0])
            g = float(self.jacobian(x, 0.0)[0])
            dx = f / g
            x -= dx
            if abs(dx) < 1e-15 * max(abs(x), 1.0):
                break
        return x

    def psi_pm(self) -> float:
        return self._psi_pm_newton()

    def inductances(self, i_d, i_q):
        """Differential inductances (l_dd, l_dq, l_qq) = inverse Jacobian at psi(i)."""
        psi_d, psi_q = self.flux(i_d, i_q)
        g_dd, g_dq, g_qq = self.jacobian(psi_d, psi_q)
        det = g_dd * g_qq - g_dq * g_dq
        return g_qq / det, -g_dq / det, g_dd / det


def torque(pole_pairs: int, psi_d, psi_q, i_d, i_q):
    """Electromagnetic torque 1.5 p (psi_d i_q - psi_q i_d)."""
    return 1.5 * pole_pairs * (np.asarray(psi_d) * i_q - np.asarray(psi_q) * i_d)


@dataclass(frozen=True)
class MtpaPoint:
    current_a: float
    i_d: float
    i_q: float
    torque_nm: float
    psi_d: float
    psi_q: float

    @property
    def angle_deg(self) -> float:
        """Current angle from the d axis (90 deg = pure q-axis current)."""
        return math.degrees(math.atan2(self.i_q, self.i_d))


@dataclass(frozen=True)
class Machine:
    name: str
    pole_pairs: int
    rs_ohm: float
    psi_pm_wb: float
    ld_h: float
    lq_h: float
    model: SaturationModel
    inertia_kgm2: float = float("nan")
    friction_nms: float = float("nan")
    i_rated_peak_a: float = float("nan")
    torque_rated_nm: float = float("nan")
    vdc_nominal_v: float = float("nan")
    f_sample_hz: float = float("nan")
    extra: dict = field(default_factory=dict, compare=False, repr=False)

    def flux(self, i_d, i_q):
        return self.model.flux(i_d, i_q)

    def torque(self, i_d, i_q):
        psi_d, psi_q = self.model.flux(i_d, i_q)
        return torque(self.pole_pairs, psi_d, psi_q, i_d, i_q)

    def mtpa(self, current_a: float, *, grid: int = 181) -> MtpaPoint:
        """Maximum torque per ampere at peak current magnitude `current_a` (motoring).

        A coarse vectorised sweep of the current angle over [90, 180] deg followed by a
        golden-section refinement; the saturated torque-vs-angle curve is unimodal there.
        """
        betas = np.linspace(0.5 * math.pi, math.pi, grid)
        t = self.torque(current_a * np.cos(betas), current_a * np.sin(betas))
        k = int(np.argmax(t))
        lo, hi = betas[max(k - 1, 0)], betas[min(k + 1, grid - 1)]

        def f(b):
            return float(self.torque(current_a * math.cos(b), current_a * math.sin(b)))

        r = (math.sqrt(5.0) - 1.0) / 2.0
        a, b = lo, hi
        c, d = b - r * (b - a), a + r * (b - a)
        fc, fd = f(c), f(d)
        while b - a > 1e-9:
            if fc > fd:
                b, d, fd = d, c, fc
                c = b - r * (b - a)
                fc = f(c)
            else:
                a, c, fc = c, d, fd
                d = a + r * (b - a)
                fd = f(d)
        beta = 0.5 * (a + b)
        i_d, i_q = current_a * math.cos(beta), current_a * math.sin(beta)
        psi_d, psi_q = self.model.flux(i_d, i_q)
        return MtpaPoint(current_a, i_d, i_q,
                         float(torque(self.pole_pairs, psi_d, psi_q, i_d, i_q)),
                         float(psi_d), float(psi_q))

    def small_signal(self):
        """(psi_pm, Ld, Lq) of the model at i = 0 (a measured map: its central differences)."""
        if hasattr(self.model, "small_signal"):
            return self.model.small_signal()
        l_dd, _, l_qq = self.model.inductances(0.0, 0.0)
        return self.model.psi_pm(), float(l_dd), float(l_qq)

    def u_max(self, vdc: float | None = None) -> float:
        """Largest fundamental phase voltage (peak) of SVPWM: Vdc/sqrt(3)."""
        return (self.vdc_nominal_v if vdc is None else vdc) / math.sqrt(3.0)

    def base_speed_rpm(self, i_d: float = 0.0, i_q: float = 0.0, vdc: float | None = None) -> float:
        """Mechanical speed at which the steady-state voltage reaches u_max.

        Solves |Rs i + omega_e J psi| = u_max for omega_e >= 0 at the operating point
        (i_d, i_q); at i = 0 this is u_max / psi_pm.
        """
        psi_d, psi_q = (float(x) for x in self.model.flux(i_d, i_q))
        um = self.u_max(vdc)
        rd, rq = self.rs_ohm * i_d, self.rs_ohm * i_q
        # J psi = (-psi_q, psi_d)
        jd, jq = -psi_q, psi_d
        a = jd * jd + jq * jq
        b = 2.0 * (rd * jd + rq * jq)
        c = rd * rd + rq * rq - um * um
        disc = b * b - 4.0 * a * c
        if c > 0 or disc < 0:
            return 0.0
        omega_e = (-b + math.sqrt(disc)) / (2.0 * a)
        return omega_e / self.pole_pairs * 60.0 / (2.0 * math.pi)

    def inductance_ranges(self, current_a: float, n: int = 41, *, motoring: bool = True):
        """Ranges of l_dd and l_qq over |i| <= current_a on an n x n grid.

        motoring=True keeps the quadrant i_d <= 0, i_q >= 0 where MTPA and field weakening
        operate (the ranges machines.md quotes); positive i_d reaches the magnet-aided,
        more saturated part of the d axis, which only polarity detection visits.
        """
        ax = np.linspace(-current_a, current_a, n)
        i_d, i_q = np.meshgrid(ax, ax)
        inside = np.hypot(i_d, i_q) <= current_a * (1 + 1e-12)
        if motoring:
            inside &= (i_d <= 0) & (i_q >= 0)
        l_dd, _, l_qq = self.model.inductances(i_d[inside], i_q[inside])
        return (float(l_dd.min()), float(l_dd.max())), (float(l_qq.min()), float(l_qq.max()))


_REQUIRED = ("name", "pole_pairs", "rs_ohm", "psi_pm_wb", "ld_h", "lq_h")
_FROM_MAP = ("psi_pm_wb", "ld_h", "lq_h")   # may be omitted with a [flux_map]
_OPTIONAL = ("inertia_kgm2", "friction_nms", "i_rated_peak_a", "torque_rated_nm",
             "vdc_nominal_v", "f_sample_hz")


def machine_from_dict(d: dict, base_dir=None) -> Machine:
    """Build a Machine from a parsed preset (TOML) mapping.

    Without a [saturation] table the constant-parameter model (ld_h, lq_h, psi_pm_wb) is used; with
    a [flux_map] the measured map (mctools.fluxmap; its file relative to base_dir, the preset's
    folder), and psi_pm_wb, ld_h, lq_h default to the map's values at i = 0.
    """
    fmap = d.get("flux_map")
    if fmap is not None:
        from mctools.fluxmap import read_flux_map
        if "saturation" in d:
            raise ValueError("key 'flux_map': a preset gives either [saturation] or [flux_map], not both")
        if not isinstance(fmap, dict) or not isinstance(fmap.get("file"), str) or not fmap["file"]:
            raise ValueError("key 'flux_map.file': expected a non-empty string (the map's CSV file)")
        f = Path(fmap["file"])
        if not f.is_absolute():
            f = Path(base_dir or ".") / f
        model = read_flux_map(str(f))
        d = dict(d)
        for k, v in zip(_FROM_MAP, model.small_signal()):
            d.setdefault(k, v)
    missing = [k for k in _REQUIRED if k not in d]
    if missing:
        raise ValueError(f"preset lacks required key(s): {', '.join(missing)}")
    sat = d.get("saturation")
    if fmap is not None:
        pass
    elif sat is None:
        model = SaturationModel.linear(float(d["ld_h"]), float(d["lq_h"]), float(d["psi_pm_wb"]))
    elif isinstance(sat, dict):
        model = SaturationModel.from_mapping(sat)
    else:
        raise ValueError("preset key 'saturation' must be a table")
    known = set(_REQUIRED) | set(_OPTIONAL) | {"saturation", "flux_map"}
    return Machine(
        name=str(d["name"]),
        pole_pairs=int(d["pole_pairs"]),
        rs_ohm=float(d["rs_ohm"]),
        psi_pm_wb=float(d["psi_pm_wb"]),
        ld_h=float(d["ld_h"]),
        lq_h=float(d["lq_h"]),
        model=model,
        **{k: float(d[k]) for k in _OPTIONAL if k in d},
        extra={k: v for k, v in d.items() if k not in known},
    )
