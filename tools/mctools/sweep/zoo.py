"""`mctools sweep zoo`: the motor zoo on default drive keys (issue 24): for every preset, the
three-step start at 8 rotor angles, a speed demo scaled to the motor, +-76 % torque steps at 10 % of
base speed, flying starts at +-5, +-50, +-100 % of base speed and the demo at the lowest sampling
rate the parameter ranges allow; one pass / fail cell per motor and test, with the reason.

Only the machine preset and scenario-level keys (profiles, durations, windows, dyno speed) are set;
every drive key keeps its default rule. Scaling rules (documented in docs/zoo.md):
* base speed N_b: where the steady-state voltage at the MTPA point of the rated current reaches
  Vdc/sqrt(3) (`Machine.base_speed_rpm` at `Machine.mtpa(i_rated)`, Rs drop included);
* demo: scenarios/sensorless_demo.toml's time table, its speeds (100, 600, -200 rpm on the thesis
  motor, N_b = 890 rpm) as the same shares of N_b, the load 50 % of the rated torque;
* start: the three-step start on a locked rotor at 8 angles; a motor without saliency (uses_if)
  starts by I/f instead (startup.init_pos = auto): free rotor, 50 % reactive load, speed mode to
  0.2 N_b, steady angle error after the hand-over;
* torque steps: +-76 % of the rated torque in torque mode, the dyno at 10 % of N_b, the start the
  drive picks (startup.init_pos = auto: three steps, or I/f);
* flying starts: scenarios/flying/catch_dyno.toml at the dyno speed, then 50 % rated torque;
* the lowest sampling rate: the demo at the drive's f_s,min for the motor (`fs_min_hz`: 20 samples a
  period at the no-load base speed, check_sampling in drive_config.c), rounded up to the R10 series
  (2, 2.5, 3.15, 4, 5, 6.3, 8, 10, 12.5, 16, 20 kHz), with LOW_FS_SEEDS seeds; and the demo at 2 kHz
  (control.ts_s's upper bound) wherever that is below f_s,min: the drive must refuse it with the
  reason (a refusal, kept apart from a failure).
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from mctools.preset import FS_RANGE_HZ, PresetError, find_preset, fs_min_hz, load_preset, search_dirs
from mctools.report import _clear_outputs, find_mcsim, read_metrics, run_mcsim
from mctools.sweep.common import SweepInputError, f_toml, number, parse_floats, write_outputs
from mctools.sweep.envelope import replace_doc_section

STEADY_MAX_DEG = 3.0       # steady angle error allowed (issue 24 acceptance)
PEAK_FACTOR = 1.1          # peak phase current allowed, x the configured limit
START_ANGLES = tuple(float(a) for a in range(0, 360, 45))
THESIS_BASE_RPM = 890.0    # sun2016-ipm-5kw, the demo's motor: its speeds are shares of this
DEMO_SPEEDS = (100.0, 600.0, -200.0)
TORQUE_SHARE = 0.76
TORQUE_SPEED_SHARE = 0.10
FLY_SHARES = (0.05, 0.5, 1.0)
DOC_MARKERS = ("<!-- zoo:begin -->", "<!-- zoo:end -->")
LOW_TS_S = 500e-6          # control.ts_s upper bound (docs/simulator.md): 2 kHz
LOW_FS_SEEDS = (1, 2, 3)   # the demo at f_s,min: sensor-noise seeds
# PWM frequencies an engineer would pick: the R10 preferred numbers (ISO 3) between 2 and 20 kHz
PWM_STEPS_HZ = (2000.0, 2500.0, 3150.0, 4000.0, 5000.0, 6300.0, 8000.0, 10000.0, 12500.0, 16000.0, 20000.0)
SCEN_DEMO = "scenarios/sensorless_demo.toml"
SCEN_START = "scenarios/thesis/initpos_sweep.toml"
SCEN_FLY = "scenarios/flying/catch_dyno.toml"
SHORT = {"demo": 0.5, "torque": 1.0}
IF_START_SPEED_SHARE = 0.2 # the I/f start's speed target, x N_b ...
IF_START_DUR = 0.6
IF_START_HANDOVER_X = 1.5  # ... at least this x the hand-over speed the drive reports (`mcsim check`)
IF_SALIENCY_MIN = 0.05     # |Lq/Ld - 1| below this: the zoo starts the motor with I/f (uses_if)   # --short: a smoke run's durations (each keeps one window)

TESTS = (("start", "start, 8 angles"), ("demo", "speed demo"), ("torque", "±76 % torque"),
         ("fly5", "fly ±5 %"), ("fly50", "fly ±50 %"), ("fly100", "fly ±100 %"),
         ("demo_low_fs", "demo at the lowest f_s the rules allow"))


@dataclass
class Motor:
    name: str
    base_rpm: float
    torque_nm: float
    i_rated_a: float
    f_sample_hz: float
    lq_over_ld: float
    fs_min_hz: float = float("nan")   # the drive's rule (mctools.preset.fs_min_hz)

    @property
    def fs_low_hz(self) -> float:
        """f_s,min rounded up to a PWM frequency (PWM_STEPS_HZ), at least 2 kHz; NaN above 20 kHz."""
        return next((f for f in PWM_STEPS_HZ if f >= self.fs_min_hz), float("nan"))


@dataclass
class Run:
    motor: str
    test: str
    label: str
    scenario: Path
    sets: tuple[str, ...]
    dir: Path
    metrics: dict | None = None
    error: str | None = None
    exit_code: int | None = None
    seconds: float = 0.0
    log_tail: str = ""
    refused: str = ""     # the drive refused the configuration (mcsim exit 2): its reason
    expect_refusal: bool = False   # a run the rules must refuse (2 kHz below f_s,min)


@dataclass
class Cell:
    motor: str
    test: str
    passed: bool
    text: str
    numbers: dict = field(default_factory=dict)
    refused: bool = False   # every run refused with a reason (not a pass, not a silent failure)


# ---------------------------------------------------------------------------------------------
# Motors and the scaled scenarios

def motor_info(name: str) -> Motor:
    m = load_preset(name)
    for key in ("i_rated_peak_a", "torque_rated_nm", "vdc_nominal_v"):
        if not math.isfinite(getattr(m, key)):
            raise SweepInputError(f"preset {name}: no {key}: the zoo scales its tests to it")
    p = m.mtpa(m.i_rated_peak_a)
    base = m.base_speed_rpm(p.i_d, p.i_q)
    if not base > 0.0:
        raise SweepInputError(f"preset {name}: the rated MTPA voltage exceeds Vdc/sqrt(3) at "
                              f"standstill (base speed 0)")
    _, ld, lq = m.small_signal()
    return Motor(name, base, m.torque_rated_nm, m.i_rated_peak_a, m.f_sample_hz, lq / ld, fs_min_hz(m))


def all_presets() -> list[str]:
    names = []
    for d in search_dirs():
        if d.is_dir():
            names += [p.stem for p in sorted(d.glob("*.toml"))]
        if names:
            break
    return names


def scenario_path(rel: str) -> Path:
    """A shipped scenario: relative to the working directory, else to the source checkout."""
    p = Path(rel)
    if p.is_file():
        return p
    q = Path(__file__).resolve().parents[3] / rel
    return q if q.is_file() else p


def _profile(points) -> str:
    return "[" + ", ".join(f"[{f_toml(t)}, {f_toml(v)}]" for t, v in points) + "]"


def demo_toml(m: Motor, short: bool) -> str:
    lo, hi, neg = (round(m.base_rpm * s / THESIS_BASE_RPM, 1) for s in DEMO_SPEEDS)
    load = round(0.5 * m.torque_nm, 4)
    dur = SHORT["demo"] if short else 3.0
    band = max(0.02 * abs(neg), 0.5)
    return f"""# Generated by `mctools sweep zoo` for {m.name}: the shape of {SCEN_DEMO} (its time table),
# speeds as the thesis demo's shares of base speed (N_b = {m.base_rpm:.0f} rpm here, {THESIS_BASE_RPM:g}
# rpm on the thesis motor), the load 50 % of the rated torque. Default drive keys.
[scenario]
name = "zoo demo {m.name}: 0 -> {lo:g} -> {hi:g} -> {neg:g} rpm, 50 % load"
duration_s = {f_toml(dur)}

[machine]
preset = "{m.name}"

[mechanics]
mode = "inertia"
load_torque_nm = {_profile([(0.0, 0.0), (0.15, 0.0), (0.3, load)])}

[control]
mode = "speed"
angle_source = "unop"
speed_ref_rpm = {_profile([(0.0, 0.0), (0.5, 0.0), (0.6, lo), (1.0, lo), (1.5, hi), (2.0, hi),
                           (2.6, neg)])}

[estimator]
model = "fluxmap"

[metrics]
start_s = 0.05
settle_from_s = 2.6
settle_signal = "speed"
settle_band = {f_toml(band)}
{_windows([("standstill_loaded", 0.35, 0.5), ("plus_lo", 0.8, 1.0), ("plus_hi", 1.6, 2.0),
           ("minus", 2.7, 3.0)], dur)}"""


def torque_toml(m: Motor, short: bool) -> str:
    n = round(TORQUE_SPEED_SHARE * m.base_rpm, 1)
    t = round(TORQUE_SHARE * m.torque_nm, 4)
    dur = SHORT["torque"] if short else 1.6
    return f"""# Generated by `mctools sweep zoo` for {m.name}: +-76 % rated torque steps at 10 % of base speed
# (the shape of scenarios/envelope/torque_steps_300rpm.toml in torque mode, the start chosen by the
# drive: startup.init_pos = auto, the three steps of scenarios/brodatzki/torque_steps_1000rpm.toml
# on a salient motor, else I/f; in torque mode I/f holds its frame until the dyno turns the rotor
# above the hand-over speed). Default drive keys.
[scenario]
name = "zoo torque steps {m.name}: +-{t:g} N m at {n:g} rpm"
duration_s = {f_toml(dur)}

[machine]
preset = "{m.name}"

[mechanics]
mode = "dyno"
dyno_speed_rpm = {_profile([(0.0, 0.0), (0.2, 0.0), (0.4, n)])}
theta0_deg = 20.0

[control]
mode = "torque"
angle_source = "unop"
torque_ref_nm = {_profile([(0.0, 0.0), (0.5, 0.0), (0.5, t), (1.0, t), (1.0, -t)])}

[estimator]
model = "fluxmap"

[startup]
init_pos = "auto"            # three_step where the model's saliency is usable, else the I/f start

[metrics]
start_s = 0.05
{_windows([("plus_76pct", 0.8, 1.0), ("minus_76pct", 1.3, 1.6)], dur)}"""


def if_start_toml(m: Motor, n: float | None = None) -> str:
    n = round(IF_START_SPEED_SHARE * m.base_rpm, 1) if n is None else round(n, 1)
    load = round(0.5 * m.torque_nm, 4)
    return f"""# Generated by `mctools sweep zoo` for {m.name}: the I/f start (no usable saliency: a locked
# rotor cannot follow an open-loop frame): free rotor, a reactive load of 50 % rated torque from
# the start, speed mode to {n:g} rpm ({IF_START_SPEED_SHARE:g} x N_b, or {IF_START_HANDOVER_X:g} x the drive's hand-over speed
# where that is higher), startup.init_pos = auto (the drive picks I/f), the rotor angle set per
# run. Default drive keys.
[scenario]
name = "zoo I/f start {m.name}: 50 % reactive load, 0 -> {n:g} rpm"
duration_s = {f_toml(IF_START_DUR)}

[machine]
preset = "{m.name}"

[mechanics]
mode = "inertia"
load_kind = "reactive"
load_torque_nm = {f_toml(load)}
theta0_deg = 0.0

[control]
mode = "speed"
angle_source = "unop"
speed_ref_rpm = {_profile([(0.0, 0.0), (0.05, 0.0), (0.25, n)])}

[estimator]
model = "fluxmap"

[startup]
init_pos = "auto"

[metrics]
start_s = 0.0
{_windows([("after_handover", 0.45, IF_START_DUR)], IF_START_DUR)}"""


def drive_handover_rpm(mcsim: str, scenario: Path) -> float | None:
    """The I/f hand-over speed the drive chose for a scenario, as `mcsim check` reports it
    (`mcsim: note: the drive runs I/f below N rpm`), or None."""
    try:
        p = subprocess.run([mcsim, "check", str(scenario)], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    hit = re.search(r"runs I/f below ([0-9.eE+-]+) rpm", p.stderr + p.stdout)
    return float(hit.group(1)) if hit else None


def uses_if(m: Motor) -> bool:
    """The harness's guess of the drive's choice (startup.init_pos = auto decides by the HF current
    difference between the axes against the ADC quantum, drive_config.c): no saliency to speak
    of. A wrong guess shows as a failing cell, not as a silent pass."""
    return abs(m.lq_over_ld - 1.0) < IF_SALIENCY_MIN


def _windows(ws, dur: float) -> str:
    out = []
    for name, a, b in ws:
        if a < dur:  # a smoke run keeps only the windows it reaches
            out.append(f"[[metrics.window]]\nname = \"{name}\"\nfrom_s = {f_toml(a)}\n"
                       f"to_s = {f_toml(min(b, dur))}")
    return "\n".join(out) + "\n"


def build_runs(motors: list[Motor], out: Path, angles, short: bool, mcsim: str | None = None) -> list[Run]:
    runs = []
    for m in motors:
        d = out / m.name
        d.mkdir(parents=True, exist_ok=True)
        demo, torque = d / "demo.toml", d / "torque_steps.toml"
        demo.write_text(demo_toml(m, short), encoding="utf-8")
        torque.write_text(torque_toml(m, short), encoding="utf-8")
        pre = (f'machine.preset="{m.name}"', "output.trace=false")
        start = scenario_path(SCEN_START)
        if uses_if(m):
            start = d / "start_if.toml"
            start.write_text(if_start_toml(m), encoding="utf-8")
            # the start is judged after the hand-over: the target above the drive's own w_h
            w_h = drive_handover_rpm(mcsim, start) if mcsim else None
            if w_h is not None and IF_START_SPEED_SHARE * m.base_rpm < IF_START_HANDOVER_X * w_h:
                start.write_text(if_start_toml(m, IF_START_HANDOVER_X * w_h), encoding="utf-8")
        for a in angles:
            runs.append(Run(m.name, "start", f"theta0={a:g}", start,
                            (*pre, f"mechanics.theta0_deg={f_toml(a)}"), d / f"start_{a:g}"))
        runs.append(Run(m.name, "demo", "demo", demo, pre, d / "demo"))
        runs.append(Run(m.name, "torque", "torque", torque, pre, d / "torque"))
        fly_t = _profile([(0.0, 0.0), (0.1, 0.0), (0.1, round(0.5 * m.torque_nm, 4))])
        for share in FLY_SHARES:
            for sign in (1, -1):
                n = round(sign * share * m.base_rpm, 1)
                sets = (*pre, f"mechanics.dyno_speed_rpm={f_toml(n)}", f"control.torque_ref_nm={fly_t}")
                runs.append(Run(m.name, f"fly{round(100 * share)}", f"{n:+g} rpm", scenario_path(SCEN_FLY),
                                sets, d / f"fly_{'p' if sign > 0 else 'm'}{round(100 * share)}"))
        f_lo = m.fs_low_hz
        if math.isfinite(f_lo):
            for seed in LOW_FS_SEEDS:
                runs.append(Run(m.name, "demo_low_fs", f"{f_lo / 1e3:g} kHz, seed {seed}", demo,
                                (*pre, f"control.ts_s={f_toml(1.0 / f_lo)}", f"scenario.seed={seed}"),
                                d / f"demo_low_fs_s{seed}"))
        if not f_lo == 1.0 / LOW_TS_S:   # 2 kHz is below f_s,min: the drive must refuse it
            runs.append(Run(m.name, "demo_low_fs", "2 kHz", demo,
                            (*pre, f"control.ts_s={f_toml(LOW_TS_S)}"), d / "demo_2khz", expect_refusal=True))
    return runs


def execute(r: Run, mcsim: str) -> Run:
    r.dir.mkdir(parents=True, exist_ok=True)
    _clear_outputs(r.dir)
    r.exit_code, log, r.seconds, cmd = run_mcsim(mcsim, r.scenario, r.sets, r.dir)
    if r.exit_code != 0:
        (r.dir / "mcsim.log").write_text(" ".join(cmd) + "\n" + log, encoding="utf-8")
        lines = [ln.strip() for ln in log.splitlines() if ln.strip()]
        r.log_tail = lines[-1][:160] if lines else ""
        r.error = f"run failed (exit {r.exit_code})"
        # a configuration the drive refuses names the key and the reason after the file's name
        why = next((ln[ln.index("key '"):] for ln in lines
                    if ln.startswith("mcsim: error:") and "key '" in ln), "")
        if r.exit_code == 2 and why:
            r.refused = why
        return r
    r.metrics, r.error = read_metrics(r.dir)
    return r


# ---------------------------------------------------------------------------------------------
# Cells

def _peak(mx: dict) -> tuple[float | None, float | None]:
    return number(mx.get("current_peak_a")), number(mx.get("current_limit_a"))


def judge_run(r: Run, need_windows: bool) -> tuple[bool, list[str], dict]:
    """(passed, reasons, numbers) of one run by the zoo's criteria."""
    if r.metrics is None:
        why = r.error or "run failed"
        return False, [why + (f": {r.log_tail}" if r.log_tail else "")], {}
    mx, reasons = r.metrics, []
    faults = list(mx.get("faults") or [])
    t = number(mx.get("fault_time_s"))
    if faults:
        reasons.append(", ".join(faults) + (f" at {t:.2f} s" if t is not None else ""))
    steady = number(mx.get("angle_err_steady_max_deg"))
    # windows the drive spent in I/f's open loop (no estimated angle: the frame's load angle is
    # left out of the angle error by mcsim; the window still counts for faults and current)
    wins = mx.get("windows") or {}
    in_if = [k for k, w in wins.items() if (number((w or {}).get("if_open_share")) or 0.0) >= 0.5]
    if need_windows:
        if steady is None:
            if not faults:
                reasons.append("in I/f (open loop) in every window" if in_if else "no steady window ran")
        elif abs(steady) > STEADY_MAX_DEG:
            reasons.append(f"steady {abs(steady):.1f}°")
    peak, lim = _peak(mx)
    if peak is not None and lim:
        if peak > PEAK_FACTOR * lim:
            reasons.append(f"peak {peak:.3g} A = {peak / lim:.2f} × limit")
    nums = {"faults": faults, "fault_time_s": t, "steady_deg": None if steady is None else abs(steady),
            "angle_err_max_deg": number(mx.get("angle_err_max_deg")), "current_peak_a": peak,
            "current_limit_a": lim, "final_state": mx.get("final_state"), "if_windows": in_if}
    return not reasons, reasons, nums


def _where(r: Run) -> dict:
    """How to run it again: the scenario, the --set keys and the run folder."""
    return {"scenario": str(r.scenario), "sets": list(r.sets), "dir": str(r.dir)}


def refused_cell(test: str, runs: list[Run]) -> Cell | None:
    """The cell of a test whose every run the drive refused (the same reason): None otherwise."""
    if not runs or not all(r.refused for r in runs):
        return None
    return Cell(runs[0].motor, test, False, f"refused: {runs[0].refused}",
                {"refused": runs[0].refused, "runs": [_where(r) for r in runs]}, refused=True)


def judge_start(runs: list[Run]) -> Cell:
    """8 of 8: polarity right, no fault, in RUN, |init error (mean over 20 ms)| <= 3 deg, current."""
    wrong, bad_err, faults, failed, not_run, over = [], [], {}, [], [], []
    worst_err, worst_pk, per = 0.0, 0.0, []
    for r in runs:
        a = r.label.split("=")[1]
        ok, reasons, nums = judge_run(r, need_windows=False)
        mx = r.metrics or {}
        pol = mx.get("polarity_correct")
        err = number(mx.get("init_pos_err_mean_deg"))
        if r.metrics is None:
            failed.append((a, reasons[0]))
        else:
            if pol is not True:
                wrong.append(a)
                ok = False
            elif err is None or abs(err) > STEADY_MAX_DEG:
                bad_err.append(a)
                ok = False
            else:
                worst_err = max(worst_err, abs(err))
            if mx.get("final_state") != "RUN" and not nums["faults"]:
                not_run.append(f"{a}: {mx.get('final_state')}")
                ok = False
            for f in nums["faults"]:
                faults.setdefault(f, []).append(a)
            pk, lim = _peak(mx)
            if pk is not None and lim:
                worst_pk = max(worst_pk, pk / lim)
                if pk > PEAK_FACTOR * lim:
                    over.append(a)
        per.append({"angle": a, "passed": ok, "polarity_correct": pol, "init_pos_err_mean_deg": err,
                    **nums, **_where(r)})
    n_ok = sum(1 for p in per if p["passed"])
    if n_ok == len(runs):
        text = f"pass {n_ok}/{len(runs)}, init ≤ {worst_err:.1f}°, peak {worst_pk:.2f}×"
    else:
        def at(xs):
            return "all" if len(xs) == len(runs) else ", ".join(xs) + "°"
        parts = [f"**{n_ok}/{len(runs)}**"]
        if wrong:
            parts.append(f"polarity wrong at {at(wrong)}")
        if bad_err:
            parts.append(f"init error > {STEADY_MAX_DEG:g}° at {at(bad_err)}")
        parts += [f"{f} at {at(xs)}" for f, xs in faults.items()]
        if not_run:
            parts.append("ended in " + ", ".join(not_run))
        if over:
            parts.append(f"peak up to {worst_pk:.2f} × limit ({at(over)})")
        if failed:
            parts.append(f"{failed[0][1]} ({at([a for a, _ in failed])})")
        text = "; ".join(parts)
    return Cell(runs[0].motor, "start", n_ok == len(runs), text, {"angles": per})


def judge_if_start(runs: list[Run]) -> Cell:
    """The I/f start: at every angle no fault, RUN, steady <= 3 deg after the hand-over, current."""
    per, bad, worst, worst_pk = [], [], 0.0, 0.0
    for r in runs:
        a = r.label.split("=")[1]
        ok, reasons, nums = judge_run(r, need_windows=True)
        if (r.metrics or {}).get("final_state") != "RUN" and not nums.get("faults"):
            ok = False
            reasons.append(f"ended in {(r.metrics or {}).get('final_state')}")
        if ok:
            worst = max(worst, nums["steady_deg"] or 0.0)
        pk, lim = nums.get("current_peak_a"), nums.get("current_limit_a")
        if pk is not None and lim:
            worst_pk = max(worst_pk, pk / lim)
        if not ok:
            bad.append(f"{a}°: {'; '.join(reasons)}")
        per.append({"angle": a, "passed": ok, "reasons": reasons, **nums, **_where(r)})
    n_ok = len(runs) - len(bad)
    if not bad:
        text = f"pass {n_ok}/{len(runs)} (I/f, 50 % load), steady ≤ {worst:.1f}°, peak {worst_pk:.2f}×"
    else:
        text = f"**{n_ok}/{len(runs)}** (I/f, 50 % load); " + " / ".join(bad[:3]) + (" / ..." if len(bad) > 3 else "")
    return Cell(runs[0].motor, "start", not bad, text, {"angles": per})


def judge_low_fs(runs: list[Run]) -> Cell:
    """The demo at f_s,min (every seed must pass) and 2 kHz below it (must be refused: not a failure,
    a refusal with the reason); f_s,min above 20 kHz: every f_s refused."""
    at_min = [r for r in runs if not r.expect_refusal]
    below = [r for r in runs if r.expect_refusal]
    f_lo = at_min[0].label.split(",")[0] if at_min else ""
    if at_min:
        cell = judge_cell("demo", at_min)
        ok, text, nums = cell.passed, cell.text.replace(f"{f_lo}, ", ""), dict(cell.numbers)
    else:
        ok, text, nums = False, "f_s,min above the 20 kHz range", {"runs": []}
    if below:
        r = below[0]
        nums["below"] = {"label": r.label, "refused": r.refused, **_where(r)}
        if r.refused and not r.refused.startswith("key 'control.ts_s'"):
            ok = False
            text += f"; **2 kHz refused for another reason**: {r.refused}"
        elif r.refused:
            # the allowed period from the reason (the whole reason is in the JSON)
            m = re.search(r"allowed range \[[^,]+, ([^\]]+)\]", r.refused)
            short = f"control.ts_s ≤ {float(m.group(1)) * 1e6:.4g} µs" if m else r.refused
            text += f"; 2 kHz refused ({short})" if at_min else f": 2 kHz refused ({short})"
        else:
            ok = False
            text += "; **2 kHz not refused** (the rule and mctools.preset.fs_min_hz disagree)"
    text = (f"{f_lo} × {len(at_min)} seeds: " if at_min else "") + text
    refused_only = not at_min and bool(below) and bool(below[0].refused)
    return Cell(runs[0].motor, "demo_low_fs", ok, text, nums, refused=refused_only)


def judge_cell(test: str, runs: list[Run]) -> Cell:
    if test == "demo_low_fs":
        return judge_low_fs(runs)
    refused = refused_cell(test, runs)
    if refused is not None:
        return refused
    if test == "start" and Path(runs[0].scenario).name == "start_if.toml":
        return judge_if_start(runs)
    if test == "start":
        return judge_start(runs)
    parts, all_ok, per = [], True, []
    for r in runs:
        ok, reasons, nums = judge_run(r, need_windows=True)
        all_ok &= ok
        per.append({"label": r.label, "passed": ok, "reasons": reasons, **nums, **_where(r)})
        pre = f"{r.label}: " if len(runs) > 1 else ""
        if ok:
            pk, lim = nums["current_peak_a"], nums["current_limit_a"]
            parts.append(f"{pre}{nums['steady_deg']:.1f}°"
                         + (f", peak {pk / lim:.2f}×" if pk is not None and lim else "")
                         + (f" (I/f in {', '.join(nums['if_windows'])})" if nums["if_windows"] else ""))
        else:
            parts.append(f"{pre}{'; '.join(reasons)}")
    text = ("pass " if all_ok else "**FAIL** ") + " / ".join(parts)
    return Cell(runs[0].motor, test, all_ok, text, {"runs": per})


# ---------------------------------------------------------------------------------------------
# Outputs

def git_commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def zoo_markdown(motors: list[Motor], cells: dict, command: str, stamp: str, n_runs: int,
                 wall: float) -> str:
    n_pass = sum(1 for c in cells.values() if c.passed)
    n_ref = sum(1 for c in cells.values() if c.refused)
    lines = [f"`{command}` ({stamp}; {n_runs} runs in {wall:.0f} s). Default drive keys; a cell "
             f"passes with no fault, steady angle error ≤ {STEADY_MAX_DEG:g}° in the steady windows "
             f"(the start: polarity right, the init error's 20 ms mean ≤ {STEADY_MAX_DEG:g}° and RUN "
             f"at every angle), peak phase current ≤ {PEAK_FACTOR:g} × the configured limit "
             f"(`current_limit_a`); else the reasons (fault at its time, the worst number). *refused*: the "
             f"drive refused the configuration with the reason shown (mcsim exit 2).", "",
             "| motor | N_b [rpm] | rated [N m] | f_s [kHz] | f_s,min [kHz] (run at) | Lq/Ld |",
             "|---|---|---|---|---|---|"]
    for m in motors:
        lines.append(f"| {m.name} | {m.base_rpm:.0f} | {m.torque_nm:g} | {m.f_sample_hz / 1e3:g} | "
                     f"{m.fs_min_hz / 1e3:.3g} ({m.fs_low_hz / 1e3:g}) | {m.lq_over_ld:.2f} |")
    lines += ["", "| motor | " + " | ".join(t for _, t in TESTS) + " |",
              "|---|" + "---|" * len(TESTS)]
    for m in motors:
        lines.append(f"| {m.name} | " + " | ".join(cells[(m.name, k)].text if (m.name, k) in cells
                                                  else "—" for k, _ in TESTS) + " |")
    lines += ["", f"Cells: {n_pass} of {len(cells)} pass, {n_ref} refused with a reason, "
                  f"{len(cells) - n_pass - n_ref} fail."]
    return "\n".join(lines)


def cmd_zoo(args) -> int:
    if args.jobs < 1:
        raise SweepInputError("--jobs must be at least 1")
    names = [s.strip() for s in args.motors.split(",") if s.strip()] if args.motors else all_presets()
    if not names:
        raise SweepInputError("no motors: no presets found and no --motors given")
    if len(set(names)) != len(names):
        raise SweepInputError("--motors: a motor twice")
    try:
        motors = [motor_info(n) for n in names]
    except PresetError as exc:
        raise SweepInputError(str(exc)) from None
    angles = START_ANGLES
    if args.angles:
        angles = tuple(parse_floats(args.angles, "--angles"))
    mcsim = find_mcsim(args.mcsim)
    out = Path(args.out or "out/sweep/zoo")
    runs = build_runs(motors, out, angles, args.short, mcsim)
    t0, done = time.monotonic(), 0
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(execute, r, mcsim) for r in runs]
        for fut in as_completed(futures):
            r = fut.result()
            done += 1
            status = r.error or (", ".join(r.metrics.get("faults") or []) or "ok")
            print(f"[{done}/{len(runs)}] {r.motor} {r.test} {r.label} ... {status} "
                  f"({r.seconds:.1f} s)", file=sys.stderr, flush=True)
    wall = time.monotonic() - t0
    cells = {}
    for m in motors:
        for k, _ in TESTS:
            sel = [r for r in runs if r.motor == m.name and r.test == k]
            if sel:
                cells[(m.name, k)] = judge_cell(k, sel)
    stamp = f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, commit {git_commit()}"
    command = "mctools sweep zoo" + (f" --motors {','.join(names)}" if args.motors else "") \
        + (" --short" if args.short else "") + (f" --angles {args.angles}" if args.angles else "")
    md = zoo_markdown(motors, cells, command, stamp, len(runs), wall)
    data = {"command": command, "stamp": stamp, "wall_s": wall, "runs_total": len(runs),
            "criteria": {"steady_max_deg": STEADY_MAX_DEG, "peak_factor": PEAK_FACTOR,
                         "low_ts_s": LOW_TS_S, "low_fs_seeds": list(LOW_FS_SEEDS)},
            "motors": [vars(m) for m in motors],
            "cells": [{"motor": c.motor, "test": c.test, "passed": c.passed, "refused": c.refused,
                       "text": c.text, **c.numbers} for c in cells.values()]}
    write_outputs(args, md, data)
    if args.doc:
        replace_doc_section(Path(args.doc), md, DOC_MARKERS)
        print(f"wrote the zoo table of {args.doc}")
    n_ref = sum(1 for c in cells.values() if c.refused)
    n_fail = sum(1 for c in cells.values() if not c.passed and not c.refused)
    print(f"sweep zoo: {len(motors)} motors x {len(TESTS)} tests, {len(cells) - n_fail - n_ref} pass, "
          f"{n_ref} refused, {n_fail} fail; {len(runs)} runs in {wall:.1f} s ({args.jobs} at a time)")
    return 1 if args.strict and n_fail else 0


def add_parser(ssub) -> None:
    z = ssub.add_parser("zoo", help="the motor zoo on default keys: start, demo, torque steps, "
                                    "flying starts, low f_s; one pass/fail cell per motor x test")
    z.add_argument("--motors", metavar="A,B,...",
                   help="preset names (default: every preset in presets/)")
    z.add_argument("--angles", metavar="DEG,...",
                   help="start angles (default 0, 45, ..., 315)")
    z.add_argument("--short", action="store_true",
                   help="smoke run: the demo cut to 0.5 s, the torque steps to 1 s (one steady "
                        "window each; the cells judge what ran)")
    z.add_argument("--jobs", type=int, default=2, metavar="N", help="simulations in parallel (default 2)")
    z.add_argument("--out", metavar="DIR", help="run folders and generated scenarios (default out/sweep/zoo)")
    z.add_argument("--mcsim", metavar="PATH",
                   help="simulator binary (default: build/host/sim/app/mcsim, else mcsim on PATH)")
    z.add_argument("--json", metavar="FILE", help="write the results as JSON")
    z.add_argument("--md", metavar="FILE", help="also write the printed markdown here")
    z.add_argument("--doc", metavar="FILE",
                   help="put the table between <!-- zoo:begin --> and <!-- zoo:end --> in FILE "
                        "(appended with the markers if they are missing)")
    z.add_argument("--strict", action="store_true", help="exit 1 when any cell fails")
    z.set_defaults(func=cmd_zoo)
