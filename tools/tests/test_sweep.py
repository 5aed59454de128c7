"""`mctools sweep` against a fake mcsim (no simulator runs here)."""

import contextlib
import io
import json
import math
import sys

import pytest

from fakes import write_fake_mcsim
from mctools import cli
from mctools.sweep.common import angle_list, distribution
from mctools.sweep.noise import trial_angles
from mctools.sweep.table7_1 import step1_peak_a

FAKE_BODY = r'''
# Stands in for mcsim: the startup metrics are simple functions of the --set values.
sets = {k: tomllib.loads("x = " + v)["x"] for k, v in sets.items()}  # TOML, as mcsim reads it
out.mkdir(parents=True, exist_ok=True)
(out / "argv.json").write_text(json.dumps(a))
th = sets.get("mechanics.theta0_deg", 0.0)
if th == sets.get("fake.fail_at"):
    print("mcsim: plant diverged", file=sys.stderr)
    sys.exit(1)
m = sets.get("startup.step1_m", 5)
cost = sets.get("startup.step1_cost", "linear")
k = 3.0 if cost == "linear" else 2.0
e1 = k * m * math.sin(math.radians(2 * th))
pol = not (scenario == "badpol" and th == 90.0)
noise = sets.get("sensors.i_noise_rms_a", 0.02)
seed = sets.get("scenario.seed", 1)
method = sets.get("startup.polarity", "generalized")
if method == "generalized" and noise > 0.1 and seed % 10 == 0:
    pol = False
if method == "dvi" and noise > 0.2 and seed % 4 == 0:
    pol = False
if method == "generalized" and noise == 0.3 and seed % 5 == 0:
    pol = None   # Step II undecided: a fault, no polarity handed on
metrics = {
    "current_peak_a": 99.0, "current_limit_a": 20.0,
    "step12_time_s": 0.0106, "step1_err_deg": e1,
    "step12_err_deg": e1 if pol else e1 + 180.0, "polarity_correct": pol,
    "init_pos_err_deg": None if th == 200.0 else 0.5 + th / 1000.0,
    "init_pos_err_mean_deg": None if th == 200.0 else 0.4 + th / 1000.0,
    "init_pos_time_s": None if th == 200.0 else 0.02 + th / 10000.0,
    "reverse_angle_max_deg": 0.0, "final_state": "RUN" if th != 200.0 else "INIT_POS",
    "faults": [],
}
(out / "metrics.json").write_text(json.dumps(metrics))
if sets.get("output.trace", True):
    rows = ["t_s,state,ia_a,ib_a,ic_a"]
    # 3 rows of offset calibration, then state 4: Step I triangle (peak 2 m A at row m), then a
    # big Step II current that the Step I peak must not see.
    for r in range(80):
        st = 1 if r < 3 else 4
        j = r - 3
        ia = 0.0
        if 0 <= j <= 4 * m:
            ia = 2.0 * (j if j <= m else (2 * m - j if j <= 3 * m else j - 4 * m))
        if j == 4 * m + 10:
            ia = 50.0
        rows.append(f"{r * 1e-4:.6f},{st},{ia:.5f},{-ia / 2:.5f},{-ia / 2:.5f}")
    (out / "trace.csv").write_text("\n".join(rows) + "\n")
'''


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweep")
    fake = root / "fake_mcsim.py"
    write_fake_mcsim(fake, FAKE_BODY)
    for name in ("good", "badpol"):
        (root / f"{name}.toml").write_text(f'[scenario]\nname = "{name}"\n')
    (root / "nopreset.toml").write_text('[scenario]\nname = "x"\n[machine]\n'
                                        'preset = "no-such-preset-xyz"\n')
    return root, fake


def run(root, fake, *argv):
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = cli.main(["sweep", *argv[:1], *argv[1:], "--mcsim", str(fake)])
    return rc, o.getvalue(), e.getvalue()


def sweep(setup, cmd, scen, *extra, tag="x"):
    root, fake = setup
    out = root / f"out_{tag}"
    js = root / f"{tag}.json"
    md = root / f"{tag}.md"
    rc, o, e = run(root, fake, cmd, str(root / f"{scen}.toml"), "--out", str(out),
                   "--json", str(js), "--md", str(md), "--jobs", "2", *extra)
    data = json.loads(js.read_text()) if js.is_file() else None
    return rc, o, e, data, (md.read_text() if md.is_file() else None)


# ---------------------------------------------------------------------------------------------
# helpers

def test_angle_list_and_distribution():
    assert len(angle_list(5.0, None, 5.0)) == 72
    assert angle_list(30.0, None, 5.0)[:3] == [0.0, 30.0, 60.0]
    assert angle_list(None, None, 15.0)[-1] == 345.0
    assert angle_list(None, "10, -20,350", 5.0) == [10.0, -20.0, 350.0]
    d = distribution([1.0, -3.0, None, 2.0, float("nan")], ["a", "b", "c", "d", "e"])
    assert d["n"] == 3 and d["missing"] == 2
    assert d["mean"] == pytest.approx(0.0)
    assert d["abs_mean"] == pytest.approx(2.0)
    assert d["abs_max"] == 3.0 and d["abs_max_at"] == "b"
    assert (d["min"], d["max"]) == (-3.0, 2.0)
    assert distribution([None])["mean"] is None


def test_trial_angles_reproducible():
    a = trial_angles(50, 1)
    assert a == trial_angles(50, 1) and a != trial_angles(50, 2)
    assert all(0.0 <= x < 360.0 for x in a)
    assert all(round(x, 3) == x for x in a)


def test_step1_peak_window(tmp_path):
    rows = ["t_s,state,ia_a,ib_a,ic_a", "0,1,0,0,0", "0.0001,4,1,-7,6", "0.0002,4,0,0,0",
            "0.0003,4,-3,1,2", "0.0004,4,0,0,0", "0.001,4,40,-20,-20"]
    (tmp_path / "trace.csv").write_text("\n".join(rows) + "\n")
    assert step1_peak_a(tmp_path / "trace.csv", 1, 1e-4) == 7.0  # 4 m + 4 rows from state 4
    assert step1_peak_a(tmp_path / "none.csv", 1, 1e-4) is None


# ---------------------------------------------------------------------------------------------
# angles

def test_angles_distribution_and_table(setup):
    rc, out, err, data, md = sweep(setup, "angles", "good", "--step-deg", "30", tag="a30")
    assert rc == 0, err
    s = data["summary"]
    assert s["runs"] == 12 and s["failed_runs"] == 0 and s["polarity_correct"] == 12
    angles = [30.0 * k for k in range(12)]
    e1 = [15.0 * math.sin(math.radians(2 * a)) for a in angles]
    assert s["step1_err_deg"]["abs_mean"] == pytest.approx(sum(map(abs, e1)) / 12, abs=1e-9)
    assert s["step1_err_deg"]["abs_max"] == pytest.approx(15 * math.sin(math.radians(60)))
    # theta0 = 200 is not in this set; final error 0.5 + th/1000
    fin = [0.5 + a / 1000 for a in angles]
    assert s["init_pos_err_deg"]["mean"] == pytest.approx(sum(fin) / 12)
    assert s["init_pos_err_deg"]["abs_max"] == pytest.approx(0.83)
    assert s["init_pos_err_deg"]["abs_max_at"] == 330.0
    assert s["init_pos_time_s"]["max"] == pytest.approx(0.053)
    assert [r["theta0_deg"] for r in data["runs"]] == angles  # in angle order, not finish order
    assert out.count("] angles theta0=") == 12  # progress lines
    assert md in out + "\n" or md.strip() in out
    assert "Polarity correct in **12 / 12** runs" in md
    assert "| error at the hand-over sample (Step III → RUN) | `init_pos_err_deg` |" in md
    assert "| final error (mean over 20 ms after the hand-over) | `init_pos_err_mean_deg` |" in md
    assert "exp. mean 0.91°" in md and "exp. mean 11.52°" in md
    assert "| 330° | " in md
    argv = json.loads((setup[0] / "out_a30" / "theta_+030p000" / "argv.json").read_text())
    assert argv[2:4] == ["--set", "mechanics.theta0_deg=30.0"]


def test_angles_expect_flags_exit_codes(setup):
    rc, out, err, data, _ = sweep(setup, "angles", "good", "--angles", "0,150,330",
                                  "--expect-polarity", "--max-final-err-deg", "1",
                                  "--max-time-s", "0.06", tag="ok")
    assert rc == 0, err
    assert "0 violation(s)" in out
    rc, out, err, data, _ = sweep(setup, "angles", "good", "--angles", "0,150,330",
                                  "--max-final-err-deg", "0.8", "--final-metric", "init_pos_err_deg",
                                  tag="fin")
    assert rc == 1
    assert "theta0 = 330 deg: |init_pos_err_deg| 0.83 > 0.8" in err
    rc, out, err, data, _ = sweep(setup, "angles", "good", "--angles", "0,150,330",
                                  "--max-final-err-deg", "0.8", tag="finmean")
    assert rc == 0, err   # the mean metric is 0.73 at 330 deg
    assert data["violations"] == []
    rc, out, err, _, _ = sweep(setup, "angles", "good", "--angles", "0,330",
                               "--max-time-s", "0.05", tag="time")
    assert rc == 1 and "init_pos_time_s 0.0530 > 0.05" in err
    rc, out, err, data, md = sweep(setup, "angles", "badpol", "--angles", "0,90,180",
                                   "--expect-polarity", tag="pol")
    assert rc == 1 and "theta0 = 90 deg: polarity_correct is false" in err
    assert data["summary"]["polarity_wrong_at"] == [90.0]
    assert "**2 / 3**" in md and "wrong at 90" in md
    # without the flag the wrong polarity is reported but is not a failure
    rc, *_ = sweep(setup, "angles", "badpol", "--angles", "0,90", tag="pol2")
    assert rc == 0
    # a null final error / time fails its bound; the end state is reported
    rc, out, err, data, md = sweep(setup, "angles", "good", "--angles", "200",
                                   "--max-final-err-deg", "1", "--max-time-s", "1", tag="null")
    assert rc == 1 and "|init_pos_err_mean_deg| — > 1" in err
    assert data["summary"]["not_run_state_at"] == [200.0]


def test_angles_failed_run(setup):
    rc, out, err, data, md = sweep(setup, "angles", "good", "--angles", "0,45",
                                   "--set", "fake.fail_at=45.0", "--expect-polarity", tag="fail")
    assert rc == 1
    assert data["summary"]["failed_runs"] == 1
    assert "run failed (exit 1)" in out and "plant diverged" in err
    assert data["summary"]["polarity_undecided_at"] == [45.0]


# ---------------------------------------------------------------------------------------------
# table7_1

def test_table7_1_summary(setup):
    rc, out, err, data, md = sweep(setup, "table7_1", "nopreset", "--m", "3,5", "--step-deg",
                                   "45", tag="t71")
    assert rc == 0, err
    assert "no-such-preset-xyz" in err  # warned: per unit from current_limit_a (20 A)
    rows = {r["m"]: r for r in data["summary"]["rows"]}
    angles = [45.0 * k for k in range(8)]
    for m in (3, 5):
        for cost, k in (("linear", 3.0), ("nonlinear", 2.0)):
            e = [abs(k * m * math.sin(math.radians(2 * a))) for a in angles]
            assert rows[m][cost]["abs_mean"] == pytest.approx(sum(e) / 8)
        assert rows[m]["peak_a"] == pytest.approx(2.0 * m)  # the 50 A Step II row is excluded
        assert rows[m]["peak_pu"] == pytest.approx(2.0 * m / 20.0)
    assert rows[3]["thesis"] == {"linear": 13.14, "nonlinear": 12.5, "peak_pu": 0.39}
    line = next(ln for ln in md.splitlines() if ln.startswith("| 5 |"))
    assert "10.77°" in line and "7.15°" in line and "0.69" in line and "0.50" in line
    assert len(data["runs"]) == 2 * 2 * 8
    argv = json.loads((setup[0] / "out_t71" / "m3_nonlinear" / "theta_+045p000"
                       / "argv.json").read_text())
    assert 'startup.step1_cost="nonlinear"' in argv and "output.decimation=1" in argv
    assert "startup.step1_m=3" in argv


def test_table7_1_rated_peak_from_preset(setup):
    from mctools.preset import load_preset

    rc, out, err, data, md = sweep(setup, "table7_1", "good", "--m", "4", "--angles", "0,90",
                                   tag="t71p")
    assert rc == 0, err
    i_rated = load_preset("sun2016-ipm-5kw").i_rated_peak_a
    assert data["summary"]["i_rated_peak_a"] == pytest.approx(i_rated)
    assert data["summary"]["rows"][0]["peak_pu"] == pytest.approx(8.0 / i_rated)


# ---------------------------------------------------------------------------------------------
# noise

def test_noise_summary(setup):
    rc, out, err, data, md = sweep(setup, "noise", "good", "--levels", "0.25,0.05,0.15",
                                   "--trials", "20", tag="noise")
    assert rc == 0, err
    g, d = data["summary"]["generalized"], data["summary"]["dvi"]
    assert [r["noise_a"] for r in g["levels"]] == [0.05, 0.15, 0.25]  # sorted
    assert [r["pct"] for r in g["levels"]] == [100.0, 90.0, 90.0]
    assert g["levels"][1]["wrong_seeds"] == [10, 20]
    assert (g["limit_a"], g["first_fail_a"]) == (0.05, 0.15)
    assert [r["pct"] for r in d["levels"]] == [100.0, 100.0, 75.0]
    assert (d["limit_a"], d["first_fail_a"]) == (0.15, 0.25)
    assert len(data["angles_deg"]) == 20 and data["angles_deg"] == trial_angles(20, 1)
    runs = [r for r in data["runs"] if r["method"] == "dvi" and r["noise_a"] == 0.25]
    assert [r["seed"] for r in runs] == list(range(1, 21))
    assert [r["theta0_deg"] for r in runs] == data["angles_deg"]
    assert "| 0.15 A | 90.0 % (18/20), 2 wrong ✗ | 100.0 % (20/20) |" in md
    assert "- generalized: ≥ 99 % correct up to 0.05 A; first below at 0.15 A." in md
    assert "dvi >= 99 % up to 0.15 A" in out
    argv = json.loads((setup[0] / "out_noise" / "dvi" / "noise_0.25" / "seed_00004"
                       / "argv.json").read_text())
    assert 'startup.polarity="dvi"' in argv and "scenario.seed=4" in argv
    assert "sensors.i_noise_rms_a=0.25" in argv


def test_noise_min_pct_and_no_working_level(setup):
    rc, out, err, data, md = sweep(setup, "noise", "good", "--levels", "0.15", "--trials", "10",
                                   "--methods", "generalized", "--min-pct", "95", tag="n2")
    assert rc == 0
    g = data["summary"]["generalized"]
    assert g["limit_a"] is None and g["first_fail_a"] == 0.15
    assert "up to none of the levels" in md
    assert "dvi" not in data["summary"]


def test_noise_refused_is_not_wrong(setup):
    # at 0.3 A the fake refuses seeds 5 and 10 (null): counted apart, and not wrong
    rc, out, err, data, md = sweep(setup, "noise", "good", "--levels", "0.3", "--trials", "10",
                                   "--methods", "generalized", "--max-wrong", "0", tag="n3")
    assert rc == 0, err
    r = data["summary"]["generalized"]["levels"][0]
    assert (r["correct"], r["undecided"], r["wrong"]) == (8, 2, 0)
    assert "| 0.3 A | 80.0 % (8/10), 2 refused ✗ |" in md


def test_noise_max_wrong_fails(setup):
    # at 0.15 A the fake hands on a wrong polarity at seed 10
    rc, out, err, data, md = sweep(setup, "noise", "good", "--levels", "0.15", "--trials", "10",
                                   "--methods", "generalized", "--max-wrong", "0", tag="n4")
    assert rc == 1
    assert "1 wrong polarities handed on (generalized at 0.15 A), more than --max-wrong 0" in err


# ---------------------------------------------------------------------------------------------
# argument validation

@pytest.mark.parametrize("cmd,extra,msg", [
    ("angles", ["--step-deg", "0"], "--step-deg must be in (0, 360]"),
    ("angles", ["--angles", "1,x"], "--angles: 'x' is not a number"),
    ("angles", ["--angles", "400"], "outside -360..360"),
    ("angles", ["--angles", "5,5"], "duplicate"),
    ("angles", ["--set", "novalue"], "is not key=value"),
    ("angles", ["--set", "mechanics.theta0_deg=3"], "sets it itself"),
    ("angles", ["--jobs", "0"], "--jobs must be at least 1"),
    ("angles", ["--max-final-err-deg", "-1"], "--max-final-err-deg must be a positive"),
    ("table7_1", ["--m", "0,3"], "--m: 0 is not an integer in 1..16"),
    ("table7_1", ["--m", "3.5"], "not an integer"),
    ("table7_1", ["--set", "startup.step1_cost=linear"], "sets it itself"),
    ("noise", ["--methods", "generalized,foo"], "--methods"),
    ("noise", ["--levels", "-0.1"], "--levels"),
    ("noise", ["--max-wrong", "-1"], "--max-wrong must be 0 or more"),
    ("noise", ["--trials", "0"], "--trials"),
    ("noise", ["--set", "scenario.seed=3"], "sets it itself"),
])
def test_bad_arguments_exit_2(setup, capsys, cmd, extra, msg):
    root, fake = setup
    rc = cli.main(["sweep", cmd, str(root / "good.toml"), "--mcsim", str(fake),
                   "--out", str(root / "never"), *extra])
    err = capsys.readouterr().err
    assert rc == 2
    assert f"mctools sweep: error: " in err and msg in err
    assert not (root / "never").exists()


def test_missing_scenario_and_mcsim(setup, capsys):
    root, fake = setup
    assert cli.main(["sweep", "angles", str(root / "nope.toml"), "--mcsim", str(fake)]) == 2
    assert "no such scenario file" in capsys.readouterr().err
    assert cli.main(["sweep", "noise", str(root / "good.toml"), "--mcsim",
                     str(root / "good.toml")]) == 2
    assert "not an executable file" in capsys.readouterr().err


def test_step_and_angles_exclusive(setup, capsys):
    root, fake = setup
    with pytest.raises(SystemExit) as ex:
        cli.main(["sweep", "angles", str(root / "good.toml"), "--step-deg", "5", "--angles", "1"])
    assert ex.value.code == 2
    assert "not allowed with argument" in capsys.readouterr().err


def test_report_appends_sweeps(setup):
    """`mctools report` runs <scenarios>/sweeps.toml through `mctools sweep` and appends the
    summaries to the doc; --no-sweeps and --only skip them."""
    root, fake = setup
    scen = root / "scen_report"
    scen.mkdir(exist_ok=True)
    (scen / "good.toml").write_text('[scenario]\nname = "good"\n')
    (scen / "expected.toml").write_text(
        '[[check]]\nscenario = "good"\nmodels = ["fluxmap"]\nmetric = "step12_err_deg"\n'
        'what = "w"\nthesis = "t"\n')
    (scen / "sweeps.toml").write_text(
        '[[sweep]]\ntitle = "a few angles"\nargs = ["angles", "good.toml", "--angles", "0,90"]\n')
    doc = root / "rep.md"
    buf_out, buf_err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(buf_out), contextlib.redirect_stderr(buf_err):
        rc = cli.main(["report", "--mcsim", str(fake), "--scenarios", str(scen), "--out",
                       str(root / "rep_out"), "--doc", str(doc), "--no-plots", "--jobs", "1"])
    assert rc == 0, buf_err.getvalue()
    text = doc.read_text()
    assert "## Sweeps" in text and "### a few angles" in text and "Polarity correct" in text
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        rc = cli.main(["report", "--mcsim", str(fake), "--scenarios", str(scen), "--out",
                       str(root / "rep_out2"), "--doc", str(doc), "--no-plots", "--no-sweeps"])
    assert rc == 0 and "## Sweeps" not in doc.read_text()
    (scen / "sweeps.toml").write_text('[[sweep]]\ntitle = 3\n')
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        rc = cli.main(["report", "--mcsim", str(fake), "--scenarios", str(scen), "--out",
                       str(root / "rep_out3"), "--doc", str(doc), "--no-plots"])
    assert rc == 2
