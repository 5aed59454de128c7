"""The `mctools` command line: every subcommand is registered one way (a module's add_parser,
listed in cli.COMMANDS), has a help text and parses --help, and every subcommand's refused input
becomes one `mctools COMMAND: error: ...` line and exit status 2."""

import argparse
import contextlib
import importlib
import io
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import mctools
from mctools import cli
from mctools.errors import EXIT_BAD_INPUT, InputError

REPO = Path(__file__).resolve().parents[2]
SUBCOMMANDS = ["plot", "preset", "report", "fit-adq", "sweep", "fly-current"]
SWEEPS = ["angles", "table7_1", "noise", "seeds", "envelope", "zoo"]


def subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


def help_texts(parser: argparse.ArgumentParser) -> dict:
    return {a.dest: a.help for a in subparsers(parser)._choices_actions}


def test_every_module_with_add_parser_is_listed():
    # a module that can register a subcommand but is not in COMMANDS would never be reachable
    with_parser = set()
    for info in pkgutil.iter_modules(mctools.__path__):
        if info.name == "__main__":   # runs the command line when imported
            continue
        mod = importlib.import_module(f"mctools.{info.name}")
        if callable(getattr(mod, "add_parser", None)):
            with_parser.add(mod.__name__)
    assert with_parser == {m.__name__ for m in cli.COMMANDS}
    assert len(cli.COMMANDS) == len(set(cli.COMMANDS))


def test_each_module_registers_one_subcommand():
    names = []
    for mod in cli.COMMANDS:
        sub = argparse.ArgumentParser().add_subparsers()
        mod.add_parser(sub)
        assert len(sub.choices) == 1, mod.__name__
        names += list(sub.choices)
    assert names == SUBCOMMANDS


def test_subcommands_have_help():
    helps = help_texts(cli.build_parser())
    assert list(helps) == SUBCOMMANDS
    assert all(h and h.strip() for h in helps.values()), helps
    sweep = subparsers(cli.build_parser()).choices["sweep"]
    sweep_helps = help_texts(sweep)
    assert list(sweep_helps) == SWEEPS
    assert all(h and h.strip() for h in sweep_helps.values()), sweep_helps


@pytest.mark.parametrize("argv", [[c] for c in SUBCOMMANDS] + [["sweep", s] for s in SWEEPS])
def test_help_parses(argv):
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as exc:
        cli.main([*argv, "--help"])
    assert exc.value.code == 0
    assert out.getvalue().startswith(f"usage: mctools {' '.join(argv)} ")


def test_every_leaf_command_has_a_func():
    ap = cli.build_parser()
    for name, p in subparsers(ap).choices.items():
        if name == "sweep":
            for kind, q in subparsers(p).choices.items():
                assert callable(q.get_default("func")), kind
        else:
            assert callable(p.get_default("func")), name


@pytest.mark.parametrize("argv, words", [
    (["plot", "{tmp}/missing.csv"], "no such file"),
    (["preset", "no-such-preset", "--preset-dir", "{tmp}"], "no-such-preset"),
    (["report", "--jobs", "0"], "--jobs"),
    (["fit-adq", "--preset", "{tmp}/missing.toml"], "no such file"),
    (["sweep", "angles", "{tmp}/missing.toml"], "no such scenario file"),
    (["fly-current", str(REPO / "presets" / "sun2016-ipm-5kw.toml"), "--rpm", "x"], "--rpm"),
])
def test_input_errors_exit_2_with_one_line(argv, words, tmp_path):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = cli.main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    assert rc == EXIT_BAD_INPUT == 2
    lines = err.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"mctools {argv[0]}: error: ")
    assert words in lines[0]


def test_module_input_errors_are_input_errors():
    from mctools.fit_adq import FitInputError
    from mctools.fly_current import FlyCurrentInputError
    from mctools.preset import PresetError
    from mctools.report import ReportInputError
    from mctools.sweep.common import SweepInputError
    from mctools.trace import TraceError

    for cls in (FitInputError, FlyCurrentInputError, PresetError, ReportInputError,
                SweepInputError, TraceError):
        assert issubclass(cls, InputError), cls
    assert issubclass(FlyCurrentInputError, ValueError)   # as before the rename


def test_the_old_handover_name_is_gone():
    err = io.StringIO()
    with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as exc:
        cli.main(["handover", "sun2016-ipm-5kw"])
    assert exc.value.code == 2 and "invalid choice: 'handover'" in err.getvalue()


def test_building_the_parser_does_not_import_matplotlib():
    code = ("import sys; from mctools import cli; cli.build_parser(); "
            "sys.exit(1 if 'matplotlib' in sys.modules else 0)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_python_m_mctools():
    r = subprocess.run([sys.executable, "-m", "mctools", "--help"], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.startswith("usage: mctools ")
    for name in SUBCOMMANDS:
        assert name in r.stdout
