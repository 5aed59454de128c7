"""Seed statistics: `mctools sweep seeds` (local pool and Dask) and the percentile bound checks of
`mctools report`, against a fake mcsim (no simulator runs here)."""

import contextlib
import io
import json
import textwrap

import pytest

from fakes import write_fake_mcsim
from mctools import cli
from mctools.report import ReportInputError, load_expected, nearest_rank, parse_bound, \
    percentile_check

# metric values are simple functions of scenario.seed: x = seed / 10, and seed 7 has a null
# settling time; the scenario "bad" fails for seed 3 like a simulator crash.
FAKE_BODY = r'''
out.mkdir(parents=True, exist_ok=True)
(out / "argv.json").write_text(json.dumps(a))
seed = int(sets.get("scenario.seed", "1"))
if scenario == "bad" and seed == 3:
    print("mcsim: plant diverged", file=sys.stderr)
    sys.exit(1)
model = json.loads(sets.get("estimator.model", '"fluxmap"'))
x = seed / 10.0
metrics = {
    "x": x, "neg": -x, "flag": seed % 2 == 0, "name": "RUN",
    "settling_time_s": None if seed == 7 else 0.01 * seed,
    "windows": {"w": {"err_deg": x - 0.5}},
    "model_const": model == "const",
}
(out / "metrics.json").write_text(json.dumps(metrics))
if sets.get("output.trace", "true") != "false":
    (out / "trace.csv").write_text("t_s,angle_err_deg\n0,0\n0.001,1\n")
'''


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    root = tmp_path_factory.mktemp("seeds")
    fake = write_fake_mcsim(root / "fake_mcsim.py", FAKE_BODY)
    for name in ("good", "bad"):
        (root / f"{name}.toml").write_text(f'[scenario]\nname = "{name}"\n')
    return root, fake


def run_cli(*argv):
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = cli.main(list(argv))
    return rc, o.getvalue(), e.getvalue()


def seeds_sweep(env, tag, *extra, scen="good"):
    root, fake = env
    out = root / f"out_{tag}"
    rc, o, e = run_cli("sweep", "seeds", str(root / f"{scen}.toml"), "--mcsim", str(fake),
                       "--out", str(out), *extra)
    data = json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() \
        else None
    return rc, o, e, data, out


# ---------------------------------------------------------------------------------------------
# percentile logic

def test_nearest_rank():
    vals = [float(k) for k in range(1, 11)]           # 1..10
    assert nearest_rank(vals, 90) == 9.0               # one outlier allowed
    assert nearest_rank(vals, 90, high=False) == 2.0
    assert nearest_rank(vals, 100) == 10.0
    assert nearest_rank(vals, 50) == 5.0
    assert nearest_rank(list(reversed(vals)), 95) == 10.0
    assert nearest_rank([1.0, None, 3.0], 50) == 3.0   # a null is the worst value on either side
    assert nearest_rank([1.0, None, 3.0], 50, high=False) == 1.0
    assert nearest_rank([1.0] * 9 + [None], 90) == 1.0
    assert nearest_rank([1.0] * 8 + [None, None], 90) is None
    assert nearest_rank([], 90) is None


def test_percentile_check_directions():
    vals = [0.1 * k for k in range(1, 11)]             # 0.1 .. 1.0
    ok, lo, hi = percentile_check(parse_bound("<= 0.9"), vals, 90)
    assert ok and hi == pytest.approx(0.9) and lo == pytest.approx(0.2)
    assert not percentile_check(parse_bound("<= 0.85"), vals, 90)[0]
    assert percentile_check(parse_bound(">= 0.2"), vals, 90)[0]
    assert not percentile_check(parse_bound(">= 0.25"), vals, 90)[0]
    assert percentile_check(parse_bound("in [0.2, 0.9]"), vals, 90)[0]
    assert not percentile_check(parse_bound("in [0.3, 0.9]"), vals, 90)[0]
    # abs: on the magnitudes
    neg = [-v for v in vals]
    assert percentile_check(parse_bound("abs <= 0.9"), neg, 90)[0]
    assert not percentile_check(parse_bound("<= -0.5"), neg, 90)[0]
    # a null (or a failed run) is never within the bound: one allowed at p90 of 10, two are not
    assert percentile_check(parse_bound("<= 1"), vals[:9] + [None], 90)[0]
    assert not percentile_check(parse_bound("<= 1"), vals[:8] + [None, "x"], 90)[0]
    assert not percentile_check(parse_bound("abs >= 0"), [None] * 10, 90)[0]


EXPECTED = '''
[[check]]
scenario = "good"
models = ["const", "fluxmap"]
metric = "x"
what = "x over seeds"
thesis = "1"
bound = { const = "<= 0.9", fluxmap = "<= 0.85" }
seeds = 10
percentile = 90

[[check]]
scenario = "good"
models = ["fluxmap"]
metric = "settling_time_s"
what = "settling, one null in 10 seeds"
bound = { fluxmap = "<= 0.1" }
seeds = 10

[[check]]
scenario = "good"
models = ["const", "fluxmap"]
metric = "windows.w.err_deg"
what = "calibrated error"
bound = { const = "abs in [0, 0.5]", fluxmap = "abs <= 0.5" }
calibration = ["const"]
seeds = 12
percentile = 80

[[check]]
scenario = "good"
models = ["fluxmap"]
metric = "x"
what = "the scenario's own seed only"
bound = { fluxmap = "<= 0.1" }
'''


def write_expected(root, text):
    scen = root / "scen"
    scen.mkdir(exist_ok=True)
    (scen / "good.toml").write_text('[scenario]\nname = "good"\n')
    (scen / "expected.toml").write_text(textwrap.dedent(text))
    return scen


def test_expected_seed_keys(tmp_path):
    checks = load_expected(write_expected(tmp_path, EXPECTED))
    assert (checks[0].seeds, checks[0].percentile, checks[0].calibration) == (10, 90.0, frozenset())
    assert checks[1].percentile == 90.0                # the default
    assert checks[2].calibration == {"const"} and checks[2].percentile == 80.0
    assert checks[3].seeds is None and checks[3].percentile is None
    base = EXPECTED.split("[[check]]")[1]
    for extra, words in (("seeds = 5", "seeds"), ("seeds = true", "seeds"),
                         ("percentile = 90", "needs 'seeds'"),
                         ("seeds = 10\npercentile = 40", "50..100"),
                         ("calibration = [\"other\"]", "no bound"),
                         ("calibration = 1", "true/false")):
        text = "[[check]]" + base.replace("seeds = 10\npercentile = 90\n", "") + extra + "\n"
        write_expected(tmp_path, text)
        with pytest.raises(ReportInputError, match=words):
            load_expected(tmp_path / "scen")


def test_report_percentile_checks(env, tmp_path):
    root, fake = env
    scen = write_expected(tmp_path, EXPECTED)
    rc, out, err = run_cli("report", "--mcsim", str(fake), "--scenarios", str(scen),
                           "--out", str(tmp_path / "out"), "--doc", str(tmp_path / "r.md"),
                           "--no-plots", "--jobs", "2")
    doc = (tmp_path / "r.md").read_text()
    assert rc == 1                                     # fluxmap <= 0.85 fails at p90 (0.9)
    assert "FAIL check 1 (good, x): const 0.100; p90 0.900 over 10 seeds (1 outside the bound) " \
           "(bound <= 0.9); fluxmap 0.100; p90 0.900 over 10 seeds (2 outside the bound) " \
           "(bound <= 0.85)" in err
    assert "report: 4 checks, 4 with bounds, 1 failed" in out
    # evidence: check 1 (2 bounds), 2, 3 fluxmap, 4; calibration: check 3 const
    assert "report: 6 bounds: 5 evidence (4 at a percentile over seeds, 3 of them hold), " \
           "1 calibration targets" in out
    rows = [ln for ln in doc.splitlines() if ln.startswith("| good")]
    assert "0.100; p90 0.900 over 10 seeds (1 outside the bound) ✓" in rows[0]
    assert "at p90 of 10 seeds" in rows[0]
    # seed 7's null counts as the worst value, and it is the only one above 0.1 s
    assert "p90 0.100 s over 10 seeds (1 outside the bound, 1 of them null/failed) ✓" in rows[1]
    # the range bound is judged on both tails; |x - 0.5| over 12 seeds: p20 0.1 .. p80 0.5
    assert "\\|x\\| p20..p80 0.100°..0.500° over 12 seeds (2 outside the bound) ✓ " \
           "(calibration)" in rows[2]
    assert "const `abs in [0, 0.5]` (calibration)" in rows[2]
    assert "0.100 ✓" in rows[3] and "seeds" not in rows[3].split("|")[5]
    assert "Seed statistics:" in doc
    # seed runs: no trace, scenario.seed set, own folder; the scenario's own run keeps its trace
    run = tmp_path / "out" / "good__fluxmap"
    argv = json.loads((run / "seeds" / "seed_0010" / "argv.json").read_text())
    assert "output.trace=false" in argv and "scenario.seed=10" in argv
    assert not (run / "seeds" / "seed_0010" / "trace.csv").exists()
    assert (run / "trace.csv").is_file()
    assert not any("scenario.seed" in x for x in json.loads((run / "argv.json").read_text()))
    assert len(list((tmp_path / "out" / "good__const" / "seeds").iterdir())) == 12


# ---------------------------------------------------------------------------------------------
# mctools sweep seeds

def test_seeds_local_statistics(env):
    rc, o, e, data, out = seeds_sweep(env, "local", "--n", "20", "--jobs", "2",
                                      "--set", "fake.k=1")
    assert rc == 0, e
    st = data["statistics"]
    assert st["x"]["median"] == pytest.approx(1.05)
    assert (st["x"]["p5"], st["x"]["p10"], st["x"]["p90"], st["x"]["p95"]) == \
        pytest.approx((0.1, 0.2, 1.8, 1.9))
    assert (st["x"]["min"], st["x"]["max"]) == pytest.approx((0.1, 2.0))
    assert (st["x"]["min_seed"], st["x"]["max_seed"]) == (1, 20)
    assert st["neg"]["min_seed"] == 20
    assert st["windows.w.err_deg"]["n"] == 20          # nested objects flattened
    assert st["flag"]["mean"] == pytest.approx(0.5)    # booleans as 0/1
    assert st["settling_time_s"]["missing"] == 1 and st["settling_time_s"]["n"] == 19
    assert "name" not in st
    assert [r["seed"] for r in data["runs"]] == list(range(1, 21))
    argv = json.loads((out / "seed_0005" / "argv.json").read_text())
    assert "scenario.seed=5" in argv and "output.trace=false" in argv and "fake.k=1" in argv
    assert not (out / "seed_0005" / "trace.csv").exists()
    csv = (out / "summary.csv").read_text().splitlines()
    assert csv[0].startswith("metric,n,missing,mean,median,p5,p10,p90,p95,min,max")
    assert any(ln.startswith("x,20,0,") for ln in csv)
    assert "| `x` | 1.05 | 0.100 | 0.200 | 1.80 | 1.90 | 0.100 (1) | 2.00 (20) | 20 | 0 |" in o
    assert "[20/20] seeds" in e                        # progress on stderr, a line per batch
    assert "sweep seeds: 20 runs, 0 failed" in o


def test_seeds_trace_kept_on_request_and_failed_runs(env):
    rc, o, e, data, out = seeds_sweep(env, "trace", "--n", "3", "--trace")
    assert rc == 0 and (out / "seed_0002" / "trace.csv").is_file()
    rc, o, e, data, out = seeds_sweep(env, "bad", "--n", "4", "--jobs", "1", scen="bad")
    assert rc == 1
    assert [r["seed"] for r in data["runs"] if r["error"]] == [3]
    assert data["statistics"]["x"]["missing"] == 1
    assert "failed: 3" in e and "**1 failed** (seeds 3)" in o


@pytest.mark.parametrize("extra, words", [
    (["--n", "0"], "--n"), (["--batch", "0"], "--batch"), (["--jobs", "0"], "--jobs"),
    (["--set", "scenario.seed=4"], "sets it itself"),
])
def test_seeds_bad_arguments(env, extra, words):
    rc, o, e, data, out = seeds_sweep(env, "args", *extra)
    assert rc == 2 and words in e


def test_seeds_on_dask_local_cluster(env):
    distributed = pytest.importorskip("distributed")
    rc0, _, _, local, _ = seeds_sweep(env, "cmp_local", "--n", "20", "--jobs", "2")
    assert rc0 == 0
    # loopback only; threads in this process keep the test fast (the tasks run mcsim processes)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp", host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0") as cluster:
        rc, o, e, data, out = seeds_sweep(env, "dask", "--n", "20", "--batch", "8",
                                          "--scheduler", cluster.scheduler_address)
    assert rc == 0, e
    assert data["scheduler"].startswith("tcp://127.0.0.1:")
    assert data["statistics"] == local["statistics"]
    assert [r["metrics"] for r in data["runs"]] == [r["metrics"] for r in local["runs"]]
    # 20 runs in batches of 8: three tasks, a progress line each
    assert e.count("] seeds ") == 3 and "[20/20]" in e
    assert (out / "seed_0020" / "metrics.json").is_file()


def test_seeds_bad_scheduler(env, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr("mctools.sweep.seeds.CONNECT_TIMEOUT", "1s")
    rc, o, e, data, out = seeds_sweep(env, "nosched", "--n", "2",
                                      "--scheduler", "tcp://127.0.0.1:9")
    assert rc == 2 and "cannot connect" in e
