"""`mctools fit-adq` against a fake mcsim (no simulator runs here)."""

import contextlib
import io
import json
import math
import tomllib

import pytest

from fakes import SUN_PRESET_TOML, write_fake_mcsim
from mctools import cli
from mctools.fit_adq import (COMMENT_MARK, TARGETS, compensated_a_q0, candidate_model, golden_section,
                             preset_comment, rewrite_preset_text, rounded_candidate, small_signal)
from mctools.machine import SaturationModel

# The preset as machines.md gives it (inline so the test does not depend on presets/).
PRESET = "# a preset for the test\n" + SUN_PRESET_TOML.replace(
    "\n[saturation]\n", "\n# a_dq = 1.0 in a comment must not be touched\n[saturation]\n")

# Stands in for mcsim: the four figures grow linearly with the candidate preset's a_dq (a
# synthetic monotone response) and equal the thesis' magnitudes at a_dq = TRUE_ADQ. The slopes
# come in through the environment so one test can make the figures inconsistent.
FAKE_BODY = r'''
assert json.loads(sets["estimator.model"]) == "const"
preset = pathlib.Path(json.loads(sets["machine.preset"]))  # a TOML string with its quotes
sat = tomllib.loads(preset.read_text())["saturation"]
x = sat["a_dq"] / float(os.environ.get("FAKE_TRUE_ADQ", "500"))
k = [float(s) for s in os.environ.get("FAKE_SLOPES", "5,10,8.5,1.5").split(",")]
w = {"fig6_13": {"standstill": k[0] * x},
     "fig6_14": {"standstill": k[1] * x, "plus_50rpm": k[2] * x},
     "fig6_15": {"plus_100rpm": k[3] * x}}[scenario]
out.mkdir(parents=True, exist_ok=True)
(out / "metrics.json").write_text(json.dumps(
    {"windows": {n: {"angle_err_mean_deg": v} for n, v in w.items()}}))
with open(out.parent / "calls.txt", "a") as f:
    f.write(json.dumps({"scenario": scenario, "a_dq": sat["a_dq"], "a_q0": sat["a_q0"],
                        "a_qq": sat["a_qq"]}) + "\n")
'''


def base_model():
    return SaturationModel.from_mapping(tomllib.loads(PRESET)["saturation"])


@pytest.fixture
def setup(tmp_path):
    fake = tmp_path / "fake_mcsim.py"
    write_fake_mcsim(fake, FAKE_BODY)
    scen = tmp_path / "scen"
    scen.mkdir()
    for s in ("fig6_13", "fig6_14", "fig6_15"):
        (scen / f"{s}.toml").write_text(f'[scenario]\nname = "{s}"\n')
    preset = tmp_path / "sun.toml"
    preset.write_text(PRESET)
    return tmp_path, fake, scen, preset


def run_fit(root, fake, scen, preset, *extra):
    o, e = io.StringIO(), io.StringIO()
    argv = ["fit-adq", "--mcsim", str(fake), "--scenarios", str(scen), "--preset", str(preset),
            "--out", str(root / "out"), "--fit-file", str(root / "fits" / "fit.json"), *extra]
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = cli.main(argv)
    return rc, o.getvalue(), e.getvalue()


# -- model side ----------------------------------------------------------------------------

@pytest.mark.parametrize("a_dq", [0.0, 200.0, 557.8, 1441.3, 3000.0])
def test_a_q0_compensation_keeps_small_signal_values(a_dq):
    base = base_model()
    new = candidate_model(base, a_dq)
    assert new.a_dq == a_dq
    s0, s1 = small_signal(base), small_signal(new)
    assert s1["psi_pm_wb"] == pytest.approx(s0["psi_pm_wb"], rel=1e-12)
    assert s1["ld_h"] == pytest.approx(s0["ld_h"], rel=1e-12)
    assert s1["lq_h"] == pytest.approx(s0["lq_h"], rel=1e-10)
    assert abs(s1["ldq_h"]) < 1e-15
    # ... and still matches machines.md's Table 4.1 values.
    assert s1["psi_pm_wb"] == pytest.approx(0.34305, abs=5e-5)
    assert s1["ld_h"] == pytest.approx(10.5e-3, abs=0.01e-3)
    assert s1["lq_h"] == pytest.approx(12.9e-3, abs=0.01e-3)


def test_without_compensation_lq_would_move():
    import dataclasses
    base = base_model()
    raw = dataclasses.replace(base, a_dq=500.0)
    assert small_signal(raw)["lq_h"] > 1.1 * small_signal(base)["lq_h"]
    # The closed form: a_q0' = a_q0 + (a_dq - a_dq')/(U+2) psi_d0^(U+2).
    psi0 = base.psi_pm()
    assert compensated_a_q0(base, 500.0) == pytest.approx(58.12 + (1441.3 - 500.0) / 3 * psi0**3)


def test_a_qq_does_not_enter_small_signal_values():
    import dataclasses
    base = base_model()
    for a_qq in (0.0, 200.0, 2000.0):
        s = small_signal(dataclasses.replace(candidate_model(base, 557.8), a_qq=a_qq))
        assert s["lq_h"] == pytest.approx(small_signal(base)["lq_h"], rel=1e-10)


def test_no_compensation_when_v_positive():
    import dataclasses
    m = dataclasses.replace(base_model(), V=1.0)
    assert compensated_a_q0(m, 10.0) == m.a_q0


def test_rounded_candidate():
    a_dq, a_q0 = rounded_candidate(base_model(), 557.834)
    assert a_dq == 557.8
    assert a_q0 == round(compensated_a_q0(base_model(), 557.8), 3)


# -- search --------------------------------------------------------------------------------

def test_golden_section_converges_on_a_monotone_response():
    # |figure| grows monotonically with x; the objective is |response - target|.
    calls = []

    def f(x):
        calls.append(x)
        return abs(0.02 * x - 10.0)

    x, fx, hist = golden_section(f, 0.0, 1441.3, 15)
    assert len(calls) == len(hist) == 15
    assert x == pytest.approx(500.0, abs=2.0)
    assert fx < 0.04


def test_golden_section_with_rounding_stops_at_resolution():
    calls = []

    def f(x):
        calls.append(x)
        return (x - 123.4) ** 2

    x, _, hist = golden_section(f, 0.0, 200.0, 60, x_key=lambda v: round(v, 1))
    assert x == pytest.approx(123.4, abs=0.11)
    assert len(calls) == len(set(calls)) < 60  # no repeated evaluations, stops early


def test_golden_section_bad_arguments():
    with pytest.raises(ValueError):
        golden_section(lambda x: x, 1.0, 1.0, 5)
    with pytest.raises(ValueError):
        golden_section(lambda x: x, 0.0, 1.0, 1)


# -- preset text ---------------------------------------------------------------------------

def changed_lines(old, new):
    a, b = old.splitlines(), new.splitlines()
    return [ln for ln in a if ln not in b], [ln for ln in b if ln not in a]


def test_rewrite_touches_only_a_dq_and_a_q0():
    new = rewrite_preset_text(PRESET, 557.8, 70.008, preset_comment("presets/fits/x.json"))
    removed, added = changed_lines(PRESET, new)
    assert removed == ["a_q0 = 58.12", "a_dq = 1441.3"]
    assert added[1:] == ["a_q0 = 70.008", "a_dq = 557.8"]
    assert added[0].startswith("# ") and COMMENT_MARK in added[0] and "presets/fits/x.json" in added[0]
    assert len(new.splitlines()) == len(PRESET.splitlines()) + 1
    d_old, d_new = tomllib.loads(PRESET), tomllib.loads(new)
    assert d_new["saturation"].pop("a_dq") == 557.8 and d_new["saturation"].pop("a_q0") == 70.008
    del d_old["saturation"]["a_dq"], d_old["saturation"]["a_q0"]
    assert d_new == d_old
    assert "# a_dq = 1.0 in a comment must not be touched" in new


def test_rewrite_is_idempotent_and_keeps_one_comment():
    once = rewrite_preset_text(PRESET, 557.8, 70.008, preset_comment("f.json"))
    twice = rewrite_preset_text(once, 600.0, 69.44, preset_comment("f.json"))
    assert twice.count(COMMENT_MARK) == 1
    assert rewrite_preset_text(twice, 557.8, 70.008, preset_comment("f.json")) == once


def test_rewrite_a_qq_only_when_asked():
    new = rewrite_preset_text(PRESET, 557.8, 70.008, a_qq=200.0)
    removed, added = changed_lines(PRESET, new)
    assert removed == ["a_q0 = 58.12", "a_qq = 774.0", "a_dq = 1441.3"]
    assert added == ["a_q0 = 70.008", "a_qq = 200.0", "a_dq = 557.8"]


def test_rewrite_needs_the_keys_in_the_saturation_table():
    from mctools.fit_adq import FitInputError
    with pytest.raises(FitInputError, match="a_dq"):
        rewrite_preset_text(PRESET.replace("a_dq = 1441.3\n", ""), 1.0, 2.0)
    with pytest.raises(FitInputError, match="saturation.a_dq"):
        rewrite_preset_text(PRESET.replace("[saturation]", "[other]"), 1.0, 2.0)


# -- the command ---------------------------------------------------------------------------

def test_fit_converges_writes_result_and_preset(setup):
    root, fake, scen, preset = setup
    rc, out, err = run_fit(root, fake, scen, preset, "--write", "--evals", "14")
    assert rc == 0, err
    progress = [ln for ln in out.splitlines() if ln.startswith("[")]
    assert len(progress) == 15 and progress[0].startswith("[ 1/15] a_dq =   1441.3")
    res = json.loads((root / "fits" / "fit.json").read_text())
    a_dq = res["after"]["a_dq"]
    assert a_dq == pytest.approx(500.0, abs=3.0)
    assert res["after"]["a_q0"] == round(compensated_a_q0(base_model(), a_dq), 3)
    assert res["within_tolerance"] is True
    for row, t in zip(res["figures"], TARGETS):
        assert abs(row["after_deg"]) == pytest.approx(abs(t.thesis_deg), abs=0.05)
        assert row["before_deg"] == pytest.approx(abs(t.thesis_deg) * 1441.3 / 500.0, rel=1e-9)
    ss = res["small_signal_at_i0"]
    assert ss["model_after"]["lq_h"] == pytest.approx(ss["model_before"]["lq_h"], rel=2e-5)  # a_q0 to 3 decimals
    assert res["command"].startswith("mctools fit-adq ")
    # Every evaluation ran the three scenarios with the candidate's compensated a_q0.
    calls = [json.loads(ln) for p in sorted((root / "out").glob("eval_*/calls.txt"))
             for ln in p.read_text().splitlines()]
    assert len(calls) == 3 * 15
    for c in calls[3:]:
        assert c["a_q0"] == round(compensated_a_q0(base_model(), c["a_dq"]), 3)
        assert c["a_qq"] == 774.0
    # The preset: only a_dq, a_q0 and one comment line changed.
    removed, added = changed_lines(PRESET, preset.read_text())
    assert removed == ["a_q0 = 58.12", "a_dq = 1441.3"]
    assert added[1:] == [f"a_q0 = {res['after']['a_q0']:.3f}", f"a_dq = {a_dq:.1f}"]


def test_fit_with_a_qq_writes_it(setup, monkeypatch):
    root, fake, scen, preset = setup
    rc, out, err = run_fit(root, fake, scen, preset, "--write", "--a-qq", "200", "--evals", "8")
    assert rc == 0, err
    assert tomllib.loads(preset.read_text())["saturation"]["a_qq"] == 200.0
    res = json.loads((root / "fits" / "fit.json").read_text())
    assert res["before"]["a_qq"] == 774.0 and res["after"]["a_qq"] == 200.0
    assert "--a-qq 200" in res["command"]


def test_fit_outside_tolerance_does_not_write(setup, monkeypatch):
    root, fake, scen, preset = setup
    monkeypatch.setenv("FAKE_SLOPES", "5,10,2,1.5")  # +50 rpm cannot be matched with the others
    rc, out, err = run_fit(root, fake, scen, preset, "--write", "--evals", "10")
    assert rc == 1
    assert "preset not written" in err
    assert preset.read_text() == PRESET
    res = json.loads((root / "fits" / "fit.json").read_text())
    assert res["within_tolerance"] is False


def test_fit_bad_input_exit_2(setup, tmp_path):
    root, fake, scen, preset = setup
    rc, _, err = run_fit(root, fake, scen, tmp_path / "nope.toml")
    assert rc == 2 and "no such file" in err
    rc, _, err = run_fit(root, fake, tmp_path / "noscen", preset)
    assert rc == 2 and "fig6_13" in err
    rc, _, err = run_fit(root, tmp_path / "no-mcsim", scen, preset)
    assert rc == 2 and "--mcsim" in err
    rc, _, err = run_fit(root, fake, scen, preset, "--lo", "10", "--hi", "5")
    assert rc == 2 and "interval" in err
    assert math.isfinite(float(tomllib.loads(preset.read_text())["saturation"]["a_dq"]))
