"""`mctools sweep table7_1`: thesis Table 7.1, the mean |Step I error| of the linear (5.5) and
nonlinear (7.1) cost for m = 3, 4, 5 and the Step I phase-current peak in per unit of the rated
peak."""

from __future__ import annotations

import math
import sys
import tomllib
from pathlib import Path

from mctools.sweep.common import (
    Point, SweepInputError, add_angle_args, add_common_args, angle_dir_name, angle_list,
    check_common, distribution, f_toml, fmt, metric, number, parse_floats, parse_sets, run_points,
    sets_text, write_outputs,
)

# Thesis values quoted in the issue (experiments).
THESIS_TABLE7_1 = {3: (13.14, 12.5, 0.39), 4: (11.92, 10.27, 0.52), 5: (10.77, 7.15, 0.69)}
COSTS = ("linear", "nonlinear")


def parse_ints(text: str, what: str, lo: int, hi: int) -> list[int]:
    vals = parse_floats(text, what)
    for v in vals:
        if v != int(v) or not lo <= v <= hi:
            raise SweepInputError(f"{what}: {v:g} is not an integer in {lo}..{hi}")
    return [int(v) for v in vals]


def step1_peak_a(trace_path: Path, m: int, ts_s: float) -> float | None:
    """Largest |ia|, |ib|, |ic| of trace.csv over the Step I pulses: from the first row in state 4
    (INIT_POS) for 4 m + 4 periods. Step I (one direction) is V(x) m, V(~x) 2m, V(x) m; the
    currents of its last pulse end at row 4m + 3 and Step II's first current appears 6 rows later,
    so the window holds Step I only. Needs output.decimation = 1."""
    from mctools.trace import TraceError, load_trace

    try:
        tr = load_trace(trace_path)
    except TraceError:
        return None
    cols = ("state", "ia_a", "ib_a", "ic_a")
    if any(c not in tr for c in cols):
        return None
    t, state = tr.t, tr["state"]
    idx = [k for k in range(len(t)) if state[k] == 4]
    if not idx:
        return None
    t0 = t[idx[0]]
    t_end = t0 + (4 * m + 4) * ts_s + 0.5 * ts_s
    peak = None
    for k in range(idx[0], len(t)):
        if t[k] > t_end:
            break
        v = max(abs(tr["ia_a"][k]), abs(tr["ib_a"][k]), abs(tr["ic_a"][k]))
        if math.isfinite(v):
            peak = v if peak is None else max(peak, v)
    return peak


def scenario_value(scenario: Path, sets: tuple[str, ...], dotted: str, default):
    """The value of a scenario key as mcsim will see it: a --set wins over the file."""
    for s in reversed(sets):
        k, v = s.split("=", 1)
        if k.strip() == dotted:
            try:
                return tomllib.loads(f"x = {v}")["x"]
            except tomllib.TOMLDecodeError:
                return v.strip()
    node = tomllib.loads(scenario.read_text(encoding="utf-8"))
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return default
        node = node[part]
    return node


def rated_peak_a(scenario: Path, sets) -> tuple[float | None, str]:
    from mctools.preset import PresetError, load_preset

    name = scenario_value(scenario, sets, "machine.preset", "sun2016-ipm-5kw")
    try:
        i = load_preset(str(name)).i_rated_peak_a
    except (PresetError, OSError, ValueError) as exc:
        print(f"sweep table7_1: warning: preset {name}: {exc}; per unit from the metrics' "
              f"current_limit_a", file=sys.stderr)
        return None, str(name)
    return (i if math.isfinite(i) else None), str(name)


def summarize_table7_1(points: list[Point], ms: list[int], i_rated: float | None) -> dict:
    rows = {}
    for m in ms:
        row = {"m": m}
        for cost in COSTS:
            pts = [p for p in points if p.info["m"] == m and p.info["cost"] == cost]
            row[cost] = distribution([metric(p, "step1_err_deg") for p in pts],
                                     [p.info["theta0_deg"] for p in pts])
        pts = [p for p in points if p.info["m"] == m]
        peaks = [p.info.get("step1_peak_a") for p in pts]
        dist = distribution(peaks, [p.info["theta0_deg"] for p in pts])
        base = i_rated
        if base is None:  # the configured limit defaults to the rated peak
            base = next((number(metric(p, "current_limit_a")) for p in pts
                         if number(metric(p, "current_limit_a"))), None)
        row["peak_a"] = dist["max"]
        row["peak_mean_a"] = dist["mean"]
        row["peak_missing"] = dist["missing"]
        row["peak_pu"] = dist["max"] / base if base and dist["max"] is not None else None
        row["peak_mean_pu"] = dist["mean"] / base if base and dist["mean"] is not None else None
        row["thesis"] = dict(zip(("linear", "nonlinear", "peak_pu"), THESIS_TABLE7_1.get(m, ())))
        rows[m] = row
    return {"i_rated_peak_a": i_rated, "rows": [rows[m] for m in ms],
            "failed_runs": sum(1 for p in points if not p.ok)}


def table7_1_markdown(summary: dict, args, scenario, n_angles: int, preset: str) -> str:
    base = summary["i_rated_peak_a"]
    cmd = (f"mctools sweep table7_1 {scenario} --m {','.join(str(r['m']) for r in summary['rows'])}"
           f" {args.angles_text}" + (f" {sets_text(args.sets_)}" if args.sets_ else ""))
    lines = [f"### Table 7.1: Step I error, linear (5.5) vs nonlinear (7.1) cost", "",
             f"`{cmd}`: {n_angles} initial angles per (m, cost). Error = mean (max) of "
             f"|`step1_err_deg`| (Step I, modulo 180°). Peak = largest phase current at the sample "
             f"instants over the Step I pulses (from `trace.csv`; max over the angles, mean in "
             f"brackets), per unit of the rated peak "
             f"{f'{base:g} A' if base else '(current_limit_a)'} of `{preset}`.", "",
             "| m | linear: ours mean (max) | thesis | nonlinear: ours mean (max) | thesis "
             "| peak ours | p.u. ours (mean) | p.u. thesis |",
             "|---|---|---|---|---|---|---|---|"]
    for r in summary["rows"]:
        th = r["thesis"]
        cells = []
        for cost in COSTS:
            d = r[cost]
            miss = f", {d['missing']} null" if d["missing"] else ""
            cells.append(f"{fmt(d['abs_mean'], 2, '°')} ({fmt(d['abs_max'], 1, '°')}{miss})")
            cells.append(fmt(th.get(cost), 2, "°"))
        lines.append(f"| {r['m']} | " + " | ".join(cells)
                     + f" | {fmt(r['peak_a'], 2, ' A')} | {fmt(r['peak_pu'], 2)} "
                       f"({fmt(r['peak_mean_pu'], 2)}) | {fmt(th.get('peak_pu'), 2)} |")
    if summary["failed_runs"]:
        lines += ["", f"**{summary['failed_runs']} run(s) failed.**"]
    return "\n".join(lines)


def cmd_table7_1(args) -> int:
    scenario, mcsim = check_common(args)
    ms = parse_ints(args.m, "--m", 1, 16)
    args.angles_text = (f"--angles {args.angles}" if args.angles is not None else
                        f"--step-deg {15.0 if args.step_deg is None else args.step_deg:g}")
    angles = angle_list(args.step_deg, args.angles, 15.0)
    args.sets_ = parse_sets(args.set, ("mechanics.theta0_deg", "startup.step1_m",
                                       "startup.step1_cost", "startup.step1_dirs",
                                       "output.decimation", "output.trace"))
    ts = scenario_value(scenario, args.sets_, "control.ts_s", 1e-4)
    if isinstance(ts, bool) or not isinstance(ts, (int, float)) or ts <= 0:
        raise SweepInputError(f"control.ts_s: {ts!r} is not a positive number")
    out = Path(args.out or "out/sweep/table7_1")
    points = []
    for m in ms:
        for cost in COSTS:
            for a in angles:
                sets = (*args.sets_, "startup.init_pos=\"three_step\"", f"startup.step1_m={m}",
                        f"startup.step1_cost=\"{cost}\"", "output.decimation=1",
                        "output.trace=true", f"mechanics.theta0_deg={f_toml(a)}")
                points.append(Point(f"m={m} {cost} theta0={a:g}", sets,
                                    out / f"m{m}_{cost}" / angle_dir_name(a),
                                    {"m": m, "cost": cost, "theta0_deg": a}))
    run_points(points, mcsim, scenario, args.jobs, "table7_1")
    for p in points:
        p.info["step1_peak_a"] = step1_peak_a(p.dir / "trace.csv", p.info["m"], float(ts)) \
            if p.ok else None
    i_rated, preset = rated_peak_a(scenario, args.sets_)
    summary = summarize_table7_1(points, ms, i_rated)
    md = table7_1_markdown(summary, args, scenario, len(angles), preset)
    data = {"command": "table7_1", "scenario": str(scenario), "sets": list(args.sets_),
            "angles_deg": angles, "summary": summary,
            "runs": [{**p.info, "dir": str(p.dir), "error": p.error,
                      "step1_err_deg": metric(p, "step1_err_deg")} for p in points]}
    write_outputs(args, md, data)
    print(f"sweep table7_1: {len(points)} runs, {summary['failed_runs']} failed")
    return 1 if summary["failed_runs"] else 0


# ---------------------------------------------------------------------------------------------
# CLI

def add_parser(ssub) -> None:
    t = ssub.add_parser("table7_1", help="thesis Table 7.1: Step I error, linear vs nonlinear "
                                         "cost, for several m, and the current peak in p.u.")
    add_common_args(t, "out/sweep/table7_1")
    add_angle_args(t, 15.0)
    t.add_argument("--m", default="3,4,5", metavar="M,M,...",
                   help="Step I pulse lengths (default 3,4,5)")
    t.set_defaults(func=cmd_table7_1)
