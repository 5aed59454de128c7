"""Command-line entry point: `mctools <command> ...` (also `python -m mctools`)."""

from __future__ import annotations

import argparse
import sys

from mctools import __version__, fit_adq, fly_current, plot, preset, report, sweep
from mctools.errors import EXIT_BAD_INPUT, InputError

# The subcommands, in the order `mctools --help` lists them. Each is a module with
# add_parser(sub): it adds its parser (or, for sweep, a parser with its own subcommands) and sets
# `func`, which takes the parsed arguments and returns the exit status. Input a subcommand refuses
# is an mctools.errors.InputError: main() prints it as one line and exits with EXIT_BAD_INPUT.
COMMANDS = (plot, preset, report, fit_adq, sweep, fly_current)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="mctools", description=__doc__)
    ap.add_argument("--version", action="version", version=f"mctools {__version__}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except InputError as exc:
        print(f"mctools {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RuntimeError as exc:  # e.g. flux inversion outside the model's valid range
        print(f"mctools {args.command}: error: {exc}", file=sys.stderr)
        return 1
