"""Command-line entry point: `mctools <command> ...` (also `python -m mctools`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mctools import __version__

EXIT_BAD_INPUT = 2


def _cmd_plot(args) -> int:
    # Imported here so `mctools preset` does not pay for importing matplotlib.
    from mctools.plot import load_metrics, plot_trace
    from mctools.trace import load_trace

    trace = load_trace(args.trace)
    metrics = load_metrics(args.metrics) if args.metrics else None
    out_dir = Path(args.out) if args.out else trace.path.parent
    headline = [k.strip() for k in args.headline.split(",") if k.strip()] if args.headline else None
    if headline and metrics is None:
        from mctools.trace import TraceError
        raise TraceError("--headline needs --metrics")
    for p in plot_trace(trace, out_dir, title=args.title, metrics=metrics, dpi=args.dpi, headline=headline):
        print(p)
    return 0


def _cmd_preset(args) -> int:
    from mctools.preset import derived_figures, find_preset, format_report, load_preset

    path = find_preset(args.preset, args.preset_dir)
    figs = derived_figures(load_preset(str(path)))
    if args.json:
        print(json.dumps(figs, indent=2))
    else:
        print(format_report(figs, path))
    return 0


def _cmd_report(args) -> int:
    from mctools.report import report

    return report(args)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="mctools", description=__doc__)
    ap.add_argument("--version", action="version", version=f"mctools {__version__}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("plot", help="render a simulator trace.csv into PNG panels")
    p.add_argument("trace", help="trace CSV written by the simulator")
    p.add_argument("--out", metavar="DIR", help="output directory (default: next to the trace)")
    p.add_argument("--title", help="figure title (default: the trace file name)")
    p.add_argument("--metrics", metavar="JSON", help="metrics.json to annotate headline figures")
    p.add_argument("--dpi", type=int, default=120, help="resolution (default 120)")
    p.add_argument("--headline", metavar="KEYS",
                   help="comma-separated metric names (dotted for windows) for the title")
    p.set_defaults(func=_cmd_plot)

    p = sub.add_parser("preset", help="print figures derived from a machine preset")
    p.add_argument("preset", metavar="NAME|PATH", help="preset name (presets/<name>.toml) or file")
    p.add_argument("--preset-dir", metavar="DIR",
                   help="directory to look up preset names in (also: env MC_PRESET_DIR)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.set_defaults(func=_cmd_preset)

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
    p.set_defaults(func=_cmd_report)

    from mctools.fit_adq import add_parser as add_fit_adq
    add_fit_adq(sub)

    from mctools.sweep import add_parser as add_sweep
    add_sweep(sub)

    from mctools.fly_current import add_parser as add_fly_current
    add_fly_current(sub)
    return ap


def main(argv=None) -> int:
    from mctools.fit_adq import FitInputError
    from mctools.fly_current import FlyCurrentInputError
    from mctools.preset import PresetError
    from mctools.report import ReportInputError
    from mctools.trace import TraceError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (TraceError, PresetError, ReportInputError, FitInputError, FlyCurrentInputError) as exc:
        print(f"mctools {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as exc:  # e.g. flux inversion outside the model's valid range
        print(f"mctools {args.command}: error: {exc}", file=sys.stderr)
        return 1
