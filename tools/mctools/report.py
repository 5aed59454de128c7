"""`mctools report`: run the thesis scenarios with mcsim and write the comparison table.

expected.toml (format documented at its top) lists one [[check]] per figure of merit. Every
distinct (scenario, set, model) is simulated once; the table in the doc is built only from the
metrics.json files those runs write, so the numbers in the doc can always be regenerated.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from mctools.errors import InputError

MODELS = ("const", "fluxmap")
MODEL_TITLES = {"const": "ours, constant parameters", "fluxmap": "ours, flux map"}
CHECK_KEYS = {"scenario", "set", "models", "metric", "what", "thesis", "bound", "seeds",
              "percentile", "calibration"}
MIN_SEEDS = 10          # a percentile check needs at least this many seeds
MAX_SEEDS = 1000
DEFAULT_PERCENTILE = 90.0
REQUIRED_KEYS = ("scenario", "models", "metric", "what")
HEADLINE = ("angle_err_steady_max_deg", "angle_err_max_deg", "settling_time_s", "newton_iter_mean")
UNITS = (("_deg", "°"), ("_rpm", " rpm"), ("_pct", " %"), ("_nm", " N m"), ("_s", " s"),
         ("_a", " A"), ("_v", " V"))
DEFAULT_MCSIM = "build/host/sim/app/mcsim"
REGEN_SCRIPT = "bash scripts/report.sh"
DASH = "—"
PASS_MARK = "✓"
FAIL_MARK = "✗ **FAIL**"
# Realism profiles (scenario.profile, docs/simulator.md). The bounds are for BASE_PROFILE; the
# others `--profiles` adds are reported beside it (one run per check key, the scenario's own seed,
# no trace), never judged: a value outside the bound only gets OUTSIDE_MARK.
PROFILES = ("realistic", "ideal", "harsh")
BASE_PROFILE = "realistic"
OUTSIDE_MARK = "⚠ outside bound"


class ReportInputError(InputError):
    """Bad expected.toml, scenario folder or arguments; the CLI turns it into exit status 2."""


# ---------------------------------------------------------------------------------------------
# Bounds

_BOUND_RE = re.compile(r"^\s*(abs\s+)?(<=|>=|==|<|>)\s*(\S+)\s*$")
_RANGE_RE = re.compile(r"^\s*(abs\s+)?in\s*\[\s*([^,\s]+)\s*,\s*([^\]\s]+)\s*\]\s*$")
_OPS = {
    "<=": lambda a, b: a <= b,
    ">=": lambda a, b: a >= b,
    "<": lambda a, b: a < b,
    ">": lambda a, b: a > b,
    # Exact equality is what "== 0" on counters means; the tolerance only absorbs the decimal
    # round trip of a float through JSON text.
    "==": lambda a, b: math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0),
    "in": lambda a, b: b[0] <= a <= b[1],
}


@dataclass(frozen=True)
class Bound:
    text: str
    use_abs: bool
    op: str
    limit: object  # float, or (lo, hi) for "in [lo, hi]"

    def holds(self, value) -> bool:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False  # null or non-numeric never satisfies an acceptance bound
        v = abs(value) if self.use_abs else float(value)
        if math.isnan(v):
            return False
        return _OPS[self.op](v, self.limit)

    def __str__(self) -> str:
        return self.text.strip()


def parse_bound(text: str) -> Bound:
    """'abs <= X' | '<= X' | '>= X' | '== X' | '< X' | '> X' | 'in [A, B]' (abs works with every
    operator; 'abs in [3, 7]' checks a magnitude whose sign convention may differ)."""
    if not isinstance(text, str):
        raise ValueError(f"bound must be a string like \"<= 2\", got {text!r}")
    r = _RANGE_RE.match(text)
    if r:
        try:
            lo, hi = float(r.group(2)), float(r.group(3))
        except ValueError:
            raise ValueError(f"bad bound {text!r}: the range needs two numbers") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ValueError(f"bad bound {text!r}: need finite lo <= hi")
        return Bound(text, bool(r.group(1)), "in", (lo, hi))
    m = _BOUND_RE.match(text)
    if not m:
        raise ValueError(f"bad bound {text!r} (expected 'abs <= X', '<= X', '>= X', '== X', "
                         f"'< X' or '> X')")
    try:
        limit = float(m.group(3))
    except ValueError:
        raise ValueError(f"bad bound {text!r}: {m.group(3)!r} is not a number") from None
    if not math.isfinite(limit):
        raise ValueError(f"bad bound {text!r}: limit must be finite")
    return Bound(text, bool(m.group(1)), m.group(2), limit)


def nearest_rank(values, p: float, high: bool = True):
    """The nearest-rank P-th percentile of `values` (numbers and None): the smallest value with at
    least P % of the values at or below it (`high`), or, for the lower tail, the largest value with
    at least P % at or above it. None (a null metric or a failed run) counts as the worst value on
    that side, so the result is None when more than 100 - P % of the values are None. With 10
    values, P = 90 is the 9th of 10: one outlier is allowed, two are not."""
    n = len(values)
    if n == 0:
        return None
    k = max(1, math.ceil(p / 100.0 * n - 1e-9))
    nums = sorted(float(v) for v in values if v is not None)  # the nulls count as the worst
    if not high:
        nums.reverse()
    return nums[k - 1] if k <= len(nums) else None


def seed_values(values, use_abs: bool) -> list:
    """Numbers of a metric over seeds (abs when the bound is on the magnitude); None for a null,
    absent or non-numeric value or a failed run."""
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            out.append(None)
        else:
            out.append(abs(float(v)) if use_abs else float(v))
    return out


def percentile_check(bound: Bound, values, p: float) -> tuple[bool, float | None, float | None]:
    """(holds, low, high): the bound holds at percentile P over seeds when it holds for the
    P-th percentile from the top (high) and from the bottom (low) of the values (of |value| for
    an `abs` bound): `<= X` then asks that at least P % of the seeds are <= X, `>= X` that at
    least P % are >= X, a range or `==` both."""
    vals = seed_values(values, bound.use_abs)
    hi = nearest_rank(vals, p, high=True)
    lo = nearest_rank(vals, p, high=False)
    ok = hi is not None and lo is not None and bound.holds(hi) and bound.holds(lo)
    return ok, lo, hi


# ---------------------------------------------------------------------------------------------
# expected.toml

@dataclass(frozen=True)
class Check:
    index: int  # 1-based position among the [[check]] tables, as people count them
    scenario: str
    sets: tuple[str, ...]
    models: tuple[str, ...]
    metric: str
    what: str
    thesis: str
    bounds: dict  # model -> Bound
    seeds: int | None = None  # evaluate the bounds over scenario.seed = 1..seeds
    percentile: float | None = None  # ... at this percentile (nearest rank)
    calibration: frozenset = frozenset()  # models whose bound was tuned to the result

    def run_keys(self):
        return [(self.scenario, self.sets, m) for m in self.models]


def _is_str_list(v) -> bool:
    return isinstance(v, list) and all(isinstance(x, str) for x in v)


def load_expected(scen_dir: Path) -> list[Check]:
    path = scen_dir / "expected.toml"
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ReportInputError(f"{path}: no such file") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ReportInputError(f"{path}: not valid TOML: {exc}") from None
    extra = sorted(set(data) - {"check"})
    if extra:
        raise ReportInputError(f"{path}: unknown top-level key(s) {', '.join(extra)} "
                               f"(only [[check]] tables)")
    raw = data.get("check")
    if not isinstance(raw, list) or not raw:
        raise ReportInputError(f"{path}: no [[check]] tables")
    checks = []
    for i, c in enumerate(raw, start=1):
        def bad(key, msg):
            return ReportInputError(f"{path}: check {i}, key '{key}': {msg}")

        unknown = sorted(set(c) - CHECK_KEYS)
        if unknown:
            raise bad(unknown[0], f"unknown key (allowed: {', '.join(sorted(CHECK_KEYS))})")
        for key in REQUIRED_KEYS:
            if key not in c:
                raise bad(key, "missing")
        for key in ("scenario", "metric", "what", "thesis"):
            if key in c and not isinstance(c[key], str):
                raise bad(key, f"must be a string, got {c[key]!r}")
        scenario = c["scenario"]
        if not re.fullmatch(r"[A-Za-z0-9._-]+", scenario) or scenario.startswith("."):
            raise bad("scenario", f"{scenario!r} is not a plain file name (without .toml)")
        if not (scen_dir / f"{scenario}.toml").is_file():
            raise bad("scenario", f"no scenario file {scen_dir / (scenario + '.toml')}")
        if not c["metric"].strip():
            raise bad("metric", "empty")
        sets = c.get("set", [])
        if not _is_str_list(sets):
            raise bad("set", f"must be a list of \"key=value\" strings, got {sets!r}")
        for s in sets:
            k = s.split("=", 1)[0].strip()
            if "=" not in s or not k:
                raise bad("set", f"{s!r} is not key=value")
            if k == "estimator.model":
                raise bad("set", "estimator.model is chosen by 'models', not by 'set'")
        models = c["models"]
        if not _is_str_list(models) or not models:
            raise bad("models", f"must be a non-empty list of {' / '.join(MODELS)}, got {models!r}")
        for m in models:
            if m not in MODELS:
                raise bad("models", f"unknown model {m!r} (known: {', '.join(MODELS)})")
        if len(set(models)) != len(models):
            raise bad("models", f"duplicate model in {models!r}")
        bound_raw = c.get("bound", {})
        if not isinstance(bound_raw, dict):
            raise bad("bound", f"must be a table model = \"<= X\", got {bound_raw!r}")
        bounds = {}
        for m, text in bound_raw.items():
            if m not in MODELS:
                raise bad("bound", f"unknown model {m!r} (known: {', '.join(MODELS)})")
            if m not in models:
                raise bad("bound", f"bound for model {m!r}, which the check does not run")
            try:
                bounds[m] = parse_bound(text)
            except ValueError as exc:
                raise bad("bound", f"{m}: {exc}") from None
        seeds, pct = c.get("seeds"), c.get("percentile")
        if seeds is not None:
            if isinstance(seeds, bool) or not isinstance(seeds, int) \
                    or not MIN_SEEDS <= seeds <= MAX_SEEDS:
                raise bad("seeds", f"must be an integer in {MIN_SEEDS}..{MAX_SEEDS}, got {seeds!r}")
            if not bounds:
                raise bad("seeds", "a check without a bound has nothing to evaluate over seeds")
        if pct is not None:
            if seeds is None:
                raise bad("percentile", "needs 'seeds'")
            if isinstance(pct, bool) or not isinstance(pct, (int, float)) \
                    or not 50.0 <= float(pct) <= 100.0:
                raise bad("percentile", f"must be a number in 50..100, got {pct!r}")
            pct = float(pct)
        elif seeds is not None:
            pct = DEFAULT_PERCENTILE
        cal = c.get("calibration", False)
        if isinstance(cal, bool):
            cal = frozenset(bounds) if cal else frozenset()
        elif _is_str_list(cal):
            for m in cal:
                if m not in bounds:
                    raise bad("calibration", f"model {m!r} has no bound in this check")
            cal = frozenset(cal)
        else:
            raise bad("calibration", f"must be true/false or a list of models, got {cal!r}")
        checks.append(Check(i, scenario, tuple(sets), tuple(models), c["metric"].strip(),
                            c["what"], c.get("thesis", ""), bounds, seeds, pct, cal))
    return checks


# ---------------------------------------------------------------------------------------------
# Runs

@dataclass
class Run:
    scenario: str
    sets: tuple[str, ...]
    model: str
    dir: Path
    seed: int | None = None  # scenario.seed of a percentile run (None: the scenario's own)
    profile: str = BASE_PROFILE  # scenario.profile; another than the base is set explicitly
    exit_code: int | None = None
    seconds: float = 0.0
    metrics: dict | None = None
    error: str | None = None  # why there are no metrics, in the words of the table
    plots: list[Path] = field(default_factory=list)

    @property
    def label(self) -> str:
        return " ".join([self.scenario, *self.sets, self.model]
                        + ([f"seed={self.seed}"] if self.seed is not None else [])
                        + ([f"profile={self.profile}"] if self.profile != BASE_PROFILE else []))

    @property
    def extra_sets(self) -> tuple[str, ...]:
        # percentile and other-profile runs: only metrics.json is read, so no trace (the fprintf
        # is a third of a long run)
        if self.profile != BASE_PROFILE:
            return ("output.trace=false", profile_set(self.profile))
        if self.seed is None:
            return ()
        return ("output.trace=false", f"scenario.seed={self.seed}")

    @property
    def ok(self) -> bool:
        return self.error is None


def model_set(model: str) -> str:
    # mcsim reads --set values as TOML, so the string needs its quotes inside the argument.
    return f'estimator.model="{model}"'


def profile_set(profile: str) -> str:
    return f'scenario.profile="{profile}"'


def parse_profiles(text: str | None) -> tuple[str, ...]:
    """--profiles "realistic,harsh": the base profile (the one the bounds are for) first, then the
    reported ones in the order given."""
    if text is None:
        return (BASE_PROFILE,)
    names = [s.strip() for s in text.split(",") if s.strip()]
    unknown = [n for n in names if n not in PROFILES]
    if unknown or not names:
        raise ReportInputError(f"--profiles: unknown profile(s) {', '.join(unknown) or '(none)'}"
                               f" (known: {', '.join(PROFILES)})")
    if BASE_PROFILE not in names:
        raise ReportInputError(f"--profiles must include {BASE_PROFILE}: the bounds are judged "
                               f"on it, the others are reported beside it")
    if len(set(names)) != len(names):
        raise ReportInputError(f"--profiles: duplicate profile in {text!r}")
    return (BASE_PROFILE, *(n for n in names if n != BASE_PROFILE))


def _sanitise(s: str) -> str:
    s = s.replace('"', "").replace("'", "")
    return re.sub(r"[^A-Za-z0-9._=+-]+", "_", s).strip("_")


def run_dir_names(keys) -> dict:
    """<scenario>[__<sanitised set>]__<model>, unique: a name two different runs would share
    (or one too long for a file system) gets a short hash of the set list."""
    names = {}
    for key in keys:
        scenario, sets, model = key
        names[key] = "__".join([scenario, *(_sanitise(s) for s in sets), model])
    counts = {}
    for n in names.values():
        counts[n] = counts.get(n, 0) + 1
    for key, n in names.items():
        if counts[n] > 1 or len(n) > 150:
            model = key[2]
            digest = hashlib.sha1("\0".join(key[1]).encode()).hexdigest()[:8]
            names[key] = f"{n[: -len(model) - 2][:120]}_{digest}__{model}"
    return names


def _clear_outputs(d: Path) -> None:
    # A failed run must not be reported with the numbers of an earlier, successful one.
    for name in ("metrics.json", "trace.csv", "mcsim.log"):
        (d / name).unlink(missing_ok=True)
    shutil.rmtree(d / "plots", ignore_errors=True)


def run_mcsim(mcsim: str, scenario: Path, sets, out_dir: Path) -> tuple[int, str, float, list[str]]:
    """One `mcsim run`: (exit code, its output, wall seconds, the command). 127 if it cannot
    start. Shared by report and sweep."""
    cmd = [mcsim, "run", str(scenario)]
    for s in sets:
        cmd += ["--set", s]
    cmd += ["--out", str(out_dir), "--quiet"]
    t0 = time.monotonic()
    try:
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              stdin=subprocess.DEVNULL)
        code, log = proc.returncode, proc.stdout.decode("utf-8", errors="replace")
    except OSError as exc:
        code, log = 127, f"cannot start {mcsim}: {exc}\n"
    return code, log, time.monotonic() - t0, cmd


def read_metrics(run_dir: Path) -> tuple[dict | None, str | None]:
    """(metrics, None) from run_dir/metrics.json, or (None, the reason the run counts as failed)."""
    try:
        data = json.loads((run_dir / "metrics.json").read_text(encoding="utf-8"))
        if not isinstance(data, dict):
            raise ValueError("not a JSON object")
        return data, None
    except FileNotFoundError:
        return None, "run failed (no metrics.json)"
    except (ValueError, UnicodeDecodeError):
        return None, "run failed (bad metrics.json)"


def execute(run: Run, mcsim: str, scen_dir: Path) -> Run:
    try:
        run.dir.mkdir(parents=True, exist_ok=True)
        _clear_outputs(run.dir)
    except OSError as exc:
        run.error = f"run failed ({exc.strerror or exc})"
        return run
    run.exit_code, log, run.seconds, cmd = run_mcsim(
        mcsim, scen_dir / f"{run.scenario}.toml", (*run.sets, *run.extra_sets, model_set(run.model)),
        run.dir)
    (run.dir / "mcsim.log").write_text(" ".join(cmd) + "\n" + log, encoding="utf-8")
    if run.exit_code != 0:
        run.error = f"run failed (exit {run.exit_code})"
        return run
    run.metrics, run.error = read_metrics(run.dir)
    return run


def render_plots(run: Run, scen_title: str, dpi: int) -> None:
    from mctools.plot import plot_trace
    from mctools.trace import TraceError, load_trace

    trace_path = run.dir / "trace.csv"
    if not trace_path.is_file():
        return
    keys = [k for k in HEADLINE if isinstance(run.metrics.get(k), (int, float))]
    title = f"{scen_title} — {', '.join(run.sets) + ', ' if run.sets else ''}{run.model}"
    try:
        run.plots = plot_trace(load_trace(trace_path), run.dir / "plots", title=title,
                               metrics=run.metrics if keys else None, dpi=dpi,
                               headline=keys or None)
    except (TraceError, ValueError, OSError) as exc:
        # The plots are an aid; the table does not depend on them.
        print(f"report: warning: {run.label}: no plots: {exc}", file=sys.stderr)


# ---------------------------------------------------------------------------------------------
# Formatting

def fmt_number(v: float) -> str:
    """Three significant digits, written out in full (1520, 12.3, 1.50, 0.0280)."""
    if v == 0 or not math.isfinite(v):
        return "0" if v == 0 else str(v)
    r = float(f"{v:.3g}")
    exp = math.floor(math.log10(abs(r)))
    if exp < -3 or exp >= 6:
        return f"{r:.2e}"
    return f"{r:.{max(0, 2 - exp)}f}"


def unit_of(metric: str) -> str:
    name = metric.rsplit(".", 1)[-1]
    for suffix, unit in UNITS:
        if name.endswith(suffix):
            return unit
    return ""


def fmt_value(v, metric: str) -> str:
    if v is None:
        return DASH
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return f"{v}{unit_of(metric)}"
    if isinstance(v, float):
        return f"{fmt_number(v)}{unit_of(metric)}"
    return str(v)


_MISSING = object()


def lookup(metrics: dict, dotted: str):
    """metrics.json value at a dotted path; _MISSING when a key on the way does not exist."""
    if dotted in metrics:
        return metrics[dotted]
    node = metrics
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return _MISSING
        node = node[part]
    return node


def _md(s: str) -> str:
    return s.replace("|", "\\|").replace("\n", " ")


@dataclass
class Cell:
    text: str
    failed: bool = False  # the bound for this model does not hold
    outside: bool = False  # a reported profile's value is outside the bound (never a failure)
    value: str = ""  # the text without the pass/fail mark, for messages


def pct_label(p: float) -> str:
    return f"p{p:g}"


def evaluate_seeds(check: Check, model: str, seed_runs: list) -> tuple[bool, str]:
    """(failed, text) of a percentile check over its seeds: the value(s) the bound is judged on."""
    bound = check.bounds[model]
    vals = [None if not r.ok else lookup(r.metrics, check.metric) for r in seed_runs]
    vals = [None if v is _MISSING else v for v in vals]
    ok, lo, hi = percentile_check(bound, vals, check.percentile)
    p, n = check.percentile, len(seed_runs)
    pre = "|x| " if bound.use_abs else ""
    f = lambda v: DASH if v is None else fmt_value(v, check.metric)  # noqa: E731
    if bound.op in ("<=", "<"):
        txt = f"{pre}{pct_label(p)} {f(hi)}"
    elif bound.op in (">=", ">"):
        txt = f"{pre}{pct_label(100 - p)} {f(lo)}"
    else:
        txt = f"{pre}{pct_label(100 - p)}..{pct_label(p)} {f(lo)}..{f(hi)}"
    nulls = sum(1 for v in vals if v is None or isinstance(v, bool)
                or not isinstance(v, (int, float)))
    outside = sum(1 for v in vals if not bound.holds(v))
    txt += f" over {n} seeds ({outside} outside the bound" + (
        f", {nulls} of them null/failed)" if nulls else ")")
    return not ok, txt


def evaluate(check: Check, model: str, run: Run | None, seed_runs: list | None = None) -> Cell:
    if model not in check.models or run is None:
        return Cell(DASH)
    bound = check.bounds.get(model)
    cal = " (calibration)" if model in check.calibration else ""
    if bound is not None and check.seeds and seed_runs:
        # judged on the percentile over seeds; the scenario's own seed is shown first
        v = lookup(run.metrics, check.metric) if run.ok else None
        one = run.error if not run.ok else (
            "— (absent)" if v is _MISSING else fmt_value(v, check.metric))
        failed, ptxt = evaluate_seeds(check, model, seed_runs)
        mark = FAIL_MARK if failed else PASS_MARK
        return Cell(f"{one}; {ptxt} {mark}{cal}", failed=failed, value=f"{one}; {ptxt}")
    if not run.ok:
        return Cell(run.error, failed=bound is not None, value=run.error)
    v = lookup(run.metrics, check.metric)
    text = "— (absent)" if v is _MISSING else fmt_value(v, check.metric)
    if v is _MISSING:
        v = None
    if bound is None:
        return Cell(text, value=text)
    if bound.holds(v):
        return Cell(f"{text} {PASS_MARK}{cal}", value=text)
    return Cell(f"{text} {FAIL_MARK}{cal}", failed=True, value=text)


def evaluate_profile(check: Check, model: str, run: Run | None) -> Cell:
    """A reported (not judged) cell of another realism profile: the value of its single run,
    marked with OUTSIDE_MARK when it is outside the check's bound (a bound over seeds is compared
    with this one value). `failed` stays False: such a value never fails the report; the mark is
    in `outside`, for the summary."""
    if model not in check.models or run is None:
        return Cell(DASH)
    bound = check.bounds.get(model)
    if not run.ok:
        return Cell(run.error, value=run.error, outside=bound is not None)
    v = lookup(run.metrics, check.metric)
    text = "— (absent)" if v is _MISSING else fmt_value(v, check.metric)
    if bound is None or bound.holds(None if v is _MISSING else v):
        return Cell(text, value=text)
    return Cell(f"{text} {OUTSIDE_MARK}", value=text, outside=True)


def _link(path: Path, doc_dir: Path) -> str:
    return Path(os.path.relpath(path, doc_dir)).as_posix()


def scenario_title(scen_dir: Path, scenario: str) -> str:
    try:
        data = tomllib.loads((scen_dir / f"{scenario}.toml").read_text(encoding="utf-8"))
        name = data.get("scenario", {}).get("name")
        if isinstance(name, str) and name.strip():
            return name.strip()
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError, AttributeError):
        pass  # mcsim reports a broken scenario file; the title is cosmetic
    return scenario


def regen_command(args) -> str:
    cmd = ["mctools", "report", "--scenarios", args.scenarios, "--out", args.out,
           "--doc", args.doc]
    if args.only:
        cmd += ["--only", args.only]
    profiles = parse_profiles(getattr(args, "profiles", None))
    if len(profiles) > 1:
        cmd += ["--profiles", ",".join(profiles)]
    return " ".join(cmd)


def cell(c: Check, m: str, runs: dict, seed_runs: dict | None = None) -> Cell:
    key = (c.scenario, c.sets, m)
    seeds = (seed_runs or {}).get(key)
    return evaluate(c, m, runs.get(key), seeds[: c.seeds] if seeds and c.seeds else None)


def profile_cell(c: Check, m: str, profile_runs: dict, profile: str) -> Cell:
    return evaluate_profile(c, m, profile_runs.get((profile, c.scenario, c.sets, m)))


def build_doc(checks, runs: dict, args, scen_dir: Path, doc_path: Path,
              seed_runs: dict | None = None, profile_runs: dict | None = None) -> str:
    doc_dir = doc_path.parent.resolve()
    profile_runs = profile_runs or {}
    others = parse_profiles(getattr(args, "profiles", None))[1:]
    lines = ["# Thesis comparison: results", ""]
    lines.append(f"Generated by `{regen_command(args)}` from `{_link(scen_dir / 'expected.toml', doc_dir)}`; "
                 f"regenerate all of it with `{REGEN_SCRIPT}`. Do not edit by hand: every number "
                 f"below comes from a simulator run of that command.")
    lines += ["", "The motor zoo on default keys (issue 24, `mctools sweep zoo`): [zoo.md](zoo.md)."]
    if args.only:
        lines += ["", f"**Partial report**: only the scenario(s) {args.only}."]
    lines += [
        "",
        "Legend: *thesis* is the thesis' value as it states it (experiment unless it says sim). "
        "*ours* are `mcsim` runs of the same scenario with the sensorless estimator using the "
        "thesis' constant parameters (`estimator.model = \"const\"`) or the flux map "
        "(`\"fluxmap\"`). "
        f"{PASS_MARK} the value is within the check's bound for that model, {FAIL_MARK} it is not "
        f"(a null value never is); {DASH} the model is not run for this check, or the metric is "
        "null (e.g. the error never settled). Numbers have 3 significant digits; units follow "
        "the metric name.",
        "",
        "Seed statistics: the sensor noise (`scenario.seed`) changes every number, so a bound that "
        "holds for the scenario's own seed may fail for another. A check with `seeds = N` is "
        "judged on the nearest-rank P-th percentile over `scenario.seed` = 1..N (N >= 10; P is "
        "the check's `percentile`, default 90): the cell shows the value of the scenario's own "
        "seed, then the percentile the bound is judged on (`p90` for `<=`, `p10` for `>=`, "
        "both for a range; of the magnitude `|x|` for an `abs` bound; a null or failed seed "
        "counts as the worst value). P = 90 over 10 seeds allows one outlier. "
        "*(calibration)* marks a bound the model was tuned to meet (the preset's `a_dq` fit "
        "against Figs. 6.13-6.15, `docs/machine-models.md`): it is checked, but it is not "
        "evidence. `mctools sweep seeds SCENARIO --n N` gives the full distribution of every "
        "metric, on all local cores or with `--scheduler ADDRESS` on a Dask distributed cluster "
        "(`tools/README.md`).",
        "",
    ]
    if others:
        names = ", ".join(f"`{p}`" for p in others)
        lines += [
            f"Realism profiles: the bounds, the percentile runs and every number outside the "
            f"*{', '.join(others)}* column(s) are for the default profile "
            f"(`scenario.profile = \"{BASE_PROFILE}\"`). The *{', '.join(others)}* column(s) "
            f"repeat each check's runs with `--set scenario.profile=\"...\"` ({names}; "
            f"`docs/simulator.md`, \"Realism profiles\") on the scenario's own seed only "
            f"(`scenario.seed` = 1 for every thesis scenario; no percentile runs, to keep the "
            f"time down, and no trace or plots). They are reported, not judged: a value outside "
            f"the check's bound is marked {OUTSIDE_MARK} (for a bound over seeds, the single "
            f"run is compared with it) but never fails the report.",
            "",
        ]
    head, rule = [], []
    for m in MODELS:
        head.append(MODEL_TITLES[m])
        head += [f"{MODEL_TITLES[m]}, {p}" for p in others]
    lines += [
        "| figure | quantity | thesis | " + " | ".join(head) + " | bound |",
        "|---|---|---|" + "---|" * len(head) + "---|",
    ]
    for c in checks:
        fig = c.scenario + (" (" + ", ".join(f"`{_md(s)}`" for s in c.sets) + ")" if c.sets else "")
        quantity = f"{_md(c.what)} (`{_md(c.metric)}`)"
        cells = []
        for m in MODELS:
            cells.append(cell(c, m, runs, seed_runs).text)
            cells += [profile_cell(c, m, profile_runs, p).text for p in others]
        bound = "; ".join(f"{m} `{b}`" + (" (calibration)" if m in c.calibration else "")
                          for m, b in c.bounds.items()) or DASH
        if c.seeds and c.bounds:
            bound += f" at {pct_label(c.percentile)} of {c.seeds} seeds"
        lines.append(f"| {fig} | {quantity} | {_md(c.thesis) or DASH} | "
                     + " | ".join(_md(x) for x in cells) + f" | {bound} |")
    lines += ["", "## Plots", "",
              f"Overview plots of every run. They are written to `{args.out}`, which is not "
              f"committed: the links work after running the command locally.", ""]
    scenarios = list(dict.fromkeys(c.scenario for c in checks))
    for s in scenarios:
        entries = []
        for key, run in runs.items():
            if key[0] != s:
                continue
            label = ", ".join([*run.sets, run.model])
            overview = run.dir / "plots" / "trace_overview.png"
            if not run.ok:
                entries.append(f"{label}: {run.error}")
            elif overview not in run.plots:
                entries.append(f"{label}: no trace plotted")
            else:
                entries.append(f"[{_md(label)}]({_link(overview, doc_dir)})")
        lines.append(f"- {s} ({_md(scenario_title(scen_dir, s))}): " + " · ".join(entries))
    lines.append("")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------

def find_mcsim(given: str | None) -> str:
    if given:
        if not (Path(given).is_file() and os.access(given, os.X_OK)):
            raise ReportInputError(f"--mcsim {given}: not an executable file")
        return given
    if Path(DEFAULT_MCSIM).is_file():
        return DEFAULT_MCSIM
    found = shutil.which("mcsim")
    if not found:
        raise ReportInputError(f"no mcsim at {DEFAULT_MCSIM} nor on PATH; build it with "
                               f"scripts/build.sh or pass --mcsim PATH")
    return found


SWEEP_KEYS = {"title", "args"}


def load_sweeps(scen_dir: Path) -> list[dict]:
    """scenarios/thesis/sweeps.toml: [[sweep]] tables with a title and the `mctools sweep`
    arguments (scenario paths relative to the scenarios folder). Optional file."""
    path = scen_dir / "sweeps.toml"
    if not path.exists():
        return []
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ReportInputError(f"{path}: not valid TOML: {exc}") from None
    sweeps = data.get("sweep", [])
    for i, sw in enumerate(sweeps, start=1):
        unknown = sorted(set(sw) - SWEEP_KEYS)
        if unknown or not isinstance(sw.get("title"), str) or not _is_str_list(sw.get("args")):
            raise ReportInputError(f"{path}: sweep {i}: needs title (string) and args (list of "
                                   f"strings){'; unknown ' + ', '.join(unknown) if unknown else ''}")
    return sweeps


def run_sweeps(scen_dir: Path, out_dir: Path, mcsim: str, jobs: int) -> tuple[str, list[str]]:
    """Run every [[sweep]] through `mctools sweep` and return its markdown for the doc (the
    sweeps' own summaries, verbatim) and the titles of those that failed."""
    sweeps = load_sweeps(scen_dir)
    if not sweeps:
        return "", []
    parts = ["\n## Sweeps (initial position, thesis chapter 5 and 7.2)\n\n"
             "Run by the same command from `" + str(scen_dir / "sweeps.toml") + "`; each block "
             "is the summary `mctools sweep` prints.\n"]
    failed = []
    for i, sw in enumerate(sweeps, start=1):
        argv = list(sw["args"])
        argv[1] = str(scen_dir / argv[1])   # [command, scenario, ...]
        md = out_dir / f"sweep_{i}.md"
        cmd = [sys.executable, "-m", "mctools", "sweep", *argv, "--mcsim", mcsim, "--jobs", str(jobs),
               "--out", str(out_dir / f"sweep_{i}"), "--md", str(md)]
        print(f"[sweep {i}/{len(sweeps)}] {sw['title']} ...", flush=True)
        r = subprocess.run(cmd, capture_output=True, text=True)
        parts.append(f"\n### {sw['title']}\n\n")
        if r.returncode != 0 or not md.exists():
            failed.append(sw["title"])
            parts.append(f"sweep failed (exit {r.returncode})\n")
            continue
        body = md.read_text(encoding="utf-8")
        # the sweep's own heading is replaced by the title above; keep the summary, not the
        # per-angle table (it is in the sweep's own .md in the run folder)
        lines, skipping = [], False
        for ln in body.splitlines():
            if ln.startswith("| θ0 |"):
                skipping = True
            elif skipping and not ln.startswith("|"):
                skipping = False
            if not skipping and not ln.startswith("### "):
                lines.append(ln)
        parts.append("\n".join(lines).strip() + "\n")
    return "".join(parts), failed


# Sections other commands write into the same document (`mctools sweep envelope --doc`), between
# their markers: a report keeps them instead of dropping them.
KEPT_MARKERS = (("<!-- envelope:begin -->", "<!-- envelope:end -->"),)


def kept_blocks(doc_path: Path) -> str:
    if not doc_path.exists():
        return ""
    text = doc_path.read_text(encoding="utf-8")
    out = ""
    for begin, end in KEPT_MARKERS:
        a, b = text.find(begin), text.find(end)
        if a >= 0 and b > a:
            out += "\n" + text[a:b + len(end)] + "\n"
    return out


def report(args) -> int:
    scen_dir = Path(args.scenarios)
    out_dir = Path(args.out)
    doc_path = Path(args.doc)
    if args.jobs < 1:
        raise ReportInputError("--jobs must be at least 1")
    checks = load_expected(scen_dir)
    if args.only:
        wanted = [s.strip() for s in args.only.split(",") if s.strip()]
        known = {c.scenario for c in checks}
        unknown = [s for s in wanted if s not in known]
        if unknown or not wanted:
            raise ReportInputError(f"--only: no check uses scenario(s) {', '.join(unknown) or '(none)'}"
                                   f" (known: {', '.join(sorted(known))})")
        checks = [c for c in checks if c.scenario in wanted]
    profiles = parse_profiles(getattr(args, "profiles", None))
    mcsim = find_mcsim(args.mcsim)

    keys = list(dict.fromkeys(k for c in checks for k in c.run_keys()))
    names = run_dir_names(keys)
    runs = {k: Run(k[0], k[1], k[2], out_dir / names[k]) for k in keys}
    titles = {s: scenario_title(scen_dir, s) for s in dict.fromkeys(k[0] for k in keys)}
    # percentile checks: each run key once more per seed 1..N (N: the most any of its checks
    # asks for), without a trace, into <run>/seeds/seed_NNNN/
    n_seeds = {}
    for c in checks:
        if c.seeds:
            for k in c.run_keys():
                if k[2] in c.bounds:
                    n_seeds[k] = max(n_seeds.get(k, 0), c.seeds)
    seed_runs = {k: [Run(k[0], k[1], k[2], runs[k].dir / "seeds" / f"seed_{s:04d}", seed=s)
                     for s in range(1, n + 1)] for k, n in n_seeds.items()}
    # other realism profiles: each run key once more, the scenario's own seed, no trace, into
    # <run>/profile_<name>/; reported beside the base profile, not judged
    profile_runs = {(p, *k): Run(k[0], k[1], k[2], runs[k].dir / f"profile_{p}", profile=p)
                    for p in profiles[1:] for k in keys}
    judged_runs = list(runs.values()) + [r for rs in seed_runs.values() for r in rs]
    all_runs = judged_runs + list(profile_runs.values())

    # Simulations run in worker threads (each just waits on its mcsim process); the plots are
    # drawn here in the main thread, one at a time, because matplotlib is not thread-safe.
    done = 0
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(execute, r, mcsim, scen_dir) for r in all_runs]
        for fut in as_completed(futures):
            run = fut.result()
            done += 1
            status = "" if run.ok else f"{run.error} "
            if run.seed is None or not run.ok or done == len(all_runs):
                print(f"[{done}/{len(all_runs)}] {run.label} ... {status}{run.seconds:.1f} s",
                      flush=True)
            if run.seed is None and run.profile == BASE_PROFILE and run.ok \
                    and not getattr(args, "no_plots", False):
                render_plots(run, titles[run.scenario], args.dpi)
            elif run.exit_code not in (0, None):
                log = run.dir / "mcsim.log"
                for ln in log.read_text(encoding="utf-8", errors="replace").splitlines()[-5:]:
                    print(f"    {ln}", file=sys.stderr)

    doc = build_doc(checks, runs, args, scen_dir, doc_path, seed_runs, profile_runs)
    sweep_failures = []
    if not args.only and not getattr(args, "no_sweeps", False):
        sweep_md, sweep_failures = run_sweeps(scen_dir, out_dir, mcsim, args.jobs)
        doc += sweep_md
    doc = doc.rstrip("\n") + "\n" + kept_blocks(doc_path)
    doc_path.parent.mkdir(parents=True, exist_ok=True)
    doc_path.write_text(doc, encoding="utf-8")

    n_bounds = sum(1 for c in checks if c.bounds)
    failed = []
    for c in checks:
        if any(cell(c, m, runs, seed_runs).failed for m in c.bounds):
            failed.append(c)
    for c in failed:
        print(f"report: FAIL check {c.index} ({c.scenario}, {c.metric}): "
              + "; ".join(f"{m} {cell(c, m, runs, seed_runs).value} "
                          f"(bound {b}{', calibration' if m in c.calibration else ''})"
                          for m, b in c.bounds.items()),
              file=sys.stderr)
    run_failures = [r for r in judged_runs if not r.ok]
    print(f"wrote {doc_path}")
    print(f"report: {len(checks)} checks, {n_bounds} with bounds, {len(failed)} failed")
    bounds = [(c, m) for c in checks for m in c.bounds]
    if any(c.seeds for c in checks) or any(c.calibration for c in checks):
        ev = [(c, m) for c, m in bounds if m not in c.calibration]
        ev_pct = [(c, m) for c, m in ev if c.seeds]
        print(f"report: {len(bounds)} bounds: {len(ev)} evidence ({len(ev_pct)} at a percentile "
              f"over seeds, {sum(1 for c, m in ev_pct if not cell(c, m, runs, seed_runs).failed)} "
              f"of them hold), {len(bounds) - len(ev)} calibration targets")
    if run_failures:
        print(f"report: {len(run_failures)} of {len(judged_runs)} runs failed: "
              + ", ".join(r.label for r in run_failures))
    for p in profiles[1:]:
        # reported, never counted in the exit status
        outside = [(c, m) for c, m in bounds if profile_cell(c, m, profile_runs, p).outside]
        print(f"report: profile {p} (reported, not judged): {len(outside)} of {len(bounds)} "
              f"bounded values outside the {BASE_PROFILE} bound"
              + "".join(f"\n  check {c.index} ({c.scenario}{' ' + ' '.join(c.sets) if c.sets else ''}"
                        f", {c.metric}) {m}: {profile_cell(c, m, profile_runs, p).value} "
                        f"(bound {c.bounds[m]})" for c, m in outside))
        failed_p = [r for r in profile_runs.values() if r.profile == p and not r.ok]
        if failed_p:
            print(f"report: profile {p}: {len(failed_p)} of {len(keys)} runs failed (reported, "
                  f"not counted): " + ", ".join(r.label for r in failed_p))
    if sweep_failures:
        print(f"report: sweeps failed: {', '.join(sweep_failures)}")
    return 1 if failed or run_failures or sweep_failures else 0


def add_parser(sub) -> None:
    p = sub.add_parser("report", help="run the thesis scenarios with mcsim and write the "
                                      "comparison table (docs/results.md)")
    p.add_argument("--mcsim", metavar="PATH",
                   help="simulator binary (default: build/host/sim/app/mcsim, else mcsim on PATH)")
    p.add_argument("--scenarios", metavar="DIR", default="scenarios/thesis",
                   help="folder with expected.toml and the scenarios (default scenarios/thesis)")
    p.add_argument("--out", metavar="DIR", default="out/thesis",
                   help="run folders and plots (default out/thesis)")
    p.add_argument("--doc", metavar="PATH", default="docs/results.md",
                   help="markdown file to write (default docs/results.md)")
    p.add_argument("--only", metavar="NAME[,NAME]",
                   help="only the checks of these scenarios")
    p.add_argument("--jobs", type=int, default=2, metavar="N",
                   help="simulations in parallel (default 2)")
    p.add_argument("--dpi", type=int, default=100, help="plot resolution (default 100)")
    p.add_argument("--no-plots", action="store_true",
                   help="skip the PNGs (tests that only need the bounds)")
    p.add_argument("--no-sweeps", action="store_true",
                   help="skip the sweeps of <scenarios>/sweeps.toml (they run unless --only)")
    p.add_argument("--profiles", metavar="NAME[,NAME]", default=None,
                   help="realism profiles (scenario.profile): realistic (default; the bounds are "
                        "for it) plus others to report beside it, e.g. realistic,harsh: one "
                        "run per check on the scenario's own seed, a column per model, never "
                        "judged")
    p.set_defaults(func=report)
