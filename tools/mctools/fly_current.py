"""How much current a drive needs to take over a rotor that already turns (flying start).

Enabled at speed with the outputs off, the stator flux is the magnet's (i = 0). Above the speed
where omega_e psi_pm exceeds the inverter's voltage, the drive cannot hold that flux: it must
shrink it (negative d current) while the rotor turns on, and whatever it cannot counter shows as
current. This tool answers, for a preset, how small the peak of that current can be:

  floor   the smallest |i| of any steady state at that speed the linear modulation can hold,
          |Rs i + j omega_e psi(i)| <= margin Vdc / sqrt3 (a hard lower bound: the drive must end
          in such a state; grid over the flux plane, the preset's saturation model);
  search  the smallest peak |i| the cross-entropy method finds over voltage sequences (one vector
          per control period, the stator-frame vector held through the period as PWM does) that
          start from i = 0 (or --i0) and end, within the horizon, in a state the linear modulation can hold.
          The voltage is limited to the circle Vdc / sqrt3 ('circle': linear SVPWM, what the
          firmware's current loop allows) or, with direction-preserving overmodulation (the
          firmware's mc_svpwm scaling into the hexagon), to the hexagon ('hexagon'). A search
          finds an achievable peak, not a proof of the minimum: it is reported as the best of
          several seeds; the floor is the proof.

The machine is integrated in flux linkage like the simulator: d psi/dt = u - Rs i(psi) - j omega
psi in the rotor frame, i(psi) from the preset's saturation model (docs/machine-models.md).
SI units; speeds mechanical rpm on the command line, electrical rad/s inside.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from mctools.errors import InputError
from mctools.machine import Machine
from mctools.preset import load_preset

SQRT3 = math.sqrt(3.0)


class FlyCurrentInputError(InputError, ValueError):
    """A bad option value; the CLI turns it into exit status 2 with the option's name."""


def _hex_scale(ua, ub, vdc):
    """Factor that scales a stator-frame vector into the SVPWM hexagon, keeping its direction
    (mc_svpwm): the largest line-to-line voltage must not exceed Vdc."""
    a = ua
    b = -0.5 * ua + 0.5 * SQRT3 * ub
    c = -0.5 * ua - 0.5 * SQRT3 * ub
    span = np.maximum(np.maximum(a, b), c) - np.minimum(np.minimum(a, b), c)
    return np.where(span > vdc, vdc / np.maximum(span, 1e-30), 1.0)


def need_voltage(m: Machine, psi_d, psi_q, omega_e):
    """Steady-state voltage magnitude that holds the flux (psi_d, psi_q) at omega_e:
    |Rs i + j omega_e psi| (2.7) with d/dt = 0."""
    i_d, i_q = m.model.current(psi_d, psi_q)
    return np.hypot(m.rs_ohm * i_d - omega_e * psi_q, m.rs_ohm * i_q + omega_e * psi_d)


def floor_current(m: Machine, omega_e: float, u_hold: float, *, n: int = 801) -> float:
    """Smallest |i| of a steady state at omega_e that u_hold can hold (grid over the flux plane,
    refined once around the best cell)."""
    psi_pm = m.model.psi_pm()
    lo_d, hi_d, lo_q, hi_q = -psi_pm, 1.2 * psi_pm, -psi_pm, psi_pm
    best = math.inf
    for _ in range(3):
        pd, pq = np.meshgrid(np.linspace(lo_d, hi_d, n), np.linspace(lo_q, hi_q, n))
        ok = need_voltage(m, pd, pq, omega_e) <= u_hold
        if not ok.any():
            return math.inf
        i_d, i_q = m.model.current(pd[ok], pq[ok])
        mag = np.hypot(i_d, i_q)
        k = int(np.argmin(mag))
        best = min(best, float(mag[k]))
        sd, sq = 4 * (hi_d - lo_d) / n, 4 * (hi_q - lo_q) / n
        cd, cq = float(pd[ok][k]), float(pq[ok][k])
        lo_d, hi_d, lo_q, hi_q = cd - sd, cd + sd, cq - sq, cq + sq
    return best


def simulate(m: Machine, omega_e: float, vdc: float, ts: float, ang, mag, *, limit: str,
             i0=(0.0, 0.0), theta0: float = 0.0, substeps: int = 8):
    """Integrate a population of voltage sequences (rows) from the current i0 (rotor frame).

    ang, mag: (P, N) rotor-frame voltage angle [rad] and magnitude [V] at each period's start;
    the stator-frame vector is held through the period. Returns (peak |i|, end psi_d, psi_q)."""
    P, N = ang.shape
    psi_d0, psi_q0 = (float(x) for x in m.model.flux(float(i0[0]), float(i0[1])))
    pd = np.full(P, psi_d0)
    pq = np.full(P, psi_q0)
    peak = np.full(P, math.hypot(float(i0[0]), float(i0[1])))
    h = ts / substeps
    u_lin = vdc / SQRT3
    theta = theta0
    i_d, i_q = m.model.current(pd, pq)   # at the start of each sub-step (the last one's end)
    for k in range(N):
        # stator-frame vector for this period, limited as the inverter would
        a_s = theta + ang[:, k]
        ua, ub = mag[:, k] * np.cos(a_s), mag[:, k] * np.sin(a_s)
        if limit == "circle":
            s = np.minimum(1.0, u_lin / np.maximum(np.hypot(ua, ub), 1e-30))
        else:
            s = _hex_scale(ua, ub, vdc)
        ua, ub = ua * s, ub * s
        for _ in range(substeps):
            c, sn = math.cos(theta + 0.5 * omega_e * h), math.sin(theta + 0.5 * omega_e * h)
            ud, uq = c * ua + sn * ub, -sn * ua + c * ub                      # Park (2.5)
            # midpoint step of d psi/dt = u - Rs i - j omega psi
            kd = ud - m.rs_ohm * i_d + omega_e * pq
            kq = uq - m.rs_ohm * i_q - omega_e * pd
            md, mq = pd + 0.5 * h * kd, pq + 0.5 * h * kq
            i_d, i_q = m.model.current(md, mq)
            pd = pd + h * (ud - m.rs_ohm * i_d + omega_e * mq)
            pq = pq + h * (uq - m.rs_ohm * i_q - omega_e * md)
            theta += omega_e * h
            i_d, i_q = m.model.current(pd, pq)
            peak = np.maximum(peak, np.hypot(i_d, i_q))
    return peak, pd, pq


# the largest steady fundamental of direction-preserving overmodulation, / (Vdc/sqrt3): the
# hexagon's mean radius, (3/pi) 2 ln(sec 30 + tan 30) = (3/pi) ln 3
OM_FUND_MAX = 3.0 / math.pi * math.log(3.0)


def search_peak(m: Machine, omega_e: float, vdc: float, ts: float, *, limit: str, margin: float,
                horizon_s: float, seed: int, i0=(0.0, 0.0), theta0: float = 0.0, iterations: int = 120,
                population: int = 160, elite: int = 16) -> dict:
    """Cross-entropy search for the smallest peak |i| of a hand-over (module docstring)."""
    n = max(2, int(round(horizon_s / ts)))
    rng = np.random.default_rng(seed)
    u_lin = vdc / SQRT3
    u_hold = margin * u_lin
    s = 1.0 if omega_e >= 0.0 else -1.0
    # start: full voltage ahead of the back-EMF (q), leaning against the flux (-d)
    mu = np.concatenate([np.full(n, s * (0.5 * math.pi + 0.6)), np.full(n, 1.2 * u_lin)])
    sd = np.concatenate([np.full(n, 0.8), np.full(n, 0.4 * u_lin)])
    penalty = 1.0 / max(u_lin, 1e-9) * 100.0   # 1 A per 1 % of the link's voltage short at the end
    best = (math.inf, math.inf, None)
    for _ in range(iterations):
        x = mu + sd * rng.standard_normal((population, 2 * n))
        peak, pd, pq = simulate(m, omega_e, vdc, ts, x[:, :n], np.abs(x[:, n:]), limit=limit, i0=i0,
                                theta0=theta0)
        short = np.maximum(0.0, need_voltage(m, pd, pq, omega_e) - u_hold)
        cost = peak + penalty * short
        order = np.argsort(cost)
        k = int(order[0])
        if cost[k] < best[0]:
            best = (float(cost[k]), float(peak[k]), float(short[k]))
        e = x[order[:elite]]
        mu, sd = e.mean(axis=0), e.std(axis=0) + 1e-3
    return {"peak_a": best[1], "end_short_v": best[2], "cost": best[0]}


def fly_current(m: Machine, rpm: float, *, vdc: float, ts: float, limits, margin: float,
                horizon_s: float, seeds: int, i0=(0.0, 0.0), theta0: float = 0.0) -> dict:
    """One speed's row: the floor and, per voltage limit, the best searched peak (module
    docstring); every search is 0 A where the magnet's flux can be held from i = 0."""
    omega_e = rpm / 60.0 * 2.0 * math.pi * m.pole_pairs
    u_lin = vdc / SQRT3
    row = {"rpm": rpm, "omega_e": omega_e, "vdc_v": vdc,
           "magnet_voltage_v": abs(omega_e) * m.model.psi_pm(),
           "u_linear_v": u_lin,
           "floor_a": floor_current(m, abs(omega_e), margin * u_lin),
           "i_max_a": m.i_rated_peak_a, "i0_dq_a": [float(i0[0]), float(i0[1])],
           "theta0_deg": math.degrees(theta0)}
    if row["magnet_voltage_v"] <= margin * u_lin and i0[0] == 0.0 and i0[1] == 0.0:
        # the magnet's flux can be held as it is: no current is needed at all
        for lim in limits:
            row[f"search_{lim}_a"] = 0.0
        return row
    for lim in limits:
        runs = [search_peak(m, omega_e, vdc, ts, limit=lim, margin=margin, horizon_s=horizon_s,
                            seed=k, i0=i0, theta0=theta0) for k in range(seeds)]
        ok = [r for r in runs if r["end_short_v"] <= 0.01 * u_lin]
        row[f"search_{lim}_a"] = min(r["peak_a"] for r in ok) if ok else math.nan
    return row


def _floats(text: str, key: str) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise FlyCurrentInputError(f"{key}: {text!r} is not a comma-separated list of numbers") from None
    if not vals or not all(math.isfinite(v) for v in vals):
        raise FlyCurrentInputError(f"{key}: {text!r}: give finite numbers")
    return vals


def _cmd(args) -> int:
    m = load_preset(args.preset, args.preset_dir)
    if not hasattr(m.model, "current"):   # a measured map gives psi(i), this integrates i(psi)
        raise FlyCurrentInputError(f"{args.preset}: a measured-map preset ([flux_map]) is not supported here: "
                                   "fly-current needs the closed-form current map of a [saturation] preset")
    rpms = _floats(args.rpm, "--rpm")
    limits = [s.strip() for s in args.limit.split(",") if s.strip()]
    bad = [s for s in limits if s not in ("circle", "hexagon")]
    if bad or not limits:
        raise FlyCurrentInputError(f"--limit: {args.limit!r}: choose from circle, hexagon")
    vdc = m.vdc_nominal_v if args.vdc is None else args.vdc
    if not (math.isfinite(vdc) and vdc > 0):
        raise FlyCurrentInputError(f"--vdc: {vdc} V: must be > 0 (or the preset's vdc_nominal_v)")
    ts = 1.0 / m.f_sample_hz if args.ts is None else args.ts
    if not (math.isfinite(ts) and 1e-6 <= ts <= 1e-2):
        raise FlyCurrentInputError(f"--ts: {ts} s: must be in 1e-6 .. 1e-2")
    if not (0.5 <= args.margin <= OM_FUND_MAX):
        raise FlyCurrentInputError(f"--margin: {args.margin}: must be in 0.5 .. {OM_FUND_MAX:.4f} "
                                 "(above 1 the end state needs overmodulation)")
    if not (0.2 <= args.horizon_ms <= 20.0):
        raise FlyCurrentInputError(f"--horizon-ms: {args.horizon_ms}: must be in 0.2 .. 20")
    if not (1 <= args.seeds <= 20):
        raise FlyCurrentInputError(f"--seeds: {args.seeds}: must be in 1 .. 20")
    i0 = _floats(args.i0, "--i0")
    if len(i0) != 2:
        raise FlyCurrentInputError(f"--i0: {args.i0!r}: give i_d,i_q in A")
    if not math.isfinite(args.theta0_deg):
        raise FlyCurrentInputError(f"--theta0-deg: {args.theta0_deg}: give a finite angle")
    rows = []
    for r in rpms:
        print(f"mctools fly-current: {m.name} at {r:g} rpm ...", file=sys.stderr, flush=True)
        rows.append(fly_current(m, r, vdc=vdc, ts=ts, limits=limits, margin=args.margin,
                                horizon_s=1e-3 * args.horizon_ms, seeds=args.seeds, i0=i0,
                                theta0=math.radians(args.theta0_deg)))
    if args.json:
        print(json.dumps({"preset": m.name, "rows": rows}, indent=1))
        return 0
    head = "| speed [rpm] | omega psi_pm [V] | linear limit [V] | floor [A] | " + \
        " | ".join(f"search, {lim} [A]" for lim in limits) + " | i_max [A] |"
    print(f"{m.name}, Vdc {vdc:g} V, control period {ts * 1e6:g} us, hold margin {args.margin:g}, "
          f"horizon {args.horizon_ms:g} ms, {args.seeds} seeds, start current (i_d, i_q) = "
          f"({i0[0]:g}, {i0[1]:g}) A, rotor at {args.theta0_deg:g} deg el from phase a")
    print(head)
    print("|" + "---:|" * (head.count("|") - 1))
    for row in rows:
        cells = [f"{row['rpm']:g}", f"{row['magnet_voltage_v']:.0f}", f"{row['u_linear_v']:.0f}",
                 f"{row['floor_a']:.2f}"] + [f"{row[f'search_{lim}_a']:.2f}" for lim in limits] + \
                [f"{row['i_max_a']:.2f}"]
        print("| " + " | ".join(cells) + " |")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("fly-current", help="the smallest peak current of taking over a turning "
                       "rotor (flying start): steady-state floor and a searched voltage sequence",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("preset", metavar="NAME|PATH", help="preset name (presets/<name>.toml) or file")
    p.add_argument("--preset-dir", metavar="DIR", help="directory to look up preset names in")
    p.add_argument("--rpm", default="900,1200,1500", help="mechanical speeds, comma-separated "
                   "(default 900,1200,1500)")
    p.add_argument("--vdc", type=float, help="DC link [V] (default: the preset's vdc_nominal_v)")
    p.add_argument("--ts", type=float, help="control period [s] (default: 1 / the preset's "
                   "f_sample_hz)")
    p.add_argument("--limit", default="circle,hexagon", help="voltage limits to search with: "
                   "circle (linear SVPWM), hexagon (overmodulation); default both")
    p.add_argument("--margin", type=float, default=1.0, help="share of Vdc/sqrt3 the end state "
                   "must be holdable with (default 1)")
    p.add_argument("--horizon-ms", type=float, default=3.0, help="time allowed to reach a "
                   "holdable state [ms] (default 3)")
    p.add_argument("--seeds", type=int, default=3, help="independent searches; the best counts "
                   "(default 3)")
    p.add_argument("--i0", default="0,0", help="current at the hand-over's start, i_d,i_q [A] in "
                   "the rotor frame (default 0,0: the outputs were off; a catch pulse leaves "
                   "some, mostly -q for a positive speed)")
    p.add_argument("--theta0-deg", type=float, default=0.0, help="rotor angle at the start, "
                   "electrical degrees from phase a (default 0). With the hexagon it matters: the "
                   "voltage that shrinks the flux keeps about one stator direction, a corner or a "
                   "side; on the thesis motor at 1500 rpm from (-0.7, -3) A the search gives 12.2 A "
                   "at -135 deg and 13.6 A at -165 deg (period 60 deg)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p.set_defaults(func=_cmd)
