"""`mctools sweep`: initial-position studies of thesis ch. 5 / 7.2 run with mcsim.

* `angles`   one run per initial angle (mechanics.theta0_deg): per-angle table and distribution
             of the startup metrics (step1_err_deg, step12_err_deg, polarity_correct,
             init_pos_err_deg, init_pos_time_s, ...); optional pass/fail flags (exit 1).
* `table7_1` thesis Table 7.1: mean |Step I error| of the linear (5.5) and nonlinear (7.1) cost
             for m = 3, 4, 5 and the Step I phase-current peak in per unit of the rated peak.
* `noise`    thesis Fig. 7.4: Step II polarity decisions (generalized vs DVI) over many seeded
             trials with random initial angles, per current-noise level.
* `seeds`    one scenario over scenario.seed = 1..N: median, p5/p10/p90/p95, min/max of every
             numeric metric; on the local cores or on a Dask distributed cluster (--scheduler).
* `envelope` the robustness envelope of sensorless control: estimator parameter errors (one at a
             time) x scenarios, each cell over seeds 1..N, classified holds / trips / runs off.

Every number comes from the metrics.json (and, for the Step I current peak, the trace.csv) of
`mcsim run` processes, `--jobs` at a time. Results are printed as markdown and can be written as
JSON (`--json`) and markdown (`--md`).
"""

from __future__ import annotations

import json
import math
import os
import random
import subprocess
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from mctools.report import ReportInputError, _clear_outputs, find_mcsim, read_metrics, run_mcsim

DASH = "—"
# Thesis values quoted in the issue (experiments).
THESIS_ANGLES = {"step12_err_deg": "exp. mean 11.52°", "init_pos_err_mean_deg": "exp. mean 0.91°",
                 "step12_time_s": "4.1 ms (Step I + II only)"}
THESIS_TABLE7_1 = {3: (13.14, 12.5, 0.39), 4: (11.92, 10.27, 0.52), 5: (10.77, 7.15, 0.69)}
COSTS = ("linear", "nonlinear")
METHODS = ("generalized", "dvi")
ANGLE_METRICS = (  # (metric, what) of the distribution table
    ("step1_err_deg", "Step I error (mod 180°)"),
    ("step12_err_deg", "pulse-only error (after Step II)"),
    ("init_pos_err_deg", "error at the hand-over sample (Step III → RUN)"),
    ("init_pos_err_mean_deg", "final error (mean over 20 ms after the hand-over)"),
    ("init_pos_time_s", "enable to < 1°"),
    ("step12_time_s", "enable → Step III (offset cal. + Step I + II)"),
    ("reverse_angle_max_deg", "reverse rotation"),
)


class SweepInputError(ReportInputError):
    """Bad arguments or scenario; the CLI turns it into exit status 2 (as ReportInputError)."""


# ---------------------------------------------------------------------------------------------
# Argument helpers

def parse_floats(text: str, what: str) -> list[float]:
    out = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            v = float(part)
        except ValueError:
            raise SweepInputError(f"{what}: {part!r} is not a number") from None
        if not math.isfinite(v):
            raise SweepInputError(f"{what}: {part!r} is not finite")
        out.append(v)
    if not out:
        raise SweepInputError(f"{what}: empty list")
    if len(set(out)) != len(out):
        raise SweepInputError(f"{what}: duplicate value in {text!r}")
    return out


def parse_ints(text: str, what: str, lo: int, hi: int) -> list[int]:
    vals = parse_floats(text, what)
    for v in vals:
        if v != int(v) or not lo <= v <= hi:
            raise SweepInputError(f"{what}: {v:g} is not an integer in {lo}..{hi}")
    return [int(v) for v in vals]


def angle_list(step_deg: float | None, angles: str | None, default_step: float) -> list[float]:
    if angles is not None:
        vals = parse_floats(angles, "--angles")
        bad = [v for v in vals if not -360.0 <= v <= 360.0]
        if bad:
            raise SweepInputError(f"--angles: {bad[0]:g} is outside -360..360 deg")
        return vals
    step = default_step if step_deg is None else step_deg
    if not (math.isfinite(step) and 0.0 < step <= 360.0):
        raise SweepInputError(f"--step-deg must be in (0, 360], got {step:g}")
    n = math.ceil(360.0 / step - 1e-9)
    return [round(k * step, 9) for k in range(n)]


def parse_sets(sets: list[str] | None, reserved: tuple[str, ...]) -> tuple[str, ...]:
    out = []
    for s in sets or []:
        k = s.split("=", 1)[0].strip()
        if "=" not in s or not k:
            raise SweepInputError(f"--set {s!r} is not key=value")
        if k in reserved:
            raise SweepInputError(f"--set {k}: this command sets it itself")
        out.append(s)
    return tuple(out)


def check_common(args) -> tuple[Path, str]:
    if args.jobs < 1:
        raise SweepInputError("--jobs must be at least 1")
    scenario = Path(args.scenario)
    if not scenario.is_file():
        raise SweepInputError(f"{scenario}: no such scenario file")
    try:
        tomllib.loads(scenario.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SweepInputError(f"{scenario}: not valid TOML: {exc}") from None
    return scenario, find_mcsim(args.mcsim)


def f_toml(v: float) -> str:
    """A float as a TOML float literal (mcsim reads --set values as TOML)."""
    return repr(float(v))


# ---------------------------------------------------------------------------------------------
# Runs

@dataclass
class Point:
    label: str
    sets: tuple[str, ...]
    dir: Path
    info: dict = field(default_factory=dict)  # the swept values (recorded in the JSON)
    exit_code: int | None = None
    seconds: float = 0.0
    metrics: dict | None = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


def execute(p: Point, mcsim: str, scenario: Path) -> Point:
    try:
        p.dir.mkdir(parents=True, exist_ok=True)
        _clear_outputs(p.dir)
    except OSError as exc:
        p.error = f"run failed ({exc.strerror or exc})"
        return p
    p.exit_code, log, p.seconds, cmd = run_mcsim(mcsim, Path(scenario), p.sets, p.dir)
    if p.exit_code != 0:
        (p.dir / "mcsim.log").write_text(" ".join(cmd) + "\n" + log, encoding="utf-8")
        p.error = f"run failed (exit {p.exit_code})"
        return p
    p.metrics, p.error = read_metrics(p.dir)
    return p


def run_points(points: list[Point], mcsim: str, scenario: Path, jobs: int, prefix: str) -> None:
    """Runs every point, `jobs` mcsim processes at a time, with progress lines (every run up to
    200 runs, else about every 2 %, and every failure)."""
    n = len(points)
    every = 1 if n <= 200 else max(1, n // 50)
    done, t0 = 0, time.monotonic()
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(execute, p, mcsim, scenario) for p in points]
        for fut in as_completed(futures):
            p = fut.result()
            done += 1
            if not p.ok:
                print(f"[{done}/{n}] {prefix} {p.label} ... {p.error}", flush=True)
                log = p.dir / "mcsim.log"
                if log.is_file():
                    for ln in log.read_text(encoding="utf-8", errors="replace").splitlines()[-3:]:
                        print(f"    {ln}", file=sys.stderr)
            elif done % every == 0 or done == n:
                if every == 1:
                    print(f"[{done}/{n}] {prefix} {p.label} ... {p.seconds:.2f} s", flush=True)
                else:
                    print(f"[{done}/{n}] {prefix} ... {time.monotonic() - t0:.0f} s elapsed",
                          flush=True)


# ---------------------------------------------------------------------------------------------
# Numbers

def number(v) -> float | None:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def metric(p: Point, key: str):
    return None if p.metrics is None else p.metrics.get(key)


def distribution(values: list, labels: list | None = None) -> dict:
    """mean, mean abs, max abs (with where), min, max, std of the finite numbers; `missing`
    counts nulls, absent keys and failed runs."""
    pairs = [(number(v), labels[i] if labels else i) for i, v in enumerate(values)]
    xs = [(v, lab) for v, lab in pairs if v is not None]
    d = {"n": len(xs), "missing": len(values) - len(xs)}
    if not xs:
        d.update(mean=None, abs_mean=None, abs_max=None, abs_max_at=None, min=None, max=None,
                 std=None)
        return d
    vals = [v for v, _ in xs]
    mean = sum(vals) / len(vals)
    worst = max(xs, key=lambda x: abs(x[0]))
    d.update(mean=mean, abs_mean=sum(abs(v) for v in vals) / len(vals), abs_max=abs(worst[0]),
             abs_max_at=worst[1], min=min(vals), max=max(vals),
             std=math.sqrt(sum((v - mean) ** 2 for v in vals) / len(vals)))
    return d


def fmt(v, digits: int = 2, unit: str = "") -> str:
    if v is None:
        return DASH
    if isinstance(v, bool):
        return "yes" if v else "**no**"
    return f"{v:.{digits}f}{unit}"


def fmt_ms(v) -> str:
    return DASH if v is None else f"{1e3 * v:.1f} ms"


def sets_text(sets) -> str:
    return " ".join(f"--set {s}" for s in sets)


def write_outputs(args, md: str, data: dict) -> None:
    print(md)
    if args.md:
        Path(args.md).parent.mkdir(parents=True, exist_ok=True)
        Path(args.md).write_text(md + "\n", encoding="utf-8")
        print(f"wrote {args.md}")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")


def angle_dir_name(a: float) -> str:
    return f"theta_{a:+08.3f}".replace(".", "p")


# ---------------------------------------------------------------------------------------------
# angles

def summarize_angles(points: list[Point]) -> dict:
    labels = [p.info["theta0_deg"] for p in points]
    s = {"runs": len(points), "failed_runs": sum(1 for p in points if not p.ok)}
    for key, _ in ANGLE_METRICS:
        s[key] = distribution([metric(p, key) for p in points], labels)
    pol = [metric(p, "polarity_correct") for p in points]
    s["polarity_correct"] = sum(1 for v in pol if v is True)
    s["polarity_wrong_at"] = [lab for lab, v in zip(labels, pol) if v is False]
    s["polarity_undecided_at"] = [lab for lab, v in zip(labels, pol) if v is not True and v is not False]
    s["not_run_state_at"] = [lab for lab, p in zip(labels, points)
                             if p.ok and metric(p, "final_state") != "RUN"]
    s["faults_at"] = [lab for lab, p in zip(labels, points) if metric(p, "faults")]
    return s


def angle_violations(points: list[Point], args) -> list[str]:
    out = []
    for p in points:
        a = f"theta0 = {p.info['theta0_deg']:g} deg"
        if not p.ok:
            out.append(f"{a}: {p.error}")
            continue
        if args.expect_polarity and metric(p, "polarity_correct") is not True:
            out.append(f"{a}: polarity_correct is {json.dumps(metric(p, 'polarity_correct'))}")
        if args.max_final_err_deg is not None:
            e = number(metric(p, args.final_metric))
            if e is None or abs(e) > args.max_final_err_deg:
                out.append(f"{a}: |{args.final_metric}| {fmt(e)} > {args.max_final_err_deg:g}")
        if args.max_time_s is not None:
            t = number(metric(p, "init_pos_time_s"))
            if t is None or t > args.max_time_s:
                out.append(f"{a}: init_pos_time_s {fmt(t, 4)} > {args.max_time_s:g}")
    return out


def angles_markdown(points, summary, args, scenario) -> str:
    cmd = f"mctools sweep angles {scenario}" + (f" {sets_text(args.sets_)}" if args.sets_ else "")
    n = summary["runs"]
    first = ", ".join(f"{p.info['theta0_deg']:g}" for p in points[:4])
    lines = [f"### Initial-angle sweep: {n} angles", "",
             f"`{cmd}` (angles {first}{', ...' if n > 4 else ''}; errors = estimate − true, "
             f"degrees electrical).", "",
             f"Polarity correct in **{summary['polarity_correct']} / {n}** runs"
             + (f"; wrong at {', '.join(f'{a:g}' for a in summary['polarity_wrong_at'])}"
                if summary["polarity_wrong_at"] else "")
             + (f"; undecided (null / failed run) at "
                f"{', '.join(f'{a:g}' for a in summary['polarity_undecided_at'])}"
                if summary["polarity_undecided_at"] else "") + ".", ""]
    if summary["failed_runs"]:
        lines += [f"**{summary['failed_runs']} run(s) failed.**", ""]
    if summary["not_run_state_at"]:
        lines += ["Not in RUN at the end: "
                  + ", ".join(f"{a:g}" for a in summary["not_run_state_at"]) + ".", ""]
    lines += ["| quantity | metric | mean | mean abs | max abs (at θ0) | min / max | n | thesis |",
              "|---|---|---|---|---|---|---|---|"]
    for key, what in ANGLE_METRICS:
        d = summary[key]
        if key.endswith("_s"):
            f1 = fmt_ms
            at = f" ({d['abs_max_at']:g}°)" if d["abs_max_at"] is not None else ""
            row = [f1(d["mean"]), f1(d["abs_mean"]), f1(d["abs_max"]) + at,
                   f"{f1(d['min'])} / {f1(d['max'])}"]
        else:
            at = f" ({d['abs_max_at']:g}°)" if d["abs_max_at"] is not None else ""
            row = [fmt(d["mean"], 2, "°"), fmt(d["abs_mean"], 2, "°"),
                   fmt(d["abs_max"], 2, "°") + at,
                   f"{fmt(d['min'], 2, '°')} / {fmt(d['max'], 2, '°')}"]
        missing = f" ({d['missing']} null)" if d["missing"] else ""
        lines.append(f"| {what} | `{key}` | " + " | ".join(row)
                     + f" | {d['n']}{missing} | {THESIS_ANGLES.get(key, DASH)} |")
    lines += ["", "| θ0 | Step I err | pulse-only err | polarity | hand-over err | final err (20 ms mean) "
              "| enable → < 1° | Step I + II | reverse | end state |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for p in points:
        if not p.ok:
            lines.append(f"| {p.info['theta0_deg']:g}° | {p.error} |  |  |  |  |  |  |  |  |")
            continue
        faults = metric(p, "faults") or []
        end = str(metric(p, "final_state")) + (f" ({', '.join(faults)})" if faults else "")
        pol = metric(p, "polarity_correct")
        lines.append(
            f"| {p.info['theta0_deg']:g}° | {fmt(number(metric(p, 'step1_err_deg')), 2, '°')} "
            f"| {fmt(number(metric(p, 'step12_err_deg')), 2, '°')} "
            f"| {fmt(pol) if isinstance(pol, bool) else DASH} "
            f"| {fmt(number(metric(p, 'init_pos_err_deg')), 2, '°')} "
            f"| {fmt(number(metric(p, 'init_pos_err_mean_deg')), 2, '°')} "
            f"| {fmt_ms(number(metric(p, 'init_pos_time_s')))} "
            f"| {fmt_ms(number(metric(p, 'step12_time_s')))} "
            f"| {fmt(number(metric(p, 'reverse_angle_max_deg')), 2, '°')} | {end} |")
    return "\n".join(lines)


def cmd_angles(args) -> int:
    scenario, mcsim = check_common(args)
    angles = angle_list(args.step_deg, args.angles, 5.0)
    args.sets_ = parse_sets(args.set, ("mechanics.theta0_deg",))
    for flag in ("max_final_err_deg", "max_time_s"):
        v = getattr(args, flag)
        if v is not None and not (math.isfinite(v) and v > 0):
            raise SweepInputError(f"--{flag.replace('_', '-')} must be a positive number")
    out = Path(args.out or "out/sweep/angles")
    points = [Point(f"theta0={a:g}", (*args.sets_, f"mechanics.theta0_deg={f_toml(a)}"),
                    out / angle_dir_name(a), {"theta0_deg": a}) for a in angles]
    run_points(points, mcsim, scenario, args.jobs, "angles")
    summary = summarize_angles(points)
    violations = angle_violations(points, args)
    md = angles_markdown(points, summary, args, scenario)
    data = {"command": "angles", "scenario": str(scenario), "sets": list(args.sets_),
            "summary": summary, "violations": violations,
            "runs": [{**p.info, "dir": str(p.dir), "error": p.error,
                      "metrics": {k: metric(p, k) for k in (
                          "step1_err_deg", "step12_err_deg", "polarity_correct",
                          "init_pos_err_deg", "init_pos_err_mean_deg", "init_pos_time_s", "step12_time_s",
                          "reverse_angle_max_deg", "current_peak_a", "final_state", "faults")}}
                     for p in points]}
    write_outputs(args, md, data)
    for v in violations:
        print(f"sweep angles: FAIL {v}", file=sys.stderr)
    checks = [f for f, on in (("polarity", args.expect_polarity),
                              (f"|final err| <= {args.max_final_err_deg:g} deg"
                               if args.max_final_err_deg is not None else "", True),
                              (f"time <= {args.max_time_s:g} s"
                               if args.max_time_s is not None else "", True)) if on and f]
    print(f"sweep angles: {len(points)} runs, {summary['failed_runs']} failed, polarity correct "
          f"{summary['polarity_correct']}/{len(points)}"
          + (f"; checks ({', '.join(checks)}): {len(violations)} violation(s)" if checks else ""))
    return 1 if violations or summary["failed_runs"] else 0


# ---------------------------------------------------------------------------------------------
# table7_1

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
# noise

def trial_angles(trials: int, seed: int) -> list[float]:
    """Uniform initial angles in [0, 360) deg, one per trial, reproducible from `seed` (rounded
    to 1e-3 deg so the recorded value is exactly the one passed to mcsim)."""
    rng = random.Random(seed)
    return [round(rng.uniform(0.0, 360.0), 3) % 360.0 for _ in range(trials)]


def summarize_noise(points: list[Point], methods, levels, min_pct: float) -> dict:
    res = {}
    for method in methods:
        rows = []
        for lv in levels:
            pts = [p for p in points if p.info["method"] == method and p.info["noise_a"] == lv]
            vals = [metric(p, "polarity_correct") for p in pts]
            correct = sum(1 for v in vals if v is True)
            undecided = sum(1 for v in vals if v is not True and v is not False)
            rows.append({"noise_a": lv, "trials": len(pts), "correct": correct,
                         "wrong": sum(1 for v in vals if v is False), "undecided": undecided,
                         "failed_runs": sum(1 for p in pts if not p.ok),
                         "pct": 100.0 * correct / len(pts) if pts else None,
                         "wrong_seeds": [p.info["seed"] for p, v in zip(pts, vals) if v is not True][:50]})
        # the limit: the highest level below the first one that misses min_pct (levels ascending)
        limit, first_fail = None, None
        for r in sorted(rows, key=lambda r: r["noise_a"]):
            if r["pct"] is not None and r["pct"] >= min_pct:
                limit = r["noise_a"]
            else:
                first_fail = r["noise_a"]
                break
        res[method] = {"levels": rows, "limit_a": limit, "first_fail_a": first_fail}
    return res


def noise_markdown(summary: dict, args, scenario, methods, levels) -> str:
    cmd = (f"mctools sweep noise {scenario} --levels {','.join(f'{v:g}' for v in levels)} "
           f"--trials {args.trials} --methods {','.join(methods)}"
           + (f" {sets_text(args.sets_)}" if args.sets_ else ""))
    lines = ["### Step II polarity decision vs current noise (Fig. 7.4)", "",
             f"`{cmd}`: per method and level {args.trials} trials, scenario.seed = 1..{args.trials}, "
             f"initial angles uniform in [0, 360)° from seed {args.angle_seed} (the same angles for "
             f"every level and method). Percentage of runs with `polarity_correct` true (a null "
             f"or failed run counts as wrong).", "",
             "| noise rms | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
    for i, lv in enumerate(levels):
        cells = []
        for method in methods:
            r = summary[method]["levels"][i]
            mark = "" if r["pct"] is not None and r["pct"] >= args.min_pct else " ✗"
            cells.append(f"{r['pct']:.1f} % ({r['correct']}/{r['trials']}){mark}"
                         if r["pct"] is not None else DASH)
        lines.append(f"| {lv:g} A | " + " | ".join(cells) + " |")
    lines.append("")
    for method in methods:
        s = summary[method]
        lim = f"{s['limit_a']:g} A" if s["limit_a"] is not None else "none of the levels"
        fail = f"; first below at {s['first_fail_a']:g} A" if s["first_fail_a"] is not None else \
            "; no level below"
        lines.append(f"- {method}: ≥ {args.min_pct:g} % correct up to {lim}{fail}.")
    return "\n".join(lines)


def cmd_noise(args) -> int:
    scenario, mcsim = check_common(args)
    levels = parse_floats(args.levels, "--levels")
    if any(not 0.0 <= v <= 10.0 for v in levels):
        raise SweepInputError("--levels: each level must be in 0..10 A (sensors.i_noise_rms_a)")
    levels = sorted(levels)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    if not methods or any(m not in METHODS for m in methods) or len(set(methods)) != len(methods):
        raise SweepInputError(f"--methods: {args.methods!r} (choose from {', '.join(METHODS)}, "
                              f"no duplicates)")
    if not 1 <= args.trials <= 100000:
        raise SweepInputError("--trials must be in 1..100000")
    if not 0.0 < args.min_pct <= 100.0:
        raise SweepInputError("--min-pct must be in (0, 100]")
    args.sets_ = parse_sets(args.set, ("mechanics.theta0_deg", "scenario.seed",
                                       "sensors.i_noise_rms_a", "startup.polarity"))
    out = Path(args.out or "out/sweep/noise")
    angles = trial_angles(args.trials, args.angle_seed)
    points = []
    for method in methods:
        for lv in levels:
            for seed, a in enumerate(angles, start=1):
                sets = (*args.sets_, "startup.init_pos=\"three_step\"",
                        f"startup.polarity=\"{method}\"", f"sensors.i_noise_rms_a={f_toml(lv)}",
                        f"scenario.seed={seed}", f"mechanics.theta0_deg={f_toml(a)}")
                points.append(Point(f"{method} noise={lv:g} seed={seed}", sets,
                                    out / method / f"noise_{lv:g}" / f"seed_{seed:05d}",
                                    {"method": method, "noise_a": lv, "seed": seed,
                                     "theta0_deg": a}))
    run_points(points, mcsim, scenario, args.jobs, "noise")
    summary = summarize_noise(points, methods, levels, args.min_pct)
    md = noise_markdown(summary, args, scenario, methods, levels)
    data = {"command": "noise", "scenario": str(scenario), "sets": list(args.sets_),
            "trials": args.trials, "angle_seed": args.angle_seed, "min_pct": args.min_pct,
            "angles_deg": angles, "summary": summary,
            "runs": [{**p.info, "error": p.error,
                      "polarity_correct": metric(p, "polarity_correct"),
                      "step12_err_deg": metric(p, "step12_err_deg")} for p in points]}
    write_outputs(args, md, data)
    failed = sum(1 for p in points if not p.ok)
    print(f"sweep noise: {len(points)} runs, {failed} failed; "
          + "; ".join(f"{m} >= {args.min_pct:g} % up to "
                      + (f"{summary[m]['limit_a']:g} A" if summary[m]["limit_a"] is not None
                         else "(none)") for m in methods))
    return 1 if failed else 0


# ---------------------------------------------------------------------------------------------
# seeds

SEED_PCTS = (5.0, 10.0, 90.0, 95.0)
DEFAULT_BATCH = 8
CONNECT_TIMEOUT = "20s"  # to reach the Dask scheduler


def run_seed_batch(mcsim: str, scenario: str, sets: tuple[str, ...], out: str,
                   seeds: list[int]) -> list[dict]:
    """Runs mcsim once per seed, one after the other, into OUT/seed_NNNN/ and returns per seed
    {seed, exit_code, seconds, error, metrics}. A plain top-level function of plain arguments:
    it is what a Dask worker runs for one batch (paths as the worker sees them)."""
    res = []
    for seed in seeds:
        p = Point(f"seed={seed}", (*sets, f"scenario.seed={seed}"), Path(out) / f"seed_{seed:04d}",
                  {"seed": seed})
        execute(p, mcsim, Path(scenario))
        res.append({"seed": seed, "exit_code": p.exit_code, "seconds": p.seconds,
                    "error": p.error, "metrics": p.metrics})
    return res


def flatten_numbers(metrics: dict | None, prefix: str = "") -> dict:
    """The numeric entries of metrics.json, nested objects as dotted keys; booleans as 0/1 and
    null as None (both kept so that a metric that is null in some seeds shows up)."""
    out = {}
    for k, v in (metrics or {}).items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten_numbers(v, key + "."))
        elif isinstance(v, bool):
            out[key] = 1.0 if v else 0.0
        elif v is None:
            out[key] = None
        elif isinstance(v, (int, float)):
            out[key] = float(v) if math.isfinite(v) else None
    return out


def seed_statistics(results: list[dict]) -> dict:
    """Per metric over the seeds: n (finite values), missing (null, absent or failed run),
    mean, median, nearest-rank p5/p10/p90/p95 (mctools.report.nearest_rank, the percentile the
    thesis checks use), min, max, and the seeds of the min and max."""
    from statistics import median

    from mctools.report import nearest_rank

    flat = [(r["seed"], flatten_numbers(r["metrics"])) for r in results]
    keys = list(dict.fromkeys(k for _, f in flat for k in f))
    stats = {}
    for key in keys:
        pairs = [(seed, f.get(key)) for seed, f in flat]
        vals = [v for _, v in pairs if v is not None]
        d = {"n": len(vals), "missing": len(pairs) - len(vals)}
        if vals:
            lo = min(pairs, key=lambda x: math.inf if x[1] is None else x[1])
            hi = max(pairs, key=lambda x: -math.inf if x[1] is None else x[1])
            d.update(mean=sum(vals) / len(vals), median=median(vals),
                     **{f"p{p:g}": nearest_rank(vals, p) for p in SEED_PCTS},
                     min=lo[1], max=hi[1], min_seed=lo[0], max_seed=hi[0])
        else:
            d.update(mean=None, median=None, **{f"p{p:g}": None for p in SEED_PCTS}, min=None,
                     max=None, min_seed=None, max_seed=None)
        stats[key] = d
    return stats


def _num(v) -> str:
    from mctools.report import fmt_number
    return DASH if v is None else fmt_number(v)


def seeds_markdown(stats: dict, args, scenario, n_runs: int, failed: list[int]) -> str:
    cmd = f"mctools sweep seeds {scenario} --n {args.n}" + (
        f" {sets_text(args.sets_)}" if args.sets_ else "")
    lines = [f"### Seed statistics: {scenario.stem}, scenario.seed = 1..{args.n}", "",
             f"`{cmd}`: {n_runs} runs" + (f", **{len(failed)} failed** (seeds "
                                           f"{', '.join(map(str, failed[:20]))})" if failed else "")
             + ". Percentiles by nearest rank (p90 of 10 seeds is the 9th smallest); booleans "
             "as 0/1; *missing* counts nulls and failed runs.", "",
             "| metric | median | p5 | p10 | p90 | p95 | min (seed) | max (seed) | n | missing |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for key, d in stats.items():
        mn = f"{_num(d['min'])} ({d['min_seed']})" if d["min"] is not None else DASH
        mx = f"{_num(d['max'])} ({d['max_seed']})" if d["max"] is not None else DASH
        lines.append(f"| `{key}` | {_num(d['median'])} | {_num(d['p5'])} | {_num(d['p10'])} "
                     f"| {_num(d['p90'])} | {_num(d['p95'])} | {mn} | {mx} | {d['n']} "
                     f"| {d['missing']} |")
    return "\n".join(lines)


def seeds_csv(stats: dict) -> str:
    cols = ["metric", "n", "missing", "mean", "median", *(f"p{p:g}" for p in SEED_PCTS), "min",
            "max", "min_seed", "max_seed"]
    rows = [",".join(cols)]
    for key, d in stats.items():
        rows.append(",".join([key] + ["" if d[c] is None else repr(d[c]) if isinstance(d[c], float)
                                      else str(d[c]) for c in cols[1:]]))
    return "\n".join(rows) + "\n"


def _batches(seeds: list[int], size: int) -> list[list[int]]:
    return [seeds[i:i + size] for i in range(0, len(seeds), size)]


def _progress(done: int, total: int, batch: list[dict], t0: float) -> None:
    bad = [r["seed"] for r in batch if r["error"]]
    seeds = f"{batch[0]['seed']}..{batch[-1]['seed']}" if len(batch) > 1 else f"{batch[0]['seed']}"
    print(f"[{done}/{total}] seeds {seeds} ... {time.monotonic() - t0:.1f} s elapsed"
          + (f"; failed: {', '.join(map(str, bad))}" if bad else ""), file=sys.stderr, flush=True)


def run_seeds_local(mcsim, scenario, sets, out, seeds, jobs, batch) -> list[dict]:
    """`jobs` batches at a time, each in a thread that waits on its mcsim processes (so `jobs`
    simulator processes run at once, one per core by default)."""
    results, done, t0 = [], 0, time.monotonic()
    batches = _batches(seeds, batch)
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(run_seed_batch, mcsim, scenario, sets, out, b) for b in batches]
        for fut in as_completed(futures):
            res = fut.result()
            results += res
            done += len(res)
            _progress(done, len(seeds), res, t0)
    return results


def run_seeds_dask(address, mcsim, scenario, sets, out, seeds, batch) -> list[dict]:
    """One Dask task per batch of seeds on the cluster at `address`; each task runs
    run_seed_batch on its worker, so the worker needs mcsim, the scenario (and the presets it
    names) at the same paths, and writes the run folders there. Only the metrics come back."""
    try:
        from distributed import Client, as_completed as dask_completed
    except ImportError:
        raise SweepInputError("--scheduler needs dask.distributed: pip install 'tools[dask]'") \
            from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as exc:
        raise SweepInputError(f"--scheduler {address}: cannot connect: {exc}") from None
    results, done, t0 = [], 0, time.monotonic()
    try:
        batches = _batches(seeds, batch)
        futures = [client.submit(run_seed_batch, mcsim, scenario, sets, out, b, pure=False,
                                 key=f"mctools-seeds-{Path(scenario).stem}-{b[0]}-{b[-1]}-"
                                     f"{time.time_ns()}")
                   for b in batches]
        for fut in dask_completed(futures):
            res = fut.result()
            results += res
            done += len(res)
            _progress(done, len(seeds), res, t0)
    finally:
        client.close()
    return results


def cmd_seeds(args) -> int:
    if args.jobs is None:
        args.jobs = os.cpu_count() or 1
    scenario, mcsim = check_common(args)
    if not 1 <= args.n <= 100000:
        raise SweepInputError("--n must be in 1..100000")
    if not 1 <= args.batch <= 10000:
        raise SweepInputError("--batch must be in 1..10000")
    sets = parse_sets(args.set, ("scenario.seed",))
    args.sets_ = sets
    if not args.trace and not any(s.split("=", 1)[0].strip() == "output.trace" for s in sets):
        sets = (*sets, "output.trace=false")  # only metrics.json is read
    out = Path(args.out or f"out/sweep/seeds/{scenario.stem}")
    seeds = list(range(1, args.n + 1))
    t0 = time.monotonic()
    if args.scheduler:
        results = run_seeds_dask(args.scheduler, str(Path(mcsim).resolve()),
                                 str(scenario.resolve()), sets, str(out.resolve()), seeds,
                                 args.batch)
    else:
        # locally a batch only amortises the thread hand-off; keep every core busy to the end
        batch = min(args.batch, max(1, math.ceil(args.n / (4 * args.jobs))))
        results = run_seeds_local(mcsim, str(scenario), sets, str(out), seeds, args.jobs, batch)
    wall = time.monotonic() - t0
    results.sort(key=lambda r: r["seed"])
    failed = [r["seed"] for r in results if r["error"]]
    stats = seed_statistics(results)
    md = seeds_markdown(stats, args, scenario, len(results), failed)
    data = {"command": "seeds", "scenario": str(scenario), "sets": list(args.sets_),
            "n": args.n, "scheduler": args.scheduler, "wall_s": wall, "statistics": stats,
            "runs": results}
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    (out / "summary.csv").write_text(seeds_csv(stats), encoding="utf-8")
    write_outputs(args, md, data)
    print(f"wrote {out / 'summary.json'} and {out / 'summary.csv'}")
    cpu = sum(r["seconds"] for r in results)
    print(f"sweep seeds: {len(results)} runs, {len(failed)} failed, {wall:.1f} s wall, "
          f"{cpu:.1f} s in mcsim" + (f" (on {args.scheduler})" if args.scheduler
                                      else f" ({args.jobs} at a time)"))
    return 1 if failed else 0


# ---------------------------------------------------------------------------------------------
# envelope

ENVELOPE_SCENARIOS = ("scenarios/envelope/standstill_loaded.toml",
                      "scenarios/envelope/speed_reversal.toml",
                      "scenarios/envelope/torque_steps_300rpm.toml",
                      "scenarios/sensorless_demo.toml")
LOST_DEG = 90.0  # an angle error at or beyond this is a lost estimate
PEAK_NOTE_DEG = 45.0  # a holding cell names its transient peak from here on
DOC_BEGIN, DOC_END = "<!-- envelope:begin -->", "<!-- envelope:end -->"
# worst first: the cell shows the worst outcome over its seeds
OUTCOME_RANK = {"holds": 0, "no_run": 1, "recovers": 2, "trips": 3, "runs_off": 4, "failed": 5}


@dataclass(frozen=True)
class EnvelopeError:
    key: str                      # run folder name
    what: str                     # the row's error, as the table shows it
    model: str                    # estimator.model
    sets: tuple[str, ...]         # the mismatch keys it sets (the others stay exact)


def envelope_errors() -> list[EnvelopeError]:
    """The rows: the exact model, then one parameter error at a time. L, psi_pm and Rs act on
    both estimator models (const: the constants; fluxmap: the map's inductive part, its magnet
    part, Rs), so those rows come once per model; the map's inductive part ±5 % and the
    cross-saturation exist in the flux-map model only (its L ×0.9 / ×1.1 rows are the map's ±10 %)."""
    rows = []
    for model in ("fluxmap", "const"):
        rows.append(EnvelopeError(f"exact_{model}", "exact (reference)", model, ()))
    groups = (("l_scale", "L", (0.8, 0.9, 0.95, 1.05, 1.1, 1.2), ("const", "fluxmap")),
              ("psi_scale", "ψpm", (0.9, 1.1), ("const", "fluxmap")),
              ("rs_scale", "Rs", (0.7, 1.3), ("const", "fluxmap")),
              ("cross_scale", "cross-saturation", (0.75, 1.25), ("fluxmap",)))
    for key, name, factors, models in groups:
        for model in models:
            for f in factors:
                if key == "l_scale" and model == "const" and f in (0.95, 1.05):
                    continue  # the ±5 % rows are the flux map's inductive part only
                what = f"{name} ×{f:g}"
                if key == "l_scale" and model == "fluxmap":
                    what = f"L ×{f:g} (map's inductive part {100 * (f - 1):+.0f} %)"
                rows.append(EnvelopeError(f"{key.split('_')[0]}_{f:g}_{model}", what, model,
                                          (f"estimator.{key}={f_toml(f)}",)))
    return rows


def steady_angle_deg(m: dict) -> float | None:
    """angle_err_steady_max_deg, else the largest of the windows' angle_err_max_deg."""
    v = number(m.get("angle_err_steady_max_deg"))
    if v is not None:
        return abs(v)
    ws = [number(w.get("angle_err_max_deg")) for w in (m.get("windows") or {}).values()
          if isinstance(w, dict)]
    ws = [abs(w) for w in ws if w is not None]
    return max(ws) if ws else None


def classify_run(metrics: dict | None, error: str | None = None) -> dict:
    """One run's outcome from its metrics.json. The metrics count the angle error only while the
    drive runs, so after a fault angle_err_max_deg is the largest error before it.
      holds     no fault, |angle error| stayed below LOST_DEG: steady_deg is the steady error;
      trips     a fault, and the angle error stayed below LOST_DEG before it (a safe trip);
      recovers  the firmware detected a loss of lock, turned the outputs off and caught the
                rotor again (protection.lock_action = recover; metrics recoveries > 0), ended
                without a fault, and the angle error stayed below LOST_DEG;
      runs_off  the angle error reached LOST_DEG: with no fault, or before a fault or a
                recovery (conservative: the metrics do not say whether the angle was lost
                before the first detection or during a retry);
      no_run    no fault, but the drive never ran (no angle error at all);
      failed    mcsim failed or wrote no metrics."""
    if error is not None or not isinstance(metrics, dict):
        return {"outcome": "failed", "error": error or "no metrics"}
    faults = [str(f) for f in (metrics.get("faults") or [])]
    amax = number(metrics.get("angle_err_max_deg"))
    lost = amax is not None and abs(amax) >= LOST_DEG
    recoveries = int(number(metrics.get("recoveries")) or 0)
    if lost:
        outcome = "runs_off"
    elif recoveries and not faults:
        outcome = "recovers"
    elif faults:
        outcome = "trips"
    elif amax is None:
        outcome = "no_run"
    else:
        outcome = "holds"
    return {"outcome": outcome, "faults": faults, "recoveries": recoveries,
            "recovered_from": [str(f) for f in (metrics.get("recovered_from") or [])],
            "fault_time_s": number(metrics.get("fault_time_s")),
            "angle_err_max_deg": None if amax is None else abs(amax),
            "steady_deg": steady_angle_deg(metrics)}


def _deg(v: float | None, digits: int = 1) -> str:
    return "?" if v is None else f"{v:.{digits}f}°"


def _outcome_text(outcome: str, sel: list[dict], n: int) -> str:
    """The table text for the runs `sel` (out of n seeds) that share one outcome."""
    maxof = lambda key: max((r[key] for r in sel if r.get(key) is not None), default=None)
    reasons = list(dict.fromkeys(f for r in sel for f in r.get("faults", [])))
    notes = [f"{len(sel)}/{n}"] if len(sel) < n else []
    if outcome == "holds":
        text = f"holds {_deg(maxof('steady_deg'))}"
        peak = maxof("angle_err_max_deg")
        if peak is not None and peak >= PEAK_NOTE_DEG:
            notes.append(f"peak {_deg(peak, 0)}")
    elif outcome == "trips":
        t_first = min((r["fault_time_s"] for r in sel if r.get("fault_time_s") is not None),
                      default=None)
        text = f"trips: {', '.join(reasons)}" + (f" at {t_first:.2f} s" if t_first is not None
                                                 else "")
        notes.append(f"max {_deg(maxof('angle_err_max_deg'), 0)}")
        rec = maxof("recoveries")
        if rec:
            notes.append(f"after {rec} recover{'y' if rec == 1 else 'ies'}")
    elif outcome == "recovers":
        why = list(dict.fromkeys(f for r in sel for f in r.get("recovered_from", [])))
        text = f"recovers ×{maxof('recoveries')} ({', '.join(why)}), then {_deg(maxof('steady_deg'))}"
        notes.append(f"max {_deg(maxof('angle_err_max_deg'), 0)}")
    elif outcome == "runs_off":
        silent = sum(1 for r in sel if not r.get("faults") and not r.get("recoveries"))
        text = f"RUNS OFF {_deg(maxof('angle_err_max_deg'), 0)}"
        if silent:
            text = f"**{text}**"  # the finding: the angle is lost and nothing trips
        if reasons:  # a trip after the angle was lost
            text += ", then " + ", ".join(reasons) \
                + (f" in {len(sel) - silent}/{len(sel)}" if silent else "")
        rec = maxof("recoveries")
        if rec:
            text += f" (after {rec} recover{'y' if rec == 1 else 'ies'})" if reasons else \
                f", then recovers ×{rec}"

    elif outcome == "no_run":
        text = "never ran"
    else:
        text = "run failed"
    return text + (f" ({', '.join(notes)})" if notes else "")


def summarize_cell(runs: list[dict]) -> dict:
    """The cell over its seeds: the worst outcome first, then the others (worst first), each
    with its share of the seeds when not all; and the numbers for the JSON."""
    n = len(runs)
    if not runs:
        return {"outcome": "failed", "text": "no runs", "count": 0, "n": 0, "faults": [],
                "silent_runs_off": 0, "steady_deg": None, "angle_err_max_deg": None}
    present = sorted({r["outcome"] for r in runs}, key=OUTCOME_RANK.__getitem__, reverse=True)
    worst = present[0]
    groups = {o: [r for r in runs if r["outcome"] == o] for o in present}
    text = "; ".join(_outcome_text(o, groups[o], n) for o in present)
    steady = [r["steady_deg"] for r in groups[worst] if r.get("steady_deg") is not None]
    return {"outcome": worst, "text": text, "count": len(groups[worst]), "n": n,
            "faults": list(dict.fromkeys(f for r in runs for f in r.get("faults", []))),
            "silent_runs_off": sum(1 for r in groups.get("runs_off", [])
                                   if not r.get("faults") and not r.get("recoveries")),
            "steady_deg": max(steady) if worst == "holds" and steady else None,
            "angle_err_max_deg": max((r["angle_err_max_deg"] for r in runs
                                      if r.get("angle_err_max_deg") is not None), default=None)}


def envelope_markdown(rows: list[EnvelopeError], scen_names: list[str], cells: dict,
                      command: str, seeds: int, n_runs: int, wall: float) -> str:
    counts = {o: sum(1 for c in cells.values() if c["outcome"] == o) for o in OUTCOME_RANK}
    silent = sum(1 for c in cells.values() if c.get("silent_runs_off"))
    lines = ["## Robustness envelope: estimator parameter errors × sensorless scenarios", "",
             f"`{command}`: sun2016-ipm-5kw, UNOP, one estimator parameter wrong at a time (the "
             f"others exact), scenario.seed = 1..{seeds} per cell, {n_runs} runs in {wall:.0f} s. "
             f"A cell shows the worst of its seeds (then the other outcomes; k/{seeds}: how many seeds had it): "
             f"**holds x°** no fault and the angle error stayed below {LOST_DEG:g}°, x = the largest "
             f"steady error (`angle_err_steady_max_deg`), with \"(peak z°)\" when the "
             f"largest error anywhere reached {PEAK_NOTE_DEG:g}°; **trips: reason at t (max y°)** a fault "
             f"(t = the first seed's `fault_time_s`), the angle error stayed below {LOST_DEG:g}° "
             f"until it (y = `angle_err_max_deg` with `metrics.start_s = 0`, counted while "
             f"running, i.e. before the fault); **RUNS OFF y°** the angle error reached "
             f"{LOST_DEG:g}°, in bold when no fault followed (the angle is lost and nothing trips), "
             f"else \"then reason\" (the trip came after the angle was lost); **recovers ×k (reason), then x°** "
             f"the firmware detected the loss (reason), turned the outputs off and caught the rotor "
             f"again k times (protection.lock_action = recover, the default) and ran on without a "
             f"fault, x = the steady error after. L = the estimator's "
             f"estimator.l_scale: the constants Ld, Lq (const model) or the flux map's "
             f"current-dependent part (fluxmap); ψpm = psi_scale, Rs = rs_scale, "
             f"cross-saturation = cross_scale (flux-map model only; docs/simulator.md "
             f"\"Estimator mismatch\").", "",
             f"Cells: {counts['holds']} hold, {counts['recovers']} recover, {counts['trips']} trip, {counts['runs_off']} run off "
             f"({silent} without any fault)"
             + (f", {counts['failed']} with failed runs" if counts["failed"] else "")
             + (f", {counts['no_run']} never ran" if counts["no_run"] else "") + ".", "",
             "| error | model | " + " | ".join(f"`{s}`" for s in scen_names) + " |",
             "|---|---|" + "---|" * len(scen_names)]
    for r in rows:
        lines.append(f"| {r.what} | {r.model} | "
                     + " | ".join(cells[(r.key, s)]["text"] for s in scen_names) + " |")
    return "\n".join(lines)


def replace_doc_section(doc: Path, section: str) -> None:
    """Puts `section` between the envelope markers of `doc`, replacing what is there, or
    appends the markers and the section (a new file holds only them)."""
    block = f"{DOC_BEGIN}\n{section.strip()}\n{DOC_END}"
    text = doc.read_text(encoding="utf-8") if doc.is_file() else ""
    if DOC_BEGIN in text:
        a = text.index(DOC_BEGIN)
        b = text.find(DOC_END, a)
        if b < 0:
            raise SweepInputError(f"{doc}: {DOC_BEGIN} without {DOC_END}")
        text = text[:a] + block + text[b + len(DOC_END):]
    elif DOC_END in text:
        raise SweepInputError(f"{doc}: {DOC_END} without {DOC_BEGIN}")
    else:
        text = (text.rstrip("\n") + "\n\n" if text.strip() else "") + block + "\n"
    doc.parent.mkdir(parents=True, exist_ok=True)
    doc.write_text(text, encoding="utf-8")


def cmd_envelope(args) -> int:
    if args.jobs is None:
        args.jobs = os.cpu_count() or 1
    if args.jobs < 1:
        raise SweepInputError("--jobs must be at least 1")
    if not 1 <= args.seeds <= 1000:
        raise SweepInputError("--seeds must be in 1..1000")
    scenarios = [Path(s) for s in (args.scenarios or ENVELOPE_SCENARIOS)]
    for s in scenarios:
        if not s.is_file():
            raise SweepInputError(f"{s}: no such scenario file")
        try:
            tomllib.loads(s.read_text(encoding="utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise SweepInputError(f"{s}: not valid TOML: {exc}") from None
    names = [s.stem for s in scenarios]
    if len(set(names)) != len(names):
        raise SweepInputError("--scenarios: two scenarios with the same file name")
    mcsim = find_mcsim(args.mcsim)
    out = Path(args.out or "out/sweep/envelope")
    rows = envelope_errors()
    seeds = list(range(1, args.seeds + 1))
    tasks = []  # (row, scenario): all seeds of one cell, one after the other
    for s in scenarios:
        for r in rows:
            # the angle error from the first RUN sample on: a trip before a scenario's own
            # metrics.start_s must not look like a run without any angle error
            sets = (f"estimator.model=\"{r.model}\"", *r.sets, "metrics.start_s=0.0",
                    "output.trace=false")
            tasks.append((r, s, sets, out / s.stem / r.key))
    cells, runs_json, t0, done = {}, [], time.monotonic(), 0
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {pool.submit(run_seed_batch, mcsim, str(s), sets, str(d), seeds): (r, s)
                   for r, s, sets, d in tasks}
        for fut in as_completed(futures):
            r, s = futures[fut]
            res = sorted(fut.result(), key=lambda x: x["seed"])
            classified = [{"seed": x["seed"], "exit_code": x["exit_code"],
                           "seconds": x["seconds"], **classify_run(x["metrics"], x["error"])}
                          for x in res]
            cell = summarize_cell(classified)
            cells[(r.key, s.stem)] = cell
            runs_json.append({"error_key": r.key, "scenario": s.stem, "runs": classified})
            done += 1
            print(f"[{done}/{len(tasks)}] {r.what} ({r.model}) × {s.stem}: "
                  f"{cell['text'].replace('**', '')} ... {time.monotonic() - t0:.1f} s elapsed",
                  file=sys.stderr, flush=True)
    wall = time.monotonic() - t0
    default_scen = args.scenarios is None
    command = "mctools sweep envelope" + ("" if default_scen else " --scenarios "
                                          + " ".join(str(s) for s in scenarios)) \
        + f" --seeds {args.seeds}"
    n_runs = len(tasks) * len(seeds)
    md = envelope_markdown(rows, names, cells, command, args.seeds, n_runs, wall)
    failed = [x for c in runs_json for x in c["runs"] if x["outcome"] == "failed"]
    order = {r.key: i for i, r in enumerate(rows)}
    runs_json.sort(key=lambda c: (names.index(c["scenario"]), order[c["error_key"]]))
    data = {"command": "envelope", "scenarios": [str(s) for s in scenarios],
            "seeds": args.seeds, "lost_deg": LOST_DEG, "wall_s": wall, "runs_total": n_runs,
            "errors": [{"key": r.key, "what": r.what, "model": r.model, "sets": list(r.sets)}
                       for r in rows],
            "cells": [{"error_key": c["error_key"], "scenario": c["scenario"],
                       **cells[(c["error_key"], c["scenario"])], "runs": c["runs"]}
                      for c in runs_json]}
    out.mkdir(parents=True, exist_ok=True)
    (out / "envelope.json").write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    (out / "envelope.md").write_text(md + "\n", encoding="utf-8")
    print(md)
    print(f"wrote {out / 'envelope.json'} and {out / 'envelope.md'}")
    if args.doc:
        replace_doc_section(Path(args.doc), md)
        print(f"wrote the envelope section of {args.doc}")
    off = sum(1 for c in cells.values() if c["outcome"] == "runs_off")
    print(f"sweep envelope: {n_runs} runs, {len(failed)} failed, {off} cell(s) run off, "
          f"{wall:.1f} s wall ({args.jobs} at a time)")
    if args.fail_on_runoff and off:
        print(f"sweep envelope: FAIL: {off} cell(s) lose the angle before any detection",
              file=sys.stderr)
        return 1
    return 1 if failed else 0


# ---------------------------------------------------------------------------------------------
# CLI

def _common(p, default_out: str, jobs_default: int | None = 2) -> None:
    p.add_argument("scenario", metavar="SCENARIO.toml", help="scenario file run for every point")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="extra mcsim --set for every run (repeatable; value is TOML)")
    p.add_argument("--mcsim", metavar="PATH",
                   help="simulator binary (default: build/host/sim/app/mcsim, else mcsim on PATH)")
    p.add_argument("--out", metavar="DIR", help=f"run folders (default {default_out})")
    p.add_argument("--jobs", type=int, default=jobs_default, metavar="N",
                   help="simulations in parallel (default "
                        + (f"{jobs_default})" if jobs_default else "all cores: os.cpu_count())"))
    p.add_argument("--json", metavar="FILE", help="write the results as JSON")
    p.add_argument("--md", metavar="FILE", help="also write the printed markdown summary here")


def _angle_args(p, default_step: float) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--step-deg", type=float, metavar="DEG",
                   help=f"angles 0, DEG, 2 DEG, ... below 360 (default {default_step:g})")
    g.add_argument("--angles", metavar="A,B,...", help="explicit initial angles in degrees")


def add_parser(sub) -> None:
    p = sub.add_parser("sweep", help="initial-position sweeps with mcsim (thesis ch. 5, 7.2)")
    ssub = p.add_subparsers(dest="sweep_command", required=True, metavar="SWEEP")

    a = ssub.add_parser("angles", help="one run per initial angle: distribution of the startup "
                                       "metrics, optional pass/fail checks")
    _common(a, "out/sweep/angles")
    _angle_args(a, 5.0)
    a.add_argument("--expect-polarity", action="store_true",
                   help="exit 1 unless polarity_correct is true in every run")
    a.add_argument("--max-final-err-deg", type=float, metavar="X",
                   help="exit 1 if any |final error| > X (or null); see --final-metric")
    a.add_argument("--final-metric", default="init_pos_err_mean_deg",
                   choices=("init_pos_err_mean_deg", "init_pos_err_deg"),
                   help="which final error --max-final-err-deg checks: the mean over the 20 ms after "
                        "the hand-over (default) or the hand-over sample itself")
    a.add_argument("--max-time-s", type=float, metavar="T",
                   help="exit 1 if any init_pos_time_s > T (or null)")
    a.set_defaults(func=cmd_angles)

    t = ssub.add_parser("table7_1", help="thesis Table 7.1: Step I error, linear vs nonlinear "
                                         "cost, for several m, and the current peak in p.u.")
    _common(t, "out/sweep/table7_1")
    _angle_args(t, 15.0)
    t.add_argument("--m", default="3,4,5", metavar="M,M,...",
                   help="Step I pulse lengths (default 3,4,5)")
    t.set_defaults(func=cmd_table7_1)

    n = ssub.add_parser("noise", help="thesis Fig. 7.4: polarity decisions vs current noise, "
                                      "seeded trials with random initial angles")
    _common(n, "out/sweep/noise")
    n.add_argument("--levels", default="0.02,0.05,0.1,0.2", metavar="A,A,...",
                   help="current noise rms levels in A (default 0.02,0.05,0.1,0.2)")
    n.add_argument("--trials", type=int, default=1000, metavar="N",
                   help="trials per method and level, scenario.seed = 1..N (default 1000)")
    n.add_argument("--methods", default="generalized,dvi", metavar="M,M",
                   help="Step II methods (default generalized,dvi)")
    n.add_argument("--angle-seed", type=int, default=1, metavar="S",
                   help="seed of the random initial angles (default 1)")
    n.add_argument("--min-pct", type=float, default=99.0, metavar="P",
                   help="a level works when at least P %% of the trials are right (default 99)")
    n.set_defaults(func=cmd_noise)

    s = ssub.add_parser("seeds", help="one scenario over scenario.seed = 1..N: median, "
                                      "percentiles, min/max of every metric (local or Dask)")
    _common(s, "out/sweep/seeds/<scenario>", jobs_default=None)
    s.add_argument("--n", type=int, default=10, metavar="N",
                   help="seeds 1..N (default 10)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on this Dask distributed scheduler (tcp://host:8786) instead of the "
                        "local cores; workers need mcsim and the scenario at the same paths")
    s.add_argument("--batch", type=int, default=DEFAULT_BATCH, metavar="B",
                   help=f"runs per Dask task (default {DEFAULT_BATCH}; locally at most this, "
                        f"smaller so that every core has work)")
    s.add_argument("--trace", action="store_true",
                   help="keep each run's trace.csv (default: --set output.trace=false)")
    s.set_defaults(func=cmd_seeds)

    e = ssub.add_parser("envelope", help="robustness envelope: estimator parameter errors x "
                                         "sensorless scenarios, each cell over N seeds, "
                                         "classified holds / trips / runs off")
    e.add_argument("--scenarios", nargs="+", metavar="SCENARIO.toml",
                   help="scenario files, one column each (default: "
                        + " ".join(ENVELOPE_SCENARIOS) + ")")
    e.add_argument("--seeds", type=int, default=3, metavar="N",
                   help="scenario.seed = 1..N per cell (default 3)")
    e.add_argument("--jobs", type=int, default=None, metavar="J",
                   help="simulations in parallel (default all cores: os.cpu_count())")
    e.add_argument("--out", metavar="DIR",
                   help="run folders, envelope.json and envelope.md (default out/sweep/envelope)")
    e.add_argument("--doc", metavar="FILE",
                   help="put the table between <!-- envelope:begin --> and <!-- envelope:end --> "
                        "in FILE (appended with the markers if they are missing)")
    e.add_argument("--mcsim", metavar="PATH",
                   help="simulator binary (default: build/host/sim/app/mcsim, else mcsim on PATH)")
    e.add_argument("--fail-on-runoff", action="store_true",
                   help="exit 1 if any cell loses the angle (>= 90 deg) before a fault or recovery")
    e.set_defaults(func=cmd_envelope)
