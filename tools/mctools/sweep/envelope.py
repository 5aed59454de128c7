"""`mctools sweep envelope`: the robustness envelope of sensorless control: estimator parameter
errors (one at a time) x scenarios, each cell over seeds 1..N, classified holds / recovers /
trips / runs off."""

from __future__ import annotations

import json
import os
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from mctools.report import find_mcsim
from mctools.sweep.common import SweepInputError, f_toml, number, run_seed_batch

ENVELOPE_SCENARIOS = ("scenarios/envelope/standstill_loaded.toml",
                      "scenarios/envelope/speed_reversal.toml",
                      "scenarios/envelope/torque_steps_300rpm.toml",
                      "scenarios/sensorless_demo.toml",
                      "scenarios/brodatzki/speed_demo.toml")
LOST_DEG = 90.0  # an angle error at or beyond this is a lost estimate
PEAK_NOTE_DEG = 45.0  # a holding cell names its transient peak from here on
CURRENT_NOTE_X = 1.1  # a cell names its peak phase current above this x the configured limit
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
              ("rs_scale", "Rs", (0.5, 0.7, 1.3, 2.0), ("const", "fluxmap")),
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
            "steady_deg": steady_angle_deg(metrics),
            "current_ratio": current_ratio(metrics)}


def current_ratio(m: dict) -> float | None:
    """The peak phase current over the configured limit (current_peak_a / current_limit_a)."""
    pk, lim = number(m.get("current_peak_a")), number(m.get("current_limit_a"))
    return pk / lim if pk is not None and lim else None


def percentile(xs: list[float], q: float) -> float | None:
    """The nearest-rank q-th percentile (the smallest value with at least q % of them at or
    below it); None for no values."""
    if not xs:
        return None
    v = sorted(xs)
    k = max(1, -(-len(v) * q // 100))   # ceil(n q / 100)
    return v[int(k) - 1]


def _deg(v: float | None, digits: int = 1) -> str:
    return "?" if v is None else f"{v:.{digits}f}°"


def _outcome_text(outcome: str, sel: list[dict], n: int) -> str:
    """The table text for the runs `sel` (out of n seeds) that share one outcome."""
    maxof = lambda key: max((r[key] for r in sel if r.get(key) is not None), default=None)
    reasons = list(dict.fromkeys(f for r in sel for f in r.get("faults", [])))
    notes = [f"{len(sel)}/{n}"] if len(sel) < n else []
    if outcome == "holds":
        text = f"holds {_deg(maxof('steady_deg'))}"
        p90 = percentile([r["steady_deg"] for r in sel if r.get("steady_deg") is not None], 90.0)
        if len(sel) >= 5 and p90 is not None:
            notes.append(f"p90 {_deg(p90)}")
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
    over = maxof("current_ratio")
    if over is not None and over > CURRENT_NOTE_X:
        notes.append(f"**current {over:.2f} × limit**")   # a limit is a limit, in every mode
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
             f"`{command}`: UNOP on the scenarios' motors (sun2016-ipm-5kw unless the column "
             f"is brodatzki's), one estimator parameter wrong at a time (the "
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
             f"fault, x = the steady error after; \"p90\": the 90th percentile of the steady "
             f"error over the seeds (5 or more); **current k × limit**: a seed's peak phase "
             f"current above {CURRENT_NOTE_X:g} × the configured limit (`current_peak_a` / "
             f"`current_limit_a`). L = the estimator's "
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


def replace_doc_section(doc: Path, section: str, markers: tuple[str, str] = (DOC_BEGIN, DOC_END)) -> None:
    """Puts `section` between the markers (default: the envelope's) of `doc`, replacing what is
    there, or appends the markers and the section (a new file holds only them)."""
    begin, end = markers
    block = f"{begin}\n{section.strip()}\n{end}"
    text = doc.read_text(encoding="utf-8") if doc.is_file() else ""
    if begin in text:
        a = text.index(begin)
        b = text.find(end, a)
        if b < 0:
            raise SweepInputError(f"{doc}: {begin} without {end}")
        text = text[:a] + block + text[b + len(end):]
    elif end in text:
        raise SweepInputError(f"{doc}: {end} without {begin}")
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

def add_parser(ssub) -> None:
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
