"""`mctools sweep zoo`: the scaled scenarios, the pass / fail rules of a cell, and the command
against a fake mcsim (no simulator runs here)."""

import contextlib
import io
import json
import subprocess
import tomllib
from pathlib import Path

import pytest

from fakes import write_fake_mcsim
from mctools import cli
from mctools.preset import fs_min_hz, load_preset
from mctools.sweep.zoo import (TESTS, Motor, Run, build_runs, demo_toml, judge_cell, judge_start,
                               if_start_toml, motor_info, torque_toml, uses_if)

# Stands in for mcsim: brodatzki trips loss_of_lock in the demo and gets the polarity wrong at
# 90 deg; the fly runs at negative speed exceed the current limit; a dyno speed of exactly 0 is
# refused like a bad key (exit 2); brodatzki at 2 kHz is refused as the drive refuses it (its
# f_s,min is 6 kHz), and at f_s,min its seed 3 exceeds the current limit; everything else passes.
FAKE_BODY = r'''
sets = {k: tomllib.loads("x = " + v)["x"] for k, v in sets.items()}
out.mkdir(parents=True, exist_ok=True)
(out / "argv.json").write_text(json.dumps(a))
motor = sets.get("machine.preset", "")
if scenario == "demo" or scenario == "torque_steps":
    motor = tomllib.loads((pathlib.Path(a[1])).read_text())["machine"]["preset"]
if sets.get("mechanics.dyno_speed_rpm") == 0.0:
    print("mcsim: error: key 'mechanics.dyno_speed_rpm' = 0: out of range", file=sys.stderr)
    sys.exit(2)
m = {"faults": [], "fault_time_s": None, "current_peak_a": 9.0, "current_limit_a": 10.0,
     "angle_err_steady_max_deg": -1.2, "angle_err_max_deg": 4.0, "final_state": "RUN"}
if scenario == "initpos_sweep":
    th = sets["mechanics.theta0_deg"]
    pol = not (motor == "brodatzki-35kw" and th == 90.0)
    m.update(polarity_correct=pol, init_pos_err_mean_deg=0.7 if pol else 179.0,
             angle_err_steady_max_deg=None)
if scenario == "demo" and motor == "brodatzki-35kw" and "control.ts_s" not in sets:
    m.update(faults=["loss_of_lock"], fault_time_s=1.23, angle_err_steady_max_deg=None,
             current_peak_a=14.5, final_state="FAULT")
if motor == "brodatzki-35kw" and sets.get("control.ts_s") == 0.0005:
    print("mcsim: error: x.toml: key 'control.ts_s' = 0.0005: f_s is below this motor's lowest; "
          "allowed range [5e-05, 0.000166855]", file=sys.stderr)
    sys.exit(2)
if motor == "brodatzki-35kw" and "control.ts_s" in sets and sets.get("scenario.seed") == 3:
    m.update(current_peak_a=12.0)
if scenario == "catch_dyno" and sets["mechanics.dyno_speed_rpm"] < 0:
    m.update(current_peak_a=12.0)
(out / "metrics.json").write_text(json.dumps(m))
'''


def run_cli(*argv):
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = cli.main(["sweep", "zoo", *argv])
    return rc, o.getvalue(), e.getvalue()


@pytest.fixture(scope="module")
def fake(tmp_path_factory):
    root = tmp_path_factory.mktemp("zoo")
    return write_fake_mcsim(root / "fake_mcsim.py", FAKE_BODY), root


THESIS = Motor("sun2016-ipm-5kw", 890.0, 29.7, 13.29, 10000.0, 1.23, 1608.0)


# ---------------------------------------------------------------------------------------------
# scaling

def test_base_speed_from_the_preset():
    m = motor_info("sun2016-ipm-5kw")
    assert m.base_rpm == pytest.approx(890.0, abs=1.0)   # `mctools preset`: MTPA rated, incl. Rs
    assert m.torque_nm == 29.7 and m.f_sample_hz == 10000.0
    assert m.lq_over_ld == pytest.approx(12.9 / 10.5, rel=0.02)


def test_demo_scaled_to_the_motor():
    d = tomllib.loads(demo_toml(THESIS, short=False))
    assert d["machine"]["preset"] == "sun2016-ipm-5kw"
    # the thesis motor gets the shipped demo's speeds and load back
    assert [v for _, v in d["control"]["speed_ref_rpm"]] == [0.0, 0.0, 100.0, 100.0, 600.0, 600.0,
                                                            -200.0]
    assert d["mechanics"]["load_torque_nm"][-1] == [0.3, 14.85]
    assert [w["name"] for w in d["metrics"]["window"]] == ["standstill_loaded", "plus_lo", "plus_hi",
                                                          "minus"]
    big = Motor("x", 3000.0, 80.0, 160.0, 8000.0, 4.0)
    d = tomllib.loads(demo_toml(big, short=False))
    assert [v for _, v in d["control"]["speed_ref_rpm"]][-3:] == [pytest.approx(2022.5, abs=0.1),
                                                                 pytest.approx(2022.5, abs=0.1),
                                                                 pytest.approx(-674.2, abs=0.1)]
    assert d["mechanics"]["load_torque_nm"][-1][1] == 40.0
    short = tomllib.loads(demo_toml(big, short=True))
    assert short["scenario"]["duration_s"] == 0.5
    assert [w["name"] for w in short["metrics"]["window"]] == ["standstill_loaded"]


def test_torque_steps_scaled():
    d = tomllib.loads(torque_toml(THESIS, short=False))
    # the drive picks the start: three_step where the saliency is usable, else I/f
    assert d["control"]["mode"] == "torque" and d["startup"]["init_pos"] == "auto"
    assert d["mechanics"]["dyno_speed_rpm"][-1] == [0.4, 89.0]
    t = [v for _, v in d["control"]["torque_ref_nm"]]
    assert max(t) == pytest.approx(0.76 * 29.7) and min(t) == pytest.approx(-0.76 * 29.7)


def test_if_start_for_motors_without_saliency(tmp_path):
    spm = Motor("spm", 7155.0, 5.0, 8.06, 8000.0, 1.0)
    assert uses_if(spm) and not uses_if(THESIS)
    d = tomllib.loads(if_start_toml(spm))
    assert d["mechanics"]["mode"] == "inertia" and d["mechanics"]["load_kind"] == "reactive"
    assert d["mechanics"]["load_torque_nm"] == 2.5
    assert d["startup"]["init_pos"] == "auto" and d["control"]["mode"] == "speed"
    assert d["control"]["speed_ref_rpm"][-1] == [0.25, pytest.approx(0.2 * 7155.0, abs=0.1)]
    runs = build_runs([spm, THESIS], tmp_path, (0.0, 90.0), short=True)
    starts = {(r.motor, r.label): r.scenario.name for r in runs if r.test == "start"}
    assert starts[("spm", "theta0=90")] == "start_if.toml"
    assert starts[(THESIS.name, "theta0=90")] == "initpos_sweep.toml"


def test_if_start_target_above_the_drives_handover(tmp_path):
    """The I/f start is judged after the hand-over: where 0.2 N_b is below 1.5 x the hand-over
    speed the drive reports (`mcsim check`), the target is raised to that; without the note (or
    without a simulator) it stays."""
    lv = Motor("lv", 2315.4, 1.06, 14.0, 20000.0, 1.0)
    fake = tmp_path / "check_mcsim.py"
    fake.write_text("#!/usr/bin/env python3\nimport sys\n"
                    "print('mcsim: note: the drive runs I/f below 600 rpm (startup.if_handover_rpm)', "
                    "file=sys.stderr)\n")
    fake.chmod(0o755)
    build_runs([lv], tmp_path / "a", (0.0,), short=True, mcsim=str(fake))
    d = tomllib.loads((tmp_path / "a" / "lv" / "start_if.toml").read_text())
    assert d["control"]["speed_ref_rpm"][-1] == [0.25, 900.0]
    build_runs([lv], tmp_path / "b", (0.0,), short=True)
    d = tomllib.loads((tmp_path / "b" / "lv" / "start_if.toml").read_text())
    assert d["control"]["speed_ref_rpm"][-1] == [0.25, pytest.approx(463.1, abs=0.05)]
    spm = Motor("spm", 7155.0, 5.0, 8.06, 8000.0, 1.0)   # 1431 rpm > 1.5 x 600: unchanged
    build_runs([spm], tmp_path / "c", (0.0,), short=True, mcsim=str(fake))
    d = tomllib.loads((tmp_path / "c" / "spm" / "start_if.toml").read_text())
    assert d["control"]["speed_ref_rpm"][-1] == [0.25, 1431.0]


def test_if_windows_judged(tmp_path):
    """A window the drive spent in I/f has no estimated angle: named, not an angle error; a run
    still in I/f in every window fails with that reason."""
    def run(wins, steady):
        r = Run("spm", "demo", "demo", tmp_path / "x.toml", (), tmp_path)
        r.metrics = {"faults": [], "angle_err_steady_max_deg": steady, "current_peak_a": 5.0,
                     "current_limit_a": 8.0, "final_state": "RUN", "windows": wins}
        return r
    ok = judge_cell("demo", [run({"standstill": {"if_open_share": 1.0}, "plus": {"if_open_share": 0.0}}, 0.8)])
    assert ok.passed and "I/f in standstill" in ok.text
    bad = judge_cell("demo", [run({"standstill": {"if_open_share": 1.0}}, None)])
    assert not bad.passed and "in I/f (open loop) in every window" in bad.text


def test_runs_per_motor(tmp_path):
    runs = build_runs([THESIS], tmp_path, (0.0, 45.0), short=False)
    by = {}
    for r in runs:
        by.setdefault(r.test, []).append(r)
    assert sorted(by) == sorted(k for k, _ in TESTS)
    assert len(by["start"]) == 2 and all(len(by[f"fly{s}"]) == 2 for s in (5, 50, 100))
    fly = sorted(dict(s.split("=", 1) for s in r.sets)["mechanics.dyno_speed_rpm"]
                 for r in by["fly100"])
    assert fly == ["-890.0", "890.0"]
    # f_s,min 1.6 kHz: the demo at 2 kHz (the range's end), three seeds, nothing below to refuse
    low = [dict(s.split("=", 1) for s in r.sets) for r in by["demo_low_fs"]]
    assert [x["control.ts_s"] for x in low] == ["0.0005"] * 3 and [x["scenario.seed"] for x in low] == ["1", "2", "3"]
    assert all(r.scenario == by["demo"][0].scenario and not r.expect_refusal for r in by["demo_low_fs"])
    # f_s,min 6 kHz: 6.3 kHz x 3 seeds, and 2 kHz expecting the refusal
    big = Motor("x", 3000.0, 80.0, 160.0, 8000.0, 4.0, 5994.0)
    lo = [r for r in build_runs([big], tmp_path, (0.0,), short=True) if r.test == "demo_low_fs"]
    assert [r.label for r in lo] == ["6.3 kHz, seed 1", "6.3 kHz, seed 2", "6.3 kHz, seed 3", "2 kHz"]
    assert [r.expect_refusal for r in lo] == [False, False, False, True]
    assert f"control.ts_s={1.0 / 6300.0!r}" in lo[0].sets and "control.ts_s=0.0005" in lo[3].sets
    for r in runs:   # default drive keys: only the preset and scenario-level keys
        keys = {s.split("=", 1)[0] for s in r.sets}
        assert keys <= {"machine.preset", "output.trace", "mechanics.theta0_deg",
                        "mechanics.dyno_speed_rpm", "control.torque_ref_nm", "control.ts_s",
                        "scenario.seed"}


def test_fs_min_by_hand():
    """20 (sensorless; 6 with a sensor) x the electrical frequency at the no-load base speed,
    Vdc / (sqrt3 psi_pm) / 2 pi."""
    # thesis: 300 V / sqrt3 = 173.21 V; / 0.34305 Wb = 504.9 rad/s = 80.36 Hz; x 20 = 1607 Hz
    assert fs_min_hz(load_preset("sun2016-ipm-5kw")) == pytest.approx(1607.2, abs=0.5)
    # brodatzki: 250 / sqrt3 / 0.07666 = 1882.8 rad/s = 299.66 Hz -> 5993 Hz
    assert fs_min_hz(load_preset("brodatzki-35kw")) == pytest.approx(5993.2, abs=1.0)
    # minicheetah: 24 / sqrt3 / 0.0024 = 5773.5 rad/s = 918.9 Hz -> 18378 Hz
    assert fs_min_hz(load_preset("minicheetah-24v-lv")) == pytest.approx(18378.0, abs=5.0)
    # with an angle sensor 6 samples a period: 5513 Hz on minicheetah, 2233 Hz on siemens
    assert fs_min_hz(load_preset("minicheetah-24v-lv"), sensorless=False) == pytest.approx(5513.3, abs=2.0)
    assert fs_min_hz(load_preset("siemens-1ft7044-spm"), sensorless=False) == pytest.approx(2232.8, abs=1.0)
    # rounded up to a PWM frequency (R10), at least the 2 kHz end of the range, none above 20 kHz
    assert [Motor("x", 1, 1, 1, 1, 1, f).fs_low_hz for f in (1607.2, 2000.0, 5993.2, 7443.0, 18378.0)] == \
        [2000.0, 2000.0, 6300.0, 8000.0, 20000.0]
    assert Motor("x", 1, 1, 1, 1, 1, 20001.0).fs_low_hz != Motor("x", 1, 1, 1, 1, 1, 20001.0).fs_low_hz


REPO = Path(__file__).resolve().parents[2]
MCSIM = REPO / "build/host/sim/app/mcsim"


@pytest.mark.skipif(not MCSIM.is_file(), reason="mcsim not built")
@pytest.mark.parametrize("sensorless", [True, False])
@pytest.mark.parametrize("name", ["sun2016-ipm-5kw", "baldor-5p6kw-pmsyrm", "brodatzki-35kw",
                                  "siemens-1ft7044-spm", "minicheetah-24v-lv"])
def test_fs_min_agrees_with_the_drive(name, sensorless, tmp_path):
    """The tool's f_s,min is the drive's: mcsim refuses control.ts_s 0.2 % above its period (where
    the range reaches) and takes it 0.2 % below (the range's 2 kHz where f_s,min is lower);
    sensorless (the demo's UNOP) and with the encoder."""
    m = motor_info(name)
    scen = tmp_path / "demo.toml"
    scen.write_text(demo_toml(m, short=True))
    src = [] if sensorless else ["--set", 'control.angle_source="encoder"']

    def check(ts):
        p = subprocess.run([str(MCSIM), "check", str(scen), "--set", f"control.ts_s={ts!r}", *src],
                           capture_output=True, text=True, timeout=60)
        return p.returncode, p.stderr
    ts_max = 1.0 / fs_min_hz(load_preset(name), sensorless)
    if ts_max * 1.002 <= 5e-4:
        rc, err = check(ts_max * 1.002)
        assert rc == 2 and "key 'control.ts_s'" in err and "f_s is below this motor's lowest" in err
    rc, err = check(min(ts_max * 0.998, 5e-4))
    assert rc == 0, err


def _low(label, metrics=None, refused="", expect=False):
    r = Run("m", "demo_low_fs", label, "demo.toml", (), "d", expect_refusal=expect)
    r.metrics, r.refused = metrics, refused
    if metrics is None:
        r.error, r.exit_code = "run failed (exit 2)", 2
    return r


def test_low_fs_cell():
    ok = {"faults": [], "angle_err_steady_max_deg": 1.5, "current_peak_a": 9.0, "current_limit_a": 10.0,
          "final_state": "RUN"}
    why = "key 'control.ts_s' = 0.0005: f_s is below this motor's lowest; allowed range [5e-05, 0.000166855]"
    runs = [_low(f"6.3 kHz, seed {s}", ok) for s in (1, 2, 3)] + [_low("2 kHz", refused=why, expect=True)]
    c = judge_cell("demo_low_fs", runs)
    assert c.passed and not c.refused
    assert c.text.startswith("6.3 kHz × 3 seeds: pass seed 1: 1.5°, peak 0.90× / seed 2: ")
    assert c.text.endswith("; 2 kHz refused (control.ts_s ≤ 166.9 µs)") and c.numbers["below"]["refused"] == why
    # a seed failing at f_s,min fails the cell; the refusal below is still reported apart
    bad = dict(ok, faults=["tracking"], fault_time_s=2.5)
    c = judge_cell("demo_low_fs", runs[:2] + [_low("6.3 kHz, seed 3", bad)] + runs[3:])
    assert not c.passed and not c.refused and "tracking at 2.50 s" in c.text and "2 kHz refused" in c.text
    # 2 kHz below f_s,min run without a refusal: the rule and the tool disagree, a failure
    c = judge_cell("demo_low_fs", runs[:3] + [_low("2 kHz", ok, expect=True)])
    assert not c.passed and "**2 kHz not refused**" in c.text
    # refused at 2 kHz, but not for the sampling rate: a failure with that reason
    other = "key 'injection.v1_v' = 900: out of range"
    c = judge_cell("demo_low_fs", runs[:3] + [_low("2 kHz", refused=other, expect=True)])
    assert not c.passed and f"**2 kHz refused for another reason**: {other}" in c.text
    # f_s,min above the range: only the refusal, a refused cell
    c = judge_cell("demo_low_fs", [_low("2 kHz", refused=why, expect=True)])
    assert c.refused and not c.passed and c.text == "f_s,min above the 20 kHz range: 2 kHz refused (control.ts_s ≤ 166.9 µs)"


# ---------------------------------------------------------------------------------------------
# cells

def mk(test, metrics, label="x", error=None):
    return Run("m", test, label, None, (), None, metrics=metrics, error=error)


def ok_metrics(**kw):
    m = {"faults": [], "fault_time_s": None, "current_peak_a": 9.0, "current_limit_a": 10.0,
         "angle_err_steady_max_deg": 1.0, "final_state": "RUN"}
    m.update(kw)
    return m


def test_cell_rules():
    c = judge_cell("demo", [mk("demo", ok_metrics())])
    assert c.passed and c.text == "pass 1.0°, peak 0.90×"
    # the 3 deg and 1.1 x limit boundaries
    assert judge_cell("demo", [mk("demo", ok_metrics(angle_err_steady_max_deg=-3.0,
                                                     current_peak_a=11.0))]).passed
    c = judge_cell("demo", [mk("demo", ok_metrics(angle_err_steady_max_deg=-3.05))])
    assert not c.passed and c.text == "**FAIL** steady 3.0°"
    c = judge_cell("demo", [mk("demo", ok_metrics(current_peak_a=11.2))])
    assert not c.passed and "peak 11.2 A = 1.12 × limit" in c.text
    c = judge_cell("demo", [mk("demo", ok_metrics(faults=["loss_of_lock", "overcurrent"],
                                                  fault_time_s=0.5,
                                                  angle_err_steady_max_deg=None))])
    assert c.text == "**FAIL** loss_of_lock, overcurrent at 0.50 s"
    # no fault, but the windows never ran
    c = judge_cell("demo", [mk("demo", ok_metrics(angle_err_steady_max_deg=None))])
    assert not c.passed and "no steady window ran" in c.text
    # a refused run is a failing cell with mcsim's reason
    r = mk("demo", None, error="run failed (exit 2)")
    r.log_tail = "mcsim: error: key 'startup.v_pol_v' = 0.12: out of range"
    c = judge_cell("demo", [r])
    assert not c.passed and "exit 2" in c.text and "v_pol_v" in c.text
    # a configuration the drive refuses in every run: a refused cell with the drive's reason
    r1, r2 = mk("fly5", None, "+10 rpm"), mk("fly5", None, "-10 rpm")
    for r in (r1, r2):
        r.error, r.refused = "run failed (exit 2)", "key 'startup.init_pos' = \"three_step\": needs saliency"
    c = judge_cell("fly5", [r1, r2])
    assert c.refused and not c.passed and c.text == "refused: key 'startup.init_pos' = \"three_step\": needs saliency"
    # ... but one refused run beside one that ran is a failure
    c = judge_cell("fly5", [r1, mk("fly5", ok_metrics(), "-10 rpm")])
    assert not c.refused and not c.passed
    # two runs in one cell: each labelled, one failing fails the cell
    c = judge_cell("fly5", [mk("fly5", ok_metrics(), "+10 rpm"),
                            mk("fly5", ok_metrics(faults=["tracking"], fault_time_s=0.1),
                               "-10 rpm")])
    assert not c.passed and c.text.startswith("**FAIL** +10 rpm: 1.0°") and "-10 rpm: tracking" in c.text


def test_start_cell():
    def st(a, pol=True, err=0.5, **kw):
        return mk("start", ok_metrics(polarity_correct=pol, init_pos_err_mean_deg=err,
                                      angle_err_steady_max_deg=None, **kw), f"theta0={a}")
    c = judge_start([st(a) for a in (0, 45, 90)])
    assert c.passed and c.text == "pass 3/3, init ≤ 0.5°, peak 0.90×"
    c = judge_start([st(0), st(45, pol=False, err=178.0), st(90, err=4.0),
                     st(135, faults=["overcurrent"], final_state="FAULT", current_peak_a=20.0)])
    assert not c.passed
    assert c.text == ("**1/4**; polarity wrong at 45°; init error > 3° at 90°; overcurrent at 135°; "
                      "peak up to 2.00 × limit (135°)")
    c = judge_start([st(0, final_state="INIT_POS"), st(45, pol=None, err=None)])
    assert "polarity wrong at 45°" in c.text and "ended in 0: INIT_POS" in c.text


# ---------------------------------------------------------------------------------------------
# the command

def test_zoo_command(fake, tmp_path):
    mcsim, _ = fake
    md, js, doc = tmp_path / "z.md", tmp_path / "z.json", tmp_path / "zoo.md"
    doc.write_text("# Zoo\n\nintro\n")
    rc, o, e = run_cli("--motors", "sun2016-ipm-5kw,brodatzki-35kw", "--mcsim", str(mcsim),
                       "--out", str(tmp_path / "out"), "--md", str(md), "--json", str(js),
                       "--doc", str(doc), "--jobs", "2")
    assert rc == 0, e   # failing cells are findings, not a tool error
    assert "[39/39]" in e   # progress: 19 runs (sun), 20 (brodatzki: 2 kHz refused)
    data = json.loads(js.read_text())
    cells = {(c["motor"], c["test"]): c for c in data["cells"]}
    assert len(cells) == 14
    assert all(cells[("sun2016-ipm-5kw", k)]["passed"] for k, _ in TESTS
               if k not in ("fly5", "fly50", "fly100"))
    assert not cells[("sun2016-ipm-5kw", "fly5")]["passed"]   # the negative speed's current
    assert "peak 12 A = 1.20 × limit" in cells[("sun2016-ipm-5kw", "fly5")]["text"]
    b = cells[("brodatzki-35kw", "demo")]
    assert not b["passed"] and b["text"] == "**FAIL** loss_of_lock at 1.23 s; peak 14.5 A = 1.45 × limit"
    low = cells[("brodatzki-35kw", "demo_low_fs")]
    assert not low["passed"] and not low["refused"]   # seed 3 over the limit at 6.3 kHz
    assert low["text"].startswith("6.3 kHz × 3 seeds: **FAIL** seed 1: 1.2°")
    assert "seed 3: peak 12 A = 1.20 × limit" in low["text"]
    assert low["text"].endswith("; 2 kHz refused (control.ts_s ≤ 166.9 µs)")
    assert low["below"]["refused"].startswith("key 'control.ts_s' = 0.0005: f_s is below this motor's lowest")
    run0 = low["runs"][0]   # enough to run it again
    assert run0["sets"][0] == 'machine.preset="brodatzki-35kw"' and f"control.ts_s={1 / 6300!r}" in run0["sets"]
    assert run0["scenario"].endswith("brodatzki-35kw/demo.toml")
    assert low["below"]["sets"][-1] == "control.ts_s=0.0005"
    assert cells[("sun2016-ipm-5kw", "demo_low_fs")]["text"].startswith("2 kHz × 3 seeds: pass ")
    assert cells[("brodatzki-35kw", "start")]["text"].startswith("**7/8**; polarity wrong at 90°")
    table = md.read_text()
    rows = [ln for ln in table.splitlines() if ln.startswith("| sun2016") or ln.startswith("| brodatzki")]
    assert len(rows) == 4 and all(r.count(" | ") == len(TESTS) for r in rows if "**" in r or "pass" in r)
    assert "Cells: 5 of 14 pass, 0 refused with a reason, 9 fail." in table
    assert "sweep zoo: 2 motors x 7 tests, 5 pass, 0 refused, 9 fail" in o
    assert "| brodatzki-35kw | 3971 | 80 | 8 | 5.99 (6.3) | 4.58 |" in table
    text = doc.read_text()
    assert text.startswith("# Zoo\n\nintro\n\n<!-- zoo:begin -->\n") and text.endswith("<!-- zoo:end -->\n")
    # the generated demo carries the motor and its scaled speeds
    demo = tomllib.loads((tmp_path / "out" / "brodatzki-35kw" / "demo.toml").read_text())
    assert demo["machine"]["preset"] == "brodatzki-35kw"
    # --strict: the failing cells make it exit 1
    rc, o, e = run_cli("--motors", "brodatzki-35kw", "--angles", "0", "--mcsim", str(mcsim),
                       "--out", str(tmp_path / "out2"), "--strict")
    assert rc == 1


def test_zoo_bad_input(fake, tmp_path):
    mcsim, _ = fake
    rc, o, e = run_cli("--motors", "no-such-motor-xyz", "--mcsim", str(mcsim), "--out", str(tmp_path))
    assert rc == 2 and "no-such-motor-xyz" in e
    rc, o, e = run_cli("--motors", "sun2016-ipm-5kw", "--angles", "0,x", "--mcsim", str(mcsim),
                       "--out", str(tmp_path))
    assert rc == 2 and "--angles" in e
    rc, o, e = run_cli("--motors", "sun2016-ipm-5kw", "--jobs", "0", "--mcsim", str(mcsim))
    assert rc == 2
