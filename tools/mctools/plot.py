"""Trace plots in the style of the thesis figures: stacked panels against time."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mctools.trace import Trace, TraceError, break_wraps, load_trace, wrap_deg

ACTUAL = dict(color="tab:blue", lw=1.2, ls="-")
ESTIMATE = dict(color="tab:red", lw=1.0, ls="--")
REFERENCE = dict(color="0.35", lw=1.0, ls=":")
EXTRA = dict(color="tab:green", lw=0.8, ls="-", alpha=0.6)


@dataclass(frozen=True)
class Line:
    column: str
    label: str
    style: dict
    primary: bool = True  # a panel is drawn only if one of its primary columns exists


@dataclass(frozen=True)
class Panel:
    key: str
    title: str
    ylabel: str
    lines: tuple[Line, ...]
    angle: bool = False


PANELS: tuple[Panel, ...] = (
    Panel("angle", "Rotor angle", "angle [deg el.]", (
        Line("theta_deg", r"$\theta$ actual", ACTUAL),
        Line("theta_hat_deg", r"$\hat\theta$ estimated", ESTIMATE),
        Line("theta_raw_deg", r"$\theta_{raw}$ estimator output", EXTRA, primary=False),
    ), angle=True),
    Panel("angle_err", "Angle estimation error", "error [deg el.]", (
        Line("angle_err_deg", r"$\hat\theta - \theta$", ACTUAL),
    ), angle=True),
    Panel("speed", "Speed", "speed [rpm]", (
        Line("speed_rpm", "actual", ACTUAL),
        Line("speed_hat_rpm", "estimated", ESTIMATE),
        Line("speed_ref_rpm", "reference", REFERENCE),
    )),
    Panel("current", "d-q currents", "current [A]", (
        Line("id_a", r"$i_d$", dict(color="tab:blue", lw=1.0)),
        Line("iq_a", r"$i_q$", dict(color="tab:orange", lw=1.0)),
        Line("id_ref_a", r"$i_d^*$", dict(color="navy", lw=1.0, ls="--")),
        Line("iq_ref_a", r"$i_q^*$", dict(color="saddlebrown", lw=1.0, ls="--")),
    )),
    Panel("torque", "Torque", "torque [N m]", (
        Line("torque_nm", r"$T_e$", ACTUAL),
        Line("torque_ref_nm", r"$T^*$", REFERENCE),
        Line("load_nm", r"$T_{load}$", dict(color="tab:purple", lw=1.0, ls="-.")),
    )),
)

WIDTH_IN = 8.0
OVERVIEW_ROW_IN = 2.0
OVERVIEW_HEAD_IN = 0.9
PANEL_HEIGHT_IN = 3.0


def derive_columns(trace: Trace) -> None:
    """Fill in columns that older traces lack but can be computed from others."""
    c = trace.columns
    if "angle_err_deg" not in c and "theta_deg" in c and "theta_hat_deg" in c:
        c["angle_err_deg"] = wrap_deg(c["theta_hat_deg"] - c["theta_deg"])


def available_panels(trace: Trace) -> list[Panel]:
    return [p for p in PANELS if any(ln.primary and ln.column in trace for ln in p.lines)]


def load_metrics(path) -> dict:
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise TraceError(f"{path}: no such metrics file") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise TraceError(f"{path}: not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise TraceError(f"{path}: metrics must be a JSON object")
    return data


def _flatten(d: dict, prefix: str = "") -> list[tuple[str, object]]:
    out = []
    for k, v in d.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out.extend(_flatten(v, name + "."))
        elif isinstance(v, (bool, int, float)):
            out.append((name, v))
    return out


# Order in which metric names make the headline: the verdict, then estimation errors,
# then the rest. The metrics schema belongs to the simulator, so match on name parts.
_PRIORITY = ("pass", "angle_err", "err", "rms", "max", "overshoot", "settl", "ripple")


def headline_metrics(metrics: dict, limit: int = 6, keys: list[str] | None = None) -> list[str]:
    """The figures for the title: `keys` (dotted paths) if given, else the top-level scalars
    ranked by _PRIORITY (per-window figures only when asked for by name)."""
    flat = _flatten(metrics)
    if keys:
        known = dict(flat)
        missing = [k for k in keys if k not in known]
        if missing:
            raise TraceError(f"metrics: no such figure(s): {', '.join(missing)}")
        items = [(k, known[k]) for k in keys]
        limit = len(items)
    else:
        items = [(k, v) for k, v in flat if "." not in k]

    def rank(item):
        name = item[0].lower()
        for k, word in enumerate(_PRIORITY):
            if word in name:
                return k
        return len(_PRIORITY)

    if not keys:
        items = sorted(items, key=rank)[:limit]  # sorted() is stable: file order within a rank
    out = []
    for name, v in items:
        if isinstance(v, bool):
            out.append(f"{name}: {'yes' if v else 'NO'}")
        elif isinstance(v, int):
            out.append(f"{name} = {v}")
        else:
            out.append(f"{name} = {v:.4g}")
    return out


def _draw_panel(ax, panel: Panel, trace: Trace, label: str, *, xlabel: bool) -> None:
    t = trace.t
    for ln in panel.lines:
        if ln.column not in trace:
            continue
        y = trace[ln.column]
        if panel.angle:
            tt, y = break_wraps(t, y)
        else:
            tt = t
        ax.plot(tt, y, label=ln.label, **ln.style)
    if panel.key == "angle":
        ax.set_ylim(-180, 180)
        ax.set_yticks([-180, -90, 0, 90, 180])
    ax.set_title(label, loc="left", fontsize=10)
    ax.set_ylabel(panel.ylabel)
    ax.grid(True, lw=0.4, alpha=0.6)
    # Outside the axes so the legend never hides data; constrained layout keeps the
    # stacked panels aligned regardless of legend width.
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    if len(t):
        ax.set_xlim(float(t[0]), float(t[-1]) if t[-1] > t[0] else float(t[0]) + 1e-9)
    if xlabel:
        ax.set_xlabel("time [s]")


def _figure_class():
    """matplotlib's Figure, imported at the first plot: `mctools` registers every subcommand
    (this module's add_parser) and `mctools preset` should not pay for importing matplotlib."""
    import matplotlib

    matplotlib.use("Agg")  # the tools run headless (CI, ssh); never pick an interactive backend
    from matplotlib.figure import Figure

    return Figure


def plot_trace(trace: Trace, out_dir, *, title: str | None = None, metrics: dict | None = None,
               dpi: int = 120, headline: list[str] | None = None) -> list[Path]:
    """Write <stem>_overview.png and one <stem>_<panel>.png per panel; return the paths."""
    Figure = _figure_class()
    derive_columns(trace)
    panels = available_panels(trace)
    if not panels:
        raise TraceError(f"{trace.path}: none of the plotted columns present "
                         f"(have: {', '.join(trace.columns)})")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = trace.path.stem
    if not title and metrics and isinstance(metrics.get("scenario"), str) and metrics["scenario"]:
        title = metrics["scenario"]
    title = title or trace.path.name
    head = headline_metrics(metrics, keys=headline) if metrics else []
    letters = [f"({chr(ord('a') + k)}) {p.title}" for k, p in enumerate(panels)]
    written = []

    n = len(panels)
    fig = Figure(figsize=(WIDTH_IN, OVERVIEW_HEAD_IN + OVERVIEW_ROW_IN * n), dpi=dpi,
                 layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for k, (ax, panel) in enumerate(zip(axes, panels)):
        _draw_panel(ax, panel, trace, letters[k], xlabel=(k == n - 1))
    suptitle = title
    if head:
        # Two metrics per line keeps the header short enough for an 8-inch figure.
        rows = ["    ".join(head[i:i + 2]) for i in range(0, len(head), 2)]
        suptitle += "\n" + "\n".join(rows)
    fig.suptitle(suptitle, fontsize=10)
    path = out_dir / f"{stem}_overview.png"
    fig.savefig(path, dpi=dpi)
    written.append(path)

    for label, panel in zip(letters, panels):
        fig = Figure(figsize=(WIDTH_IN, PANEL_HEIGHT_IN), dpi=dpi, layout="constrained")
        ax = fig.subplots()
        _draw_panel(ax, panel, trace, label, xlabel=True)
        fig.suptitle(title, fontsize=9)
        path = out_dir / f"{stem}_{panel.key}.png"
        fig.savefig(path, dpi=dpi)
        written.append(path)
    return written


def cmd_plot(args) -> int:
    trace = load_trace(args.trace)
    metrics = load_metrics(args.metrics) if args.metrics else None
    out_dir = Path(args.out) if args.out else trace.path.parent
    headline = [k.strip() for k in args.headline.split(",") if k.strip()] if args.headline else None
    if headline and metrics is None:
        raise TraceError("--headline needs --metrics")
    for p in plot_trace(trace, out_dir, title=args.title, metrics=metrics, dpi=args.dpi, headline=headline):
        print(p)
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("plot", help="render a simulator trace.csv into PNG panels")
    p.add_argument("trace", help="trace CSV written by the simulator")
    p.add_argument("--out", metavar="DIR", help="output directory (default: next to the trace)")
    p.add_argument("--title", help="figure title (default: the trace file name)")
    p.add_argument("--metrics", metavar="JSON", help="metrics.json to annotate headline figures")
    p.add_argument("--dpi", type=int, default=120, help="resolution (default 120)")
    p.add_argument("--headline", metavar="KEYS",
                   help="comma-separated metric names (dotted for windows) for the title")
    p.set_defaults(func=cmd_plot)
