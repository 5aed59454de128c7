"""`mctools sweep envelope`: the classification of a run and a cell, the doc section, and the
command against a fake mcsim (no simulator runs here)."""

import contextlib
import io
import json

import pytest

from fakes import write_fake_mcsim
from mctools import cli
from mctools.sweep.common import SweepInputError
from mctools.sweep.envelope import (DOC_BEGIN, DOC_END, classify_run, envelope_errors, percentile,
                                    replace_doc_section, summarize_cell)


def metrics(faults=(), amax=1.0, steady=0.5, t_fault=None, windows=None):
    return {"faults": list(faults), "angle_err_max_deg": amax, "angle_err_steady_max_deg": steady,
            "fault_time_s": t_fault, "windows": windows or {}}


# ---------------------------------------------------------------------------------------------
# one run

def test_classify_holds_trips_runs_off():
    assert classify_run(metrics(amax=12.0, steady=-3.5)) == {
        "outcome": "holds", "faults": [], "recoveries": 0, "recovered_from": [], "fault_time_s": None,
        "angle_err_max_deg": 12.0, "steady_deg": 3.5, "current_ratio": None}
    c = classify_run(metrics(["voltage_model"], amax=40.0, steady=None, t_fault=0.22))
    assert c["outcome"] == "trips" and c["faults"] == ["voltage_model"] and c["fault_time_s"] == 0.22
    # no fault, angle lost: the finding
    assert classify_run(metrics(amax=120.0))["outcome"] == "runs_off"
    # a fault, but only after the angle was lost
    c = classify_run(metrics(["loss_of_lock"], amax=178.0, steady=None, t_fault=0.2))
    assert c["outcome"] == "runs_off" and c["faults"] == ["loss_of_lock"]
    # the boundary: 90 deg is lost, just below is not
    assert classify_run(metrics(amax=90.0))["outcome"] == "runs_off"
    assert classify_run(metrics(["tracking"], amax=89.9))["outcome"] == "trips"


def test_classify_recoveries():
    # detected, caught again, ran on: recovers
    m = metrics(amax=40.0, steady=1.2)
    m.update(recoveries=1, recovered_from=["loss_of_lock"])
    c = classify_run(m)
    assert c["outcome"] == "recovers" and c["recovered_from"] == ["loss_of_lock"]
    cell = summarize_cell([{"seed": 1, **c}])
    assert cell["outcome"] == "recovers" and "recovers ×1 (loss_of_lock), then 1.2°" in cell["text"]
    # retries used up, then the fault: a (detected) trip
    m = metrics(["loss_of_lock"], amax=60.0, steady=None, t_fault=0.3)
    m.update(recoveries=3, recovered_from=["loss_of_lock"])
    c = classify_run(m)
    assert c["outcome"] == "trips"
    assert "after 3 recoveries" in summarize_cell([{"seed": 1, **c}])["text"]
    # the angle lost at some point: a run-off, conservatively, with what followed
    m = metrics(amax=178.0, steady=1.2)
    m.update(recoveries=1, recovered_from=["loss_of_lock"])
    cell = summarize_cell([{"seed": 1, **classify_run(m)}])
    assert cell["outcome"] == "runs_off" and cell["text"] == "RUNS OFF 178°, then recovers ×1"
    assert cell["silent_runs_off"] == 0   # detected: not silent


def test_classify_edge_cases():
    assert classify_run(None, "run failed (exit 1)") == {"outcome": "failed",
                                                         "error": "run failed (exit 1)"}
    assert classify_run(None)["outcome"] == "failed"
    # a trip before any running sample: no angle error, still a safe trip
    assert classify_run(metrics(["overcurrent"], amax=None, steady=None))["outcome"] == "trips"
    # no fault and never running
    assert classify_run(metrics(amax=None, steady=None))["outcome"] == "no_run"
    # the steady error falls back to the windows' max (null windows ignored)
    w = {"a": {"angle_err_max_deg": 2.0}, "b": {"angle_err_max_deg": -4.5},
         "c": {"angle_err_max_deg": None}}
    assert classify_run(metrics(steady=None, windows=w))["steady_deg"] == 4.5
    assert classify_run(metrics(steady=None))["steady_deg"] is None


# ---------------------------------------------------------------------------------------------
# one cell

def runs(*ms):
    return [{"seed": i + 1, **classify_run(m)} for i, m in enumerate(ms)]


def test_cell_holds_and_trips():
    c = summarize_cell(runs(metrics(steady=1.2), metrics(steady=-0.8), metrics(steady=1.0)))
    assert c["outcome"] == "holds" and c["text"] == "holds 1.2°" and c["steady_deg"] == 1.2
    c = summarize_cell(runs(metrics(amax=60.0, steady=3.0), metrics(steady=1.0)))
    assert c["text"] == "holds 3.0° (peak 60°)"
    c = summarize_cell(runs(metrics(["voltage_model"], amax=30.0, t_fault=0.3),
                            metrics(["loss_of_lock"], amax=20.0, t_fault=0.25),
                            metrics(steady=2.0)))
    assert c["outcome"] == "trips" and c["count"] == 2
    assert c["text"] == "trips: voltage_model, loss_of_lock at 0.25 s (2/3, max 30°); " \
                        "holds 2.0° (1/3)"
    assert c["silent_runs_off"] == 0


def test_cell_runs_off():
    # a fault after the angle was lost: not bold
    c = summarize_cell(runs(metrics(["loss_of_lock"], amax=178.0), metrics(["loss_of_lock"],
                                                                            amax=179.5)))
    assert c["outcome"] == "runs_off" and c["text"] == "RUNS OFF 180°, then loss_of_lock"
    assert c["silent_runs_off"] == 0
    # lost without any fault in one seed: bold, the share of the silent ones
    c = summarize_cell(runs(metrics(amax=120.0), metrics(["tracking"], amax=170.0),
                            metrics(["voltage_model"], amax=50.0, t_fault=0.5)))
    assert c["text"] == "**RUNS OFF 170°**, then tracking in 1/2 (2/3); " \
                        "trips: voltage_model at 0.50 s (1/3, max 50°)"
    assert c["silent_runs_off"] == 1 and c["faults"] == ["tracking", "voltage_model"]
    assert summarize_cell(runs(metrics(amax=95.0)))["text"] == "**RUNS OFF 95°**"


def test_cell_failed_and_empty():
    r = runs(metrics(steady=1.0)) + [{"seed": 2, **classify_run(None, "run failed (exit 1)")}]
    c = summarize_cell(r)
    assert c["outcome"] == "failed" and c["text"] == "run failed (1/2); holds 1.0° (1/2)"
    assert summarize_cell([])["outcome"] == "failed"


# ---------------------------------------------------------------------------------------------
# the grid and the doc section

def test_errors_grid():
    rows = envelope_errors()
    keys = [r.key for r in rows]
    assert len(set(keys)) == len(keys) == 26
    assert keys[:2] == ["exact_fluxmap", "exact_const"] and rows[0].sets == rows[1].sets == ()
    by = {r.key: r for r in rows}
    assert by["l_0.8_const"].sets == ("estimator.l_scale=0.8",)
    assert by["l_0.95_fluxmap"].sets == ("estimator.l_scale=0.95",) and "l_0.95_const" not in by
    assert by["cross_1.25_fluxmap"].sets == ("estimator.cross_scale=1.25",)
    assert "cross_1.25_const" not in by
    assert {k for k in keys if k.startswith("rs_")} == {f"rs_{f}_{m}" for f in ("0.5", "0.7", "1.3", "2")
                                                        for m in ("const", "fluxmap")}
    assert {k for k in keys if k.startswith("psi_")} == {"psi_0.9_const", "psi_1.1_const",
                                                         "psi_0.9_fluxmap", "psi_1.1_fluxmap"}
    assert all(len(r.sets) <= 1 for r in rows)  # one error at a time


def test_doc_section(tmp_path):
    doc = tmp_path / "results.md"
    replace_doc_section(doc, "table 1")                      # a new file: only the section
    assert doc.read_text() == f"{DOC_BEGIN}\ntable 1\n{DOC_END}\n"
    doc.write_text("# Results\n\nbefore\n")                 # appended
    replace_doc_section(doc, "table 1\n")
    assert doc.read_text() == f"# Results\n\nbefore\n\n{DOC_BEGIN}\ntable 1\n{DOC_END}\n"
    doc.write_text(doc.read_text() + "\nafter\n")          # replaced in place, the rest kept
    replace_doc_section(doc, "table 2")
    assert doc.read_text() == f"# Results\n\nbefore\n\n{DOC_BEGIN}\ntable 2\n{DOC_END}\n\nafter\n"
    doc.write_text(f"x\n{DOC_BEGIN}\nold\n")
    with pytest.raises(SweepInputError):
        replace_doc_section(doc, "t")
    doc.write_text(f"x\n{DOC_END}\n")
    with pytest.raises(SweepInputError):
        replace_doc_section(doc, "t")


# ---------------------------------------------------------------------------------------------
# the command

# the outcome is a function of the mismatch keys: L x1.2 runs off silently, L x0.8 runs off and
# trips, Rs x0.7 trips safely on scenario "two", psi x1.1 crashes there (both models).
FAKE_BODY = r'''
sets = {k: tomllib.loads("x = " + v)["x"] for k, v in sets.items()}
out.mkdir(parents=True, exist_ok=True)
(out / "argv.json").write_text(json.dumps(a))
seed = sets.get("scenario.seed", 1)
if scenario == "two" and sets.get("estimator.psi_scale") == 1.1:
    print("mcsim: plant diverged", file=sys.stderr)
    sys.exit(1)
l, rs = sets.get("estimator.l_scale", 1.0), sets.get("estimator.rs_scale", 1.0)
const = sets.get("estimator.model") == "const"
faults, amax, steady, tf = [], 2.0 + seed / 10, (5.0 if const else 1.0) + seed / 10, None
if l == 1.2:
    amax, steady = 175.0, 175.0
elif l == 0.8:
    faults, amax, steady, tf = ["loss_of_lock"], 179.0, None, 0.2
elif rs == 0.7 and scenario == "two":
    faults, amax, steady, tf = ["voltage_model"], 30.0, None, 0.31
m = {"faults": faults, "angle_err_max_deg": amax, "angle_err_steady_max_deg": steady,
     "fault_time_s": tf, "final_state": "FAULT" if faults else "RUN", "windows": {}}
(out / "metrics.json").write_text(json.dumps(m))
'''


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    root = tmp_path_factory.mktemp("envelope")
    fake = write_fake_mcsim(root / "fake_mcsim.py", FAKE_BODY)
    for name in ("one", "two"):
        (root / f"{name}.toml").write_text(f'[scenario]\nname = "{name}"\n')
    return root, fake


def run_cli(*argv):
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = cli.main(list(argv))
    return rc, o.getvalue(), e.getvalue()


def test_envelope_command(env):
    root, fake = env
    out, doc = root / "out", root / "results.md"
    doc.write_text(f"# Results\n\n{DOC_BEGIN}\nold table\n{DOC_END}\n\n## Later\n")
    rc, o, e = run_cli("sweep", "envelope", "--scenarios", str(root / "one.toml"),
                       str(root / "two.toml"), "--seeds", "1", "--jobs", "4", "--mcsim", str(fake),
                       "--out", str(out), "--doc", str(doc))
    assert rc == 1  # two runs failed
    assert "[52/52]" in e and "elapsed" in e  # progress on stderr, one line per cell
    data = json.loads((out / "envelope.json").read_text())
    assert data["seeds"] == 1 and data["runs_total"] == 52 and len(data["cells"]) == 52
    cells = {(c["error_key"], c["scenario"]): c for c in data["cells"]}
    assert cells[("exact_fluxmap", "one")]["text"] == "holds 1.1°"
    assert cells[("exact_const", "one")]["text"] == "holds 5.1°"
    assert cells[("l_1.2_const", "one")]["text"] == "**RUNS OFF 175°**"
    assert cells[("l_0.8_fluxmap", "two")]["text"] == "RUNS OFF 179°, then loss_of_lock"
    assert cells[("rs_0.7_const", "two")]["text"] == "trips: voltage_model at 0.31 s (max 30°)"
    assert cells[("rs_0.7_const", "one")]["text"] == "holds 5.1°"
    assert cells[("psi_1.1_fluxmap", "two")]["outcome"] == "failed"
    assert cells[("psi_1.1_fluxmap", "one")]["outcome"] == "holds"
    assert [r["seed"] for r in cells[("exact_const", "two")]["runs"]] == [1]
    # what each run was given: the model, one error, no trace, the angle error from t = 0
    argv = json.loads((out / "two" / "cross_0.75_fluxmap" / "seed_0001" / "argv.json").read_text())
    sets = [argv[i + 1] for i, x in enumerate(argv) if x == "--set"]
    assert sets == ['estimator.model="fluxmap"', "estimator.cross_scale=0.75",
                    "metrics.start_s=0.0", "output.trace=false", "scenario.seed=1"]
    # the markdown: one row per error, one column per scenario; the doc section replaced
    md = (out / "envelope.md").read_text()
    assert "| error | model | `one` | `two` |" in md
    assert "| L ×1.2 | const | **RUNS OFF 175°** | **RUNS OFF 175°** |" in md
    assert "| cross-saturation ×0.75 | fluxmap | holds 1.1° | holds 1.1° |" in md
    assert "| Rs ×0.7 | fluxmap | holds 1.1° | trips: voltage_model at 0.31 s (max 30°) |" in md
    assert "Cells: " in md and "(4 without any fault)" in md
    text = doc.read_text()
    assert "old table" not in text and text.startswith("# Results\n\n" + DOC_BEGIN)
    assert text.endswith(f"{DOC_END}\n\n## Later\n") and md.strip() in text
    assert "sweep envelope: 52 runs, 2 failed" in o


def test_envelope_fail_on_runoff(env):
    root, fake = env
    # only scenario "one": no failed run, but L x1.2 and x0.8 run off
    rc, o, e = run_cli("sweep", "envelope", "--scenarios", str(root / "one.toml"), "--seeds", "1",
                       "--mcsim", str(fake), "--out", str(root / "out_ro"))
    assert rc == 0 and "4 cell(s) run off" in o
    rc, o, e = run_cli("sweep", "envelope", "--scenarios", str(root / "one.toml"), "--seeds", "1",
                       "--mcsim", str(fake), "--out", str(root / "out_ro2"), "--fail-on-runoff")
    assert rc == 1 and "lose the angle before any detection" in e


def test_envelope_input_errors(env):
    root, fake = env
    rc, _, e = run_cli("sweep", "envelope", "--scenarios", str(root / "missing.toml"),
                       "--mcsim", str(fake), "--out", str(root / "x"))
    assert rc == 2 and "no such scenario file" in e
    rc, _, e = run_cli("sweep", "envelope", "--seeds", "0", "--mcsim", str(fake))
    assert rc == 2 and "--seeds" in e
    rc, _, e = run_cli("sweep", "envelope", "--scenarios", str(root / "one.toml"),
                       str(root / "one.toml"), "--mcsim", str(fake), "--out", str(root / "x"))
    assert rc == 2 and "same file name" in e


def test_holding_cell_percentile():
    """Over 5 seeds and more a holding cell also gives the nearest-rank 90th percentile of its
    steady error (the worst stays the headline)."""
    assert percentile([], 90.0) is None
    assert percentile([3.0], 90.0) == 3.0
    xs = [5.1 + i / 10 for i in range(10)]
    assert percentile(xs, 90.0) == pytest.approx(5.9) and percentile(xs, 50.0) == pytest.approx(5.5)
    runs = [{"outcome": "holds", "steady_deg": x, "angle_err_max_deg": x} for x in xs]
    assert summarize_cell(runs)["text"] == "holds 6.0° (p90 5.9°)"
    assert summarize_cell(runs[:4])["text"] == "holds 5.4°"   # fewer than 5 seeds: the worst only


def test_cell_names_current_over_the_limit():
    """A limit is a limit in every mode: a cell names the worst seed's peak current above
    1.1 x the configured limit, whatever its outcome."""
    ok = classify_run({"faults": [], "angle_err_max_deg": 3.0, "angle_err_steady_max_deg": 2.0,
                       "current_peak_a": 11.0, "current_limit_a": 10.0})
    over = classify_run({"faults": [], "angle_err_max_deg": 3.0, "angle_err_steady_max_deg": 2.5,
                         "current_peak_a": 14.7, "current_limit_a": 10.0})
    assert ok["current_ratio"] == pytest.approx(1.1) and over["current_ratio"] == pytest.approx(1.47)
    assert summarize_cell([ok])["text"] == "holds 2.0°"
    assert summarize_cell([ok, over])["text"] == "holds 2.5° (**current 1.47 × limit**)"
    tripped = classify_run({"faults": ["overcurrent"], "angle_err_max_deg": 30.0, "fault_time_s": 0.2,
                            "current_peak_a": 30.0, "current_limit_a": 10.0})
    assert summarize_cell([tripped])["text"] == "trips: overcurrent at 0.20 s (max 30°, **current 3.00 × limit**)"
    assert classify_run({"faults": []})["current_ratio"] is None
