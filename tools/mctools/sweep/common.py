"""What the sweeps of `mctools sweep` share: argument checks, the mcsim runs (one `Point` per
run, `jobs` at a time; a batch of seeds for the Dask workers), the numbers and their markdown
formatting, the written outputs and the common command-line options."""

from __future__ import annotations

import json
import math
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from mctools.report import ReportInputError, _clear_outputs, find_mcsim, read_metrics, run_mcsim

DASH = "—"


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
# Command-line options of the sweeps that run one scenario per point

def add_common_args(p, default_out: str, jobs_default: int | None = 2) -> None:
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


def add_angle_args(p, default_step: float) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--step-deg", type=float, metavar="DEG",
                   help=f"angles 0, DEG, 2 DEG, ... below 360 (default {default_step:g})")
    g.add_argument("--angles", metavar="A,B,...", help="explicit initial angles in degrees")
