"""`mctools sweep noise`: thesis Fig. 7.4, the Step II polarity decisions (generalized vs DVI) over
many seeded trials with random initial angles, per current-noise level."""

from __future__ import annotations

import random
import sys
from pathlib import Path

from mctools.sweep.common import (
    DASH, Point, SweepInputError, add_common_args, check_common, f_toml, metric, parse_floats,
    parse_sets, run_points, sets_text, write_outputs,
)

METHODS = ("generalized", "dvi")


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
             f"every level and method). Percentage of runs with `polarity_correct` true; "
             f"\"refused\": no polarity handed on (Step II undecided, a fault with the reason, "
             f"or a failed run), \"wrong\": a wrong polarity handed on.", "",
             "| noise rms | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
    for i, lv in enumerate(levels):
        cells = []
        for method in methods:
            r = summary[method]["levels"][i]
            mark = "" if r["pct"] is not None and r["pct"] >= args.min_pct else " ✗"
            extra = (f", {r['undecided']} refused" if r["undecided"] else "") + \
                (f", {r['wrong']} wrong" if r["wrong"] else "")
            cells.append(f"{r['pct']:.1f} % ({r['correct']}/{r['trials']}){extra}{mark}"
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
    if args.max_wrong is not None and args.max_wrong < 0:
        raise SweepInputError("--max-wrong must be 0 or more")
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
    if failed:
        return 1
    if args.max_wrong is not None:
        worst = max((r["wrong"], m, r["noise_a"]) for m in methods for r in summary[m]["levels"])
        if worst[0] > args.max_wrong:
            print(f"sweep noise: {worst[0]} wrong polarities handed on ({worst[1]} at "
                  f"{worst[2]:g} A), more than --max-wrong {args.max_wrong}", file=sys.stderr)
            return 1
    return 0


# ---------------------------------------------------------------------------------------------
# CLI

def add_parser(ssub) -> None:
    n = ssub.add_parser("noise", help="thesis Fig. 7.4: polarity decisions vs current noise, "
                                      "seeded trials with random initial angles")
    add_common_args(n, "out/sweep/noise")
    n.add_argument("--levels", default="0.02,0.05,0.1,0.2", metavar="A,A,...",
                   help="current noise rms levels in A (default 0.02,0.05,0.1,0.2)")
    n.add_argument("--trials", type=int, default=1000, metavar="N",
                   help="trials per method and level, scenario.seed = 1..N (default 1000)")
    n.add_argument("--methods", default="generalized,dvi", metavar="M,M",
                   help="Step II methods (default generalized,dvi)")
    n.add_argument("--angle-seed", type=int, default=1, metavar="S",
                   help="seed of the random initial angles (default 1)")
    n.add_argument("--max-wrong", type=int, default=None, metavar="N",
                   help="exit 1 if a method hands on more than N wrong polarities at a level "
                        "(a refusal is not wrong)")
    n.add_argument("--min-pct", type=float, default=99.0, metavar="P",
                   help="a level works when at least P %% of the trials are right (default 99)")
    n.set_defaults(func=cmd_noise)
