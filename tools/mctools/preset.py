"""Locating and reading machine preset files (TOML), and the `preset` report."""

from __future__ import annotations

import json
import math
import os
import tomllib

import numpy as np
from pathlib import Path

from mctools.errors import InputError
from mctools.machine import Machine, machine_from_dict


class PresetError(InputError):
    """Preset not found or malformed; the CLI turns it into exit status 2."""


def search_dirs(preset_dir=None) -> list[Path]:
    """Where a preset name is looked up, in order."""
    dirs = []
    if preset_dir:
        dirs.append(Path(preset_dir))
    env = os.environ.get("MC_PRESET_DIR")
    if env:
        dirs.append(Path(env))
    # Editable install / source checkout: tools/mctools/preset.py -> <repo>/presets
    dirs.append(Path(__file__).resolve().parents[2] / "presets")
    dirs.append(Path.cwd() / "presets")
    seen, out = set(), []
    for d in dirs:
        key = d.resolve() if d.exists() else d
        if key not in seen:
            seen.add(key)
            out.append(d)
    return out


def find_preset(name_or_path: str, preset_dir=None) -> Path:
    p = Path(name_or_path)
    looks_like_path = p.suffix == ".toml" or os.sep in name_or_path or "/" in name_or_path
    if p.is_file():
        return p
    if looks_like_path:
        raise PresetError(f"{name_or_path}: no such preset file")
    dirs = search_dirs(preset_dir)
    for d in dirs:
        cand = d / f"{name_or_path}.toml"
        if cand.is_file():
            return cand
    raise PresetError(f"preset '{name_or_path}' not found; looked in: "
                      + ", ".join(str(d) for d in dirs))


def load_preset(name_or_path: str, preset_dir=None) -> Machine:
    path = find_preset(name_or_path, preset_dir)
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"{path}: invalid TOML: {exc}") from None
    try:
        return machine_from_dict(data, base_dir=path.parent)
    except (ValueError, TypeError) as exc:
        raise PresetError(f"{path}: {exc}") from None


FS_RANGE_HZ = (2000.0, 20000.0)   # control.ts_s's range (the parameter table)
FS_PULSE_RATIO = 20.0             # samples a period at the no-load base speed, sensorless
FS_PULSE_RATIO_SENSOR = 6.0       # ... with an angle sensor (drive_config.c, check_sampling)


def fs_min_hz(m: Machine, sensorless: bool = True) -> float:
    """The drive's lowest sampling rate for this motor on default keys (check_sampling in
    firmware/app/drive_config.c, docs/parameters.md "The lowest sampling rate"): 20 samples
    (sensorless; 6 with an angle sensor) a period of the electrical frequency at the no-load base
    speed Vdc / (sqrt3 psi_pm). The injection's 4 samples a period hold by its own rule
    (min(500 Hz, f_s / 4)). NaN without Vdc."""
    f_el = m.vdc_nominal_v / math.sqrt(3.0) / (2.0 * math.pi * m.psi_pm_wb)
    return (FS_PULSE_RATIO if sensorless else FS_PULSE_RATIO_SENSOR) * f_el


def derived_figures(m: Machine) -> dict:
    """Figures derived from the model, for the `preset` report and for tests."""
    psi_pm, ld, lq = m.small_signal()
    out = {
        "name": m.name,
        "pole_pairs": m.pole_pairs,
        "psi_pm_model_wb": psi_pm,
        "psi_pm_preset_wb": m.psi_pm_wb,
        "ld_model_h": ld,
        "ld_preset_h": m.ld_h,
        "lq_model_h": lq,
        "lq_preset_h": m.lq_h,
    }
    fm = getattr(m.model, "recip_rms", None)
    if fm is not None:
        mp = m.model
        out.update({
            "flux_map_file": mp.file,
            "flux_map_grid": [mp.x.n, mp.y.n],
            "flux_map_i_d_range_a": [mp.x.lo, mp.x.hi],
            "flux_map_i_q_range_a": [mp.y.lo, mp.y.hi],
            "flux_map_ldq_h": mp.ldq,
            "flux_map_reciprocity_rms": mp.recip_rms,
            "flux_map_reciprocity_max": mp.recip_max,
            "flux_map_reciprocity_max_at_a": list(mp.recip_max_at),
            "flux_map_warnings": list(mp.warnings),
        })
    if math.isfinite(m.vdc_nominal_v):
        out["vdc_nominal_v"] = m.vdc_nominal_v
        out["u_max_v"] = m.u_max()
        out["base_speed_noload_rpm"] = m.base_speed_rpm()
        out["fs_min_hz"] = fs_min_hz(m)
        out["fs_min_sensor_hz"] = fs_min_hz(m, sensorless=False)
    if math.isfinite(m.i_rated_peak_a):
        p = m.mtpa(m.i_rated_peak_a)
        out.update({
            "i_rated_peak_a": m.i_rated_peak_a,
            "mtpa_id_a": p.i_d,
            "mtpa_iq_a": p.i_q,
            "mtpa_angle_deg": p.angle_deg,
            "mtpa_torque_nm": p.torque_nm,
            "mtpa_psi_d_wb": p.psi_d,
            "mtpa_psi_q_wb": p.psi_q,
        })
        if math.isfinite(m.torque_rated_nm):
            out["torque_rated_nm"] = m.torque_rated_nm
        if math.isfinite(m.vdc_nominal_v):
            out["base_speed_mtpa_rated_rpm"] = m.base_speed_rpm(p.i_d, p.i_q)
        (ldd_lo, ldd_hi), (lqq_lo, lqq_hi) = m.inductance_ranges(m.i_rated_peak_a)
        out.update({"l_dd_min_h": ldd_lo, "l_dd_max_h": ldd_hi,
                    "l_qq_min_h": lqq_lo, "l_qq_max_h": lqq_hi})
    return out


def format_report(f: dict, source: Path | None = None) -> str:
    def mh(x):
        return f"{x * 1e3:.4g} mH"

    def dev(model, preset):
        return f"({100.0 * (model / preset - 1.0):+.2f} % vs preset)" if preset else ""

    kind = "saturation model"
    if "flux_map_file" in f:
        kind = "flux map, central differences"
    lines = [f"preset {f['name']}" + (f"  [{source}]" if source else ""),
             f"  pole pairs                 {f['pole_pairs']}"]
    if "flux_map_file" in f:
        (d_lo, d_hi), (q_lo, q_hi) = f["flux_map_i_d_range_a"], f["flux_map_i_q_range_a"]
        lines += [f"  measured flux map          {f['flux_map_file']}",
                  f"    grid                     {f['flux_map_grid'][0]} x {f['flux_map_grid'][1]}, "
                  f"i_d {d_lo:g} .. {d_hi:g} A, i_q {q_lo:g} .. {q_hi:g} A",
                  f"    reciprocity mismatch     rms {100 * f['flux_map_reciprocity_rms']:.2f} %, max "
                  f"{100 * f['flux_map_reciprocity_max']:.2f} % at ({f['flux_map_reciprocity_max_at_a'][0]:g}, "
                  f"{f['flux_map_reciprocity_max_at_a'][1]:g}) A  (|l_dq - l_qd| / sqrt(l_dd l_qq))"]
        lines += [f"    warning: {w}" for w in f["flux_map_warnings"]]
    lines += [f"  small-signal at i = 0 ({kind}):",
             f"    psi_pm                   {f['psi_pm_model_wb']:.5f} Wb "
             f"{dev(f['psi_pm_model_wb'], f['psi_pm_preset_wb'])}",
             f"    Ld                       {mh(f['ld_model_h'])} {dev(f['ld_model_h'], f['ld_preset_h'])}",
             f"    Lq                       {mh(f['lq_model_h'])} {dev(f['lq_model_h'], f['lq_preset_h'])}"]
    if "flux_map_ldq_h" in f:
        lines.append(f"    Ldq (d psi_d / d i_q)    {mh(f['flux_map_ldq_h'])}")
    if "u_max_v" in f:
        lines += [f"  at Vdc = {f['vdc_nominal_v']:g} V (u_max = Vdc/sqrt(3) = {f['u_max_v']:.1f} V):",
                  f"    no-load base speed       {f['base_speed_noload_rpm']:.0f} rpm"]
        lo, hi = FS_RANGE_HZ
        for key, what, k in (("fs_min_hz", "sensorless", FS_PULSE_RATIO),
                             ("fs_min_sensor_hz", "with a sensor", FS_PULSE_RATIO_SENSOR)):
            fs = f[key]
            note = ("" if lo <= fs <= hi else "; below the range: 2 kHz" if fs < lo
                    else "; above the 20 kHz range: every f_s refused")
            lines.append(f"    lowest sampling rate     {fs / 1e3:.3g} kHz {what}  ({k:g} x the electrical "
                         f"frequency at the no-load base speed; control.ts_s <= {1e6 / max(fs, lo):.4g} us"
                         f"{note})")
    if "mtpa_torque_nm" in f:
        rated = (f"  (preset rated {f['torque_rated_nm']:g} N m)" if "torque_rated_nm" in f else "")
        lines += [f"  MTPA at rated {f['i_rated_peak_a']:g} A peak:",
                  f"    torque                   {f['mtpa_torque_nm']:.2f} N m{rated}",
                  f"    i_d, i_q                 {f['mtpa_id_a']:.2f} A, {f['mtpa_iq_a']:.2f} A "
                  f"(angle {f['mtpa_angle_deg']:.1f} deg from d)",
                  f"    psi_d, psi_q             {f['mtpa_psi_d_wb']:.4f} Wb, {f['mtpa_psi_q_wb']:.4f} Wb",
                  f"  differential inductances, i_d <= 0, i_q >= 0, |i| <= {f['i_rated_peak_a']:g} A:",
                  f"    l_dd                     {mh(f['l_dd_min_h'])} .. {mh(f['l_dd_max_h'])}",
                  f"    l_qq                     {mh(f['l_qq_min_h'])} .. {mh(f['l_qq_max_h'])}"]
    return "\n".join(lines)


def export_map(m: Machine, out, points: int, span_a: float | None) -> str:
    """Tabulate the preset's model psi(i) on a points x points grid over +-span_a (default
    1.5 x i_rated_peak_a) and write it as a measured-map CSV (`[flux_map] file = ...`)."""
    from mctools.fluxmap import write_flux_map
    if points < 3:
        raise PresetError(f"--export-points {points}: a map needs at least 3 points per axis")
    span = span_a if span_a is not None else 1.5 * m.i_rated_peak_a
    if not (math.isfinite(span) and span > 0):
        raise PresetError("--export-span: give a positive span (the preset has no i_rated_peak_a)")
    axis = np.linspace(-span, span, points)
    axis[points // 2] = 0.0 if points % 2 else axis[points // 2]   # exact i = 0 on odd grids
    n = write_flux_map(out, axis, axis, m.model.flux)
    return f"wrote {out}: {points} x {points} grid, i_d, i_q in +-{span:g} A ({n} rows)"


def cmd_preset(args) -> int:
    path = find_preset(args.preset, args.preset_dir)
    if args.export_map:
        print(export_map(load_preset(str(path)), args.export_map, args.export_points, args.export_span))
        return 0
    figs = derived_figures(load_preset(str(path)))
    if args.json:
        print(json.dumps(figs, indent=2))
    else:
        print(format_report(figs, path))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("preset", help="print figures derived from a machine preset")
    p.add_argument("preset", metavar="NAME|PATH", help="preset name (presets/<name>.toml) or file")
    p.add_argument("--preset-dir", metavar="DIR",
                   help="directory to look up preset names in (also: env MC_PRESET_DIR)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--export-map", metavar="FILE",
                   help="write the preset's flux map psi(i) as a CSV for a [flux_map] preset and exit")
    p.add_argument("--export-points", metavar="N", type=int, default=41,
                   help="grid points per axis of --export-map (default 41)")
    p.add_argument("--export-span", metavar="A", type=float,
                   help="--export-map grid half-width [A] (default 1.5 x i_rated_peak_a)")
    p.set_defaults(func=cmd_preset)
