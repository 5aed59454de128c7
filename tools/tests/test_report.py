"""`mctools report` against a fake mcsim (no simulator runs here)."""

import contextlib
import io
import json
import sys
import textwrap

import pytest

from fakes import write_fake_mcsim
from mctools import cli
from mctools.report import fmt_number, fmt_value, parse_bound, run_dir_names

DPI = "30"  # the plots only have to exist

FAKE_BODY = r'''
# Stands in for mcsim: metrics depend on the model and on estimator.rs_scale; the scenario
# "broken" fails like a simulator crash.
out.mkdir(parents=True, exist_ok=True)
(out / "argv.json").write_text(json.dumps(a))
if scenario == "broken":
    print("mcsim: plant diverged", file=sys.stderr)
    sys.exit(1)
model = json.loads(sets["estimator.model"])  # a TOML string: must arrive with its quotes
scale = float(sets.get("estimator.rs_scale", "1"))
# Finish out of submission order when run in parallel.
time.sleep(0.15 if scenario == "alpha" and model == "const" else 0.0)
err = (1.234 if model == "fluxmap" else 7.891) * scale
metrics = {
    "angle_err_steady_max_deg": err,
    "angle_err_max_deg": 3 * err,
    "settling_time_s": 0.0456 if model == "fluxmap" else None,
    "newton_iter_mean": 2.5,
    "speed_final_rpm": 1523.4,
    "fault_count": 0,
    "windows": {"standstill": {"angle_err_mean_deg": -err / 2}},
}
(out / "metrics.json").write_text(json.dumps(metrics))
rows = ["t_s,angle_err_deg"] + [f"{k * 1e-3},{err * (k % 3 - 1)}" for k in range(8)]
(out / "trace.csv").write_text("\n".join(rows) + "\n")
'''

EXPECTED = '''
[[check]]
scenario = "alpha"
models = ["const", "fluxmap"]
metric = "angle_err_steady_max_deg"
what = "steady error"
thesis = "within 3 deg"
bound = { fluxmap = "abs <= 2" }

[[check]]
scenario = "alpha"
set = ["estimator.rs_scale=2"]
models = ["fluxmap"]
metric = "angle_err_steady_max_deg"
what = "steady error with Rs x 2"
thesis = "5 deg"
bound = { fluxmap = "<= 2" }

[[check]]
scenario = "alpha"
models = ["const", "fluxmap"]
metric = "settling_time_s"
what = "settling"
thesis = "0.3 s"

[[check]]
scenario = "beta"
models = ["const"]
metric = "windows.standstill.angle_err_mean_deg"
what = "error at standstill"
thesis = "-5 deg"
bound = { const = ">= -5" }

[[check]]
scenario = "beta"
models = ["const"]
metric = "speed_final_rpm"
what = "final speed"
thesis = "1500 rpm"

[[check]]
scenario = "broken"
models = ["fluxmap"]
metric = "angle_err_max_deg"
what = "a run that fails"
thesis = "n/a"
'''


def make_setup(root, expected=EXPECTED):
    fake = root / "fake_mcsim.py"
    write_fake_mcsim(fake, FAKE_BODY)
    scen = root / "scen"
    scen.mkdir(exist_ok=True)
    for name in ("alpha", "beta", "broken"):
        (scen / f"{name}.toml").write_text(f'[scenario]\nname = "{name}: test scenario"\n')
    (scen / "expected.toml").write_text(textwrap.dedent(expected))
    return fake, scen


def run_report(root, fake, scen, *extra):
    """cli.main with stdout/stderr captured (also usable from the module-scoped fixture,
    which cannot take capsys)."""
    o, e = io.StringIO(), io.StringIO()
    argv = ["report", "--mcsim", str(fake), "--scenarios", str(scen), "--out", str(root / "out"),
            "--doc", str(root / "docs" / "results.md"), "--dpi", DPI, *extra]
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = cli.main(argv)
    return rc, o.getvalue(), e.getvalue()


def table_rows(doc):
    rows = [ln for ln in doc.splitlines() if ln.startswith("| ") and not ln.startswith("| figure")]
    return [[c.strip() for c in ln.strip("|").split(" | ")] for ln in rows]


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    root = tmp_path_factory.mktemp("report")
    fake, scen = make_setup(root)
    rc, out, err = run_report(root, fake, scen, "--jobs", "1")
    return dict(root=root, fake=fake, scen=scen, rc=rc, out=out, err=err,
                doc=(root / "docs" / "results.md").read_text(encoding="utf-8"))


def test_table_rows_and_formatting(full):
    rows = table_rows(full["doc"])
    assert len(rows) == 6
    assert rows[0][:3] == ["alpha", "steady error (`angle_err_steady_max_deg`)", "within 3 deg"]
    assert rows[0][3] == "7.89°"          # const: no bound, no mark
    assert rows[0][4] == "1.23° ✓"        # fluxmap: abs <= 2 holds
    assert rows[0][5] == "fluxmap `abs <= 2`"
    assert rows[1][0] == "alpha (`estimator.rs_scale=2`)"
    assert rows[1][3] == "—"              # const not run for this check
    assert rows[1][4] == "2.47° ✗ **FAIL**"
    assert rows[2][3:] == ["—", "0.0456 s", "—"]  # null settling time
    assert rows[3][3] == "-3.95° ✓"
    assert rows[3][4] == "—"
    assert rows[4][3] == "1520 rpm"
    assert rows[5][4] == "run failed (exit 1)"


def test_doc_header_legend_and_plot_links(full):
    doc, root = full["doc"], full["root"]
    assert doc.startswith("# ")
    assert "bash scripts/report.sh" in doc
    assert "mctools report --scenarios" in doc
    assert "| figure | quantity | thesis | ours, constant parameters | ours, flux map | bound |" in doc
    assert "not committed" in doc
    # Relative links from docs/ into out/, and the PNGs are really there.
    link = "../out/alpha__fluxmap/plots/trace_overview.png"
    assert f"({link})" in doc
    assert (root / "docs" / link).is_file()
    assert "../out/alpha__estimator.rs_scale=2__fluxmap/plots/trace_overview.png" in doc
    assert "broken (broken: test scenario): fluxmap: run failed (exit 1)" in doc


def test_exit_status_summary_and_progress(full):
    assert full["rc"] == 1
    assert "report: 6 checks, 3 with bounds, 1 failed" in full["out"]
    assert "1 of 5 runs failed: broken fluxmap" in full["out"]
    progress = [ln for ln in full["out"].splitlines() if ln.startswith("[")]
    assert len(progress) == 5
    assert progress[-1].startswith("[5/5] ")
    assert any(ln.startswith("[") and "alpha estimator.rs_scale=2 fluxmap ... " in ln
               and ln.endswith(" s") for ln in progress)
    assert "plant diverged" in full["err"]  # the tail of the failing run's output
    assert "FAIL check 2" in full["err"]


def test_mcsim_arguments(full):
    argv = json.loads((full["root"] / "out" / "alpha__estimator.rs_scale=2__fluxmap"
                       / "argv.json").read_text())
    assert argv[0] == "run" and argv[1].endswith("alpha.toml")
    assert argv[2:6] == ["--set", "estimator.rs_scale=2", "--set", 'estimator.model="fluxmap"']
    assert argv[-1] == "--quiet"


def test_parallel_jobs_write_the_same_doc(full):
    root = full["root"]
    rc, out, _ = run_report(root, full["fake"], full["scen"], "--jobs", "3")
    assert rc == 1
    assert (root / "docs" / "results.md").read_text(encoding="utf-8") == full["doc"]


def test_only_filters_checks_and_runs(tmp_path):
    fake, scen = make_setup(tmp_path)
    rc, out, err = run_report(tmp_path, fake, scen, "--only", "beta")
    assert rc == 0, err
    assert "report: 2 checks, 1 with bounds, 0 failed" in out
    doc = (tmp_path / "docs" / "results.md").read_text(encoding="utf-8")
    assert [r[0] for r in table_rows(doc)] == ["beta", "beta"]
    assert "--only beta" in doc
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["beta__const"]


def test_failed_run_does_not_reuse_stale_metrics(tmp_path):
    fake, scen = make_setup(tmp_path)
    stale = tmp_path / "out" / "broken__fluxmap"
    stale.mkdir(parents=True)
    (stale / "metrics.json").write_text('{"angle_err_max_deg": 1.0}')
    rc, out, _ = run_report(tmp_path, fake, scen, "--only", "broken")
    assert rc == 1
    assert not (stale / "metrics.json").exists()
    doc = (tmp_path / "docs" / "results.md").read_text(encoding="utf-8")
    assert table_rows(doc)[0][4] == "run failed (exit 1)"
    assert "report: 1 checks, 0 with bounds, 0 failed" in out


GOOD = '''
[[check]]
scenario = "alpha"
models = ["const", "fluxmap"]
metric = "angle_err_max_deg"
what = "w"
thesis = "t"
'''


@pytest.mark.parametrize("extra, words", [
    ('metrik = "x"', ["check 2", "'metrik'", "unknown key"]),
    ('bound = { fluxmap = "about 2" }', ["check 2", "'bound'", "about 2"]),
    ('bound = { fluxmap = "<= two" }', ["check 2", "'bound'", "two"]),
    ('bound = { magic = "<= 2" }', ["check 2", "'bound'", "magic"]),
    ('set = ["estimator.model=\\"const\\""]', ["check 2", "'set'"]),
])
def test_validation_errors_exit_2(tmp_path, extra, words):
    fake, scen = make_setup(tmp_path, GOOD + GOOD.replace('thesis = "t"', 'thesis = "t"\n' + extra))
    rc, out, err = run_report(tmp_path, fake, scen)
    assert rc == 2
    for w in words:
        assert w in err
    assert not (tmp_path / "out").exists()  # nothing ran
    assert not (tmp_path / "docs").exists()


@pytest.mark.parametrize("old, new, words", [
    ('scenario = "alpha"', 'scenario = "gamma"', ["check 1", "'scenario'", "gamma.toml"]),
    ('models = ["const", "fluxmap"]', 'models = ["const", "magic"]', ["check 1", "'models'", "magic"]),
    ('metric = "angle_err_max_deg"\n', '', ["check 1", "'metric'", "missing"]),
])
def test_validation_of_required_values(tmp_path, old, new, words):
    fake, scen = make_setup(tmp_path, GOOD.replace(old, new))
    rc, _, err = run_report(tmp_path, fake, scen)
    assert rc == 2
    for w in words:
        assert w in err


def test_bound_for_model_not_run(tmp_path):
    text = GOOD.replace('models = ["const", "fluxmap"]', 'models = ["const"]') \
        + 'bound = { fluxmap = "<= 1" }\n'
    fake, scen = make_setup(tmp_path, text)
    rc, _, err = run_report(tmp_path, fake, scen)
    assert rc == 2 and "check 1" in err and "'bound'" in err


def test_unknown_only_and_missing_mcsim(tmp_path):
    fake, scen = make_setup(tmp_path)
    rc, _, err = run_report(tmp_path, fake, scen, "--only", "nope")
    assert rc == 2 and "nope" in err
    rc, _, err = run_report(tmp_path, tmp_path / "no_mcsim", scen)
    assert rc == 2 and "no_mcsim" in err


@pytest.mark.parametrize("v, s", [
    (0.028, "0.0280"), (1.5, "1.50"), (12.345, "12.3"), (1523.4, "1520"), (-4.9999, "-5.00"),
    (9.996, "10.0"), (0.0, "0"), (123456.0, "123000"), (1.2e-5, "1.20e-05"),
])
def test_fmt_number(v, s):
    assert fmt_number(v) == s


def test_fmt_value_units():
    assert fmt_value(2.0, "windows.a.angle_err_mean_deg") == "2.00°"
    assert fmt_value(0.1, "settling_time_s") == "0.100 s"
    assert fmt_value(3.0, "speed_err_steady_max_pct") == "3.00 %"
    assert fmt_value(13.29, "current_peak_a") == "13.3 A"
    assert fmt_value(600.0, "speed_final_rpm") == "600 rpm"
    assert fmt_value(3, "fault_count") == "3"
    assert fmt_value(None, "settling_time_s") == "—"


@pytest.mark.parametrize("text, value, ok", [
    ("abs <= 2", -1.9, True), ("abs <= 2", -2.1, False), ("<= 0.028", 0.028, True),
    (">= 5", 4.9, False), ("== 0", 0, True), ("< 1", 1.0, False), ("> -1", 0.0, True),
    ("<= 1", None, False), ("<=1e-3", 0.0005, True),
])
def test_bounds(text, value, ok):
    assert parse_bound(text).holds(value) is ok


@pytest.mark.parametrize("text", ["about 2", "<= ", "abs 2", "=< 2", "<= nan", "<= 2 deg"])
def test_bad_bounds(text):
    with pytest.raises(ValueError):
        parse_bound(text)


def test_run_dir_names_unique():
    keys = [("s", ("a=1",), "const"), ("s", ("a=\"1\"",), "const"), ("s", (), "fluxmap"),
            ("s", ('control.mode="torque"',), "const")]
    names = run_dir_names(keys)
    assert len(set(names.values())) == len(keys)
    assert names[("s", (), "fluxmap")] == "s__fluxmap"
    assert names[("s", ('control.mode="torque"',), "const")] == "s__control.mode=torque__const"
    assert all("/" not in n and '"' not in n for n in names.values())


def test_range_bound():
    from mctools.report import parse_bound

    b = parse_bound("abs in [3, 7]")
    assert b.holds(-5.0) and b.holds(3.0) and b.holds(7) and not b.holds(-7.5) and not b.holds(2.9)
    assert not b.holds(None)
    assert parse_bound("in [-1, 1]").holds(-0.5) and not parse_bound("in [-1, 1]").holds(-5)
    with pytest.raises(ValueError):
        parse_bound("in [7, 3]")


def test_report_keeps_the_envelope_block(tmp_path):
    """A report rewrites docs/results.md but keeps what `sweep envelope --doc` wrote there."""
    from mctools.report import kept_blocks
    doc = tmp_path / "results.md"
    doc.write_text("old table\n<!-- envelope:begin -->\n## Envelope\n| a |\n<!-- envelope:end -->\ntail\n")
    kept = kept_blocks(doc)
    assert "## Envelope" in kept and kept.strip().startswith("<!-- envelope:begin -->")
    assert "old table" not in kept and "tail" not in kept
    assert kept_blocks(tmp_path / "missing.md") == ""


HARSH_BODY = FAKE_BODY.replace(
    'err = (1.234 if model == "fluxmap" else 7.891) * scale',
    'err = (1.234 if model == "fluxmap" else 7.891) * scale'
    ' * (1.5 if sets.get("scenario.profile") == \'"harsh"\' else 1.0)')


def test_profiles_harsh_is_run_with_the_profile_and_never_fails(tmp_path):
    """--profiles realistic,harsh: one more run per check key with scenario.profile="harsh"
    (scenario's own seed, no trace, no percentile runs); its column is reported, a value outside
    the bound is marked but does not fail the report."""
    _, scen = make_setup(tmp_path)
    fake = write_fake_mcsim(tmp_path / "fake_mcsim_harsh.py", HARSH_BODY)
    # check 1's fluxmap bound holds on every realistic seed (1.23) but not under harsh (1.85)
    expected = EXPECTED.replace('bound = { fluxmap = "abs <= 2" }',
                                'bound = { fluxmap = "abs <= 1.5" }\nseeds = 10', 1)
    (scen / "expected.toml").write_text(textwrap.dedent(expected))
    rc, out, err = run_report(tmp_path, fake, scen, "--only", "alpha", "--jobs", "2",
                              "--profiles", "realistic,harsh")
    assert rc == 1, out + err  # check 2 fails in the realistic profile, as without --profiles
    assert "report: 3 checks, 2 with bounds, 1 failed" in out
    assert "FAIL check 2" in err and "FAIL check 1" not in err

    harsh = json.loads((tmp_path / "out" / "alpha__fluxmap" / "profile_harsh"
                        / "argv.json").read_text())
    assert 'scenario.profile="harsh"' in harsh and "output.trace=false" in harsh
    assert not any(a.startswith("scenario.seed") for a in harsh)  # the scenario's own seed
    assert not (tmp_path / "out" / "alpha__fluxmap" / "profile_harsh" / "seeds").exists()
    assert not (tmp_path / "out" / "alpha__fluxmap" / "profile_harsh" / "plots").exists()
    base = json.loads((tmp_path / "out" / "alpha__fluxmap" / "argv.json").read_text())
    assert not any(a.startswith("scenario.profile") for a in base)
    for s in range(1, 11):  # percentile runs only for the realistic profile
        seed = json.loads((tmp_path / "out" / "alpha__fluxmap" / "seeds" / f"seed_{s:04d}"
                           / "argv.json").read_text())
        assert not any(a.startswith("scenario.profile") for a in seed)

    doc = (tmp_path / "docs" / "results.md").read_text(encoding="utf-8")
    assert ("| figure | quantity | thesis | ours, constant parameters | "
            "ours, constant parameters, harsh | ours, flux map | ours, flux map, harsh | bound |"
            in doc)
    assert "--profiles realistic,harsh" in doc and "not judged" in doc
    rows = table_rows(doc)
    assert [len(r) for r in rows] == [8, 8, 8]
    assert rows[0][3:5] == ["7.89°", "11.8°"]  # const: no bound, no mark
    assert rows[0][5].endswith("✓")
    assert rows[0][6] == "1.85° ⚠ outside bound"
    assert rows[1][5] == "2.47° ✗ **FAIL**"   # realistic: judged
    assert rows[1][6] == "3.70° ⚠ outside bound"  # harsh: only marked
    assert rows[2][4:7] == ["—", "0.0456 s", "0.0456 s"]
    assert "report: profile harsh (reported, not judged): 2 of 2 bounded values outside" in out


def test_profiles_harsh_alone_does_not_fail(tmp_path):
    _, scen = make_setup(tmp_path)
    fake = write_fake_mcsim(tmp_path / "fake_mcsim_harsh.py", HARSH_BODY)
    expected = EXPECTED.replace('bound = { fluxmap = "<= 2" }', 'bound = { fluxmap = "<= 3" }')
    (scen / "expected.toml").write_text(textwrap.dedent(expected))
    rc, out, err = run_report(tmp_path, fake, scen, "--only", "alpha", "--no-plots",
                              "--profiles", "harsh,realistic")
    assert rc == 0, out + err  # realistic passes; harsh 3.70 > 3 is only marked
    assert "3.70° ⚠ outside bound" in (tmp_path / "docs" / "results.md").read_text()


@pytest.mark.parametrize("profiles", ["harsh", "realistic,bogus", "", "realistic,harsh,harsh"])
def test_bad_profiles_exit_2(tmp_path, profiles):
    fake, scen = make_setup(tmp_path)
    rc, _, err = run_report(tmp_path, fake, scen, "--profiles", profiles)
    assert rc == 2 and "--profiles" in err
