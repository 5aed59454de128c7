"""`mctools sweep seeds`: one scenario over scenario.seed = 1..N: median, p5/p10/p90/p95, min/max
of every numeric metric; on the local cores or on a Dask distributed cluster (--scheduler)."""

from __future__ import annotations

import json
import math
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

from mctools.sweep.common import (
    DASH, SweepInputError, add_common_args, check_common, parse_sets, run_seed_batch, sets_text,
    write_outputs,
)

SEED_PCTS = (5.0, 10.0, 90.0, 95.0)
DEFAULT_BATCH = 8
CONNECT_TIMEOUT = "20s"  # to reach the Dask scheduler


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
# CLI

def add_parser(ssub) -> None:
    s = ssub.add_parser("seeds", help="one scenario over scenario.seed = 1..N: median, "
                                      "percentiles, min/max of every metric (local or Dask)")
    add_common_args(s, "out/sweep/seeds/<scenario>", jobs_default=None)
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
