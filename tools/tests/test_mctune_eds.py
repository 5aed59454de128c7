"""mctune's modules on their own: the EDS parser (mctools.mctune.eds) on the EDS the package ships
(tools/mctools/data/drive.eds, generated from the firmware), value formatting against it, and the
command line's registration (every subcommand parses --help; `python -m mctools.mctune`)."""

import argparse
import contextlib
import io
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

pytest.importorskip("canopen")

from mctools import mctune  # noqa: E402
from mctools.mctune.drive import format_value  # noqa: E402
from mctools.mctune.eds import (  # noqa: E402
    INT_RANGES, PARAM_BASE, PARAM_END, TELEM_BASE, TELEM_END, Eds, Entry, check_range, default_eds_path,
    parse_value,
)
from mctools.mctune.errors import InputError  # noqa: E402

ACCESS = {"INIT", "STANDSTILL", "RUNTIME"}


@pytest.fixture(scope="module")
def eds():
    return Eds(default_eds_path())


def test_shipped_eds_is_package_data():
    path = default_eds_path()
    assert path.is_file()
    assert path.parent.parent == Path(mctune.__file__).resolve().parent.parent   # mctools/data


def test_parameters(eds):
    params = eds.params()
    assert params and len({p.index for p in params}) == len(params)
    assert isinstance(eds.table_hash, int)   # what mctune compares with the drive's 0x2FF0
    for p in params:
        assert PARAM_BASE <= p.index <= PARAM_END and p.sub == 0 and not p.parent
        assert "." in p.name, p.name
        assert p.access in ACCESS, (p.name, p.access)
        # INIT parameters are read-only on the bus, the others writable (docs/can.md)
        assert p.writable == (p.access != "INIT"), p.name
        assert p.readable and p.default is not None, p.name
        assert p.is_float or p.data_type in INT_RANGES, (p.name, p.data_type)
        if p.low is not None and p.high is not None:
            assert p.low <= p.high, p.name
        # the default passes the range check `mctune set` applies before any write
        check_range(p, p.default, str(p.default), f"set {p.name}")
        if p.choices:
            assert 0 <= p.default < len(p.choices) and p.low == 0 and p.high == len(p.choices) - 1


def test_telemetry(eds):
    telem = eds.telemetry()
    assert telem
    for t in telem:
        assert TELEM_BASE <= t.index <= TELEM_END and t.name.startswith("telem."), t.name
        assert not t.writable, t.name
        assert eds.resolve(t.name.removeprefix("telem.")) == [t]   # named without the prefix


def test_resolve_by_name_case_and_index(eds):
    for p in eds.params():
        assert eds.resolve(p.name) == [p]
        assert eds.resolve(p.name.upper()) == [p]
        assert eds.resolve(f"0x{p.index:04X}") == [p]
        assert eds.resolve(f"0x{p.index:04x}:0") == [p]
    identity = eds.resolve("0x1018")   # a record: every sub-index
    assert len(identity) > 1 and all(e.index == 0x1018 and e.parent for e in identity)


def test_resolve_suggests_close_names(eds):
    names = {p.name for p in eds.params()}
    p = next(p for p in eds.params() if p.name[:-1] not in names)
    with pytest.raises(InputError, match="did you mean") as exc:
        eds.resolve(p.name[:-1])
    assert p.name in str(exc.value)


def test_values_round_trip_through_their_text(eds):
    # what `mctune get` prints, `mctune set` reads back: choices by name, integers exactly,
    # floats to the 7 significant digits format_value shows
    for p in eds.params():
        text = format_value(p, p.default, with_unit=False)
        v = parse_value(p, text)
        if p.is_float:
            assert abs(v - p.default) <= 5e-7 * abs(p.default), (p.name, text)
        else:
            assert v == p.default, (p.name, text)
        if p.choices:
            assert text == p.choices[p.default]


def test_choice_out_of_range_is_refused(eds):
    p = next(p for p in eds.params() if p.choices)
    with pytest.raises(InputError, match="out of range"):
        check_range(p, len(p.choices), str(len(p.choices)), f"set {p.name}")
    with pytest.raises(InputError, match="not one of the choices"):
        parse_value(p, "no-such-choice")


def test_every_mctune_subcommand_parses_help():
    ap = mctune.build_parser()
    sub = next(a for a in ap._actions if isinstance(a, argparse._SubParsersAction))
    assert sub.choices
    for name, p in sub.choices.items():
        assert callable(p.get_default("func")), name
        out = io.StringIO()
        with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as exc:
            ap.parse_args([name, "--help"])
        assert exc.value.code == 0 and out.getvalue().startswith(f"usage: mctune {name} ")
    assert all(a.help for a in sub._choices_actions)


def test_python_m_mctools_mctune():
    r = subprocess.run([sys.executable, "-m", "mctools.mctune", "--help"], capture_output=True,
                       text=True)
    assert r.returncode == 0 and r.stdout.startswith("usage: mctune ")


def test_console_scripts_point_at_the_entry_points():
    try:
        eps = metadata.entry_points(group="console_scripts")
    except metadata.PackageNotFoundError:   # pragma: no cover - not installed (PYTHONPATH run)
        pytest.skip("mctools is not installed")
    by_name = {ep.name: ep for ep in eps if ep.value.startswith("mctools.")}
    if not by_name:
        pytest.skip("mctools is not installed")
    from mctools import cli

    assert by_name["mctools"].load() is cli.main
    assert by_name["mctune"].load() is mctune.main


# CiA 301 Table 44: the integer types' codes, widths and signs
CIA301_INTEGERS = {0x01: ("BOOLEAN", 1, False), 0x02: ("INTEGER8", 8, True), 0x03: ("INTEGER16", 16, True),
                   0x04: ("INTEGER32", 32, True), 0x05: ("UNSIGNED8", 8, False), 0x06: ("UNSIGNED16", 16, False),
                   0x07: ("UNSIGNED32", 32, False), 0x15: ("INTEGER64", 64, True), 0x1B: ("UNSIGNED64", 64, False)}


def _entry(data_type, access_type="rw"):
    return Entry(index=0x2100, sub=0, name="x", parent="", var=None, data_type=data_type, access_type=access_type)


def test_integer_ranges_are_the_types_ranges():
    """`mctune set` refuses a value its data type cannot hold before any write: every integer type
    takes its whole range, ends included, and nothing one beyond either end (a value outside it
    would be truncated or refused by the drive with a less helpful abort)."""
    assert set(INT_RANGES) == set(CIA301_INTEGERS)
    for code, (name, bits, signed) in CIA301_INTEGERS.items():
        lo, hi = (-2**(bits - 1), 2**(bits - 1) - 1) if signed else (0, 2**bits - 1)
        e = _entry(code)
        for v in (lo, hi, (lo + hi) // 2):
            check_range(e, v, str(v), "set x")
        for v in (lo - 1, hi + 1):
            with pytest.raises(InputError, match=f"does not fit .*{name}"):
                check_range(e, v, str(v), "set x")


def test_readable_and_writable_follow_the_access_type():
    """CiA 306 access types: const and ro are read-only, wo write-only, rw/rwr/rww both. An
    access type the tool does not know is neither: mctune reads or writes no object whose access
    it cannot tell (an EDS from another tool, a typo)."""
    expect = {"const": (True, False), "ro": (True, False), "wo": (False, True), "rw": (True, True),
              "rwr": (True, True), "rww": (True, True)}
    for at, (r, w) in expect.items():
        e = _entry(0x07, at)
        assert (e.readable, e.writable) == (r, w), at
    for at in ("-", "0", "c", "con", "cons", "none", "x"):
        e = _entry(0x07, at)
        assert not e.readable and not e.writable, at
