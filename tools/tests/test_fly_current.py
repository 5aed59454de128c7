"""mctools fly-current: the flying-start hand-over's current floor and searched peak."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mctools import cli
from mctools.fly_current import floor_current, search_peak, simulate
from mctools.machine import machine_from_dict
from mctools.preset import load_preset

REPO_PRESETS = Path(__file__).resolve().parents[2] / "presets"


def linear_machine(rs=0.0):
    return machine_from_dict({"name": "lin", "pole_pairs": 5, "rs_ohm": rs, "psi_pm_wb": 0.34305,
                              "ld_h": 10.5e-3, "lq_h": 12.9e-3, "i_rated_peak_a": 13.29,
                              "vdc_nominal_v": 300.0, "f_sample_hz": 1e4})


def test_zero_vector_gives_the_catch_equation():
    # V(000) from i = 0, Rs = 0: the flux stands in the stator frame, so after a rotation
    # Delta the current is (C.1) of mc/catch.h; checks the integrator and its frames
    m = linear_machine()
    w = 2 * math.pi * 100.0
    n = 10
    ts = 1e-4
    peak, pd, pq = simulate(m, w, 300.0, ts, np.zeros((1, n)), np.zeros((1, n)), limit="circle",
                            substeps=40)
    delta = w * n * ts
    i_d, i_q = m.model.current(pd, pq)
    assert float(i_d[0]) == pytest.approx(0.34305 * (math.cos(delta) - 1) / 10.5e-3, rel=2e-3)
    assert float(i_q[0]) == pytest.approx(-0.34305 * math.sin(delta) / 12.9e-3, rel=2e-3)
    assert float(peak[0]) >= math.hypot(float(i_d[0]), float(i_q[0])) - 1e-9


def test_floor_matches_the_linear_machine():
    # Rs = 0, Ld < Lq: the least current that holds omega |psi| <= U lies on the d axis
    m = linear_machine()
    w = 1500 / 60 * 2 * math.pi * 5
    u = 300.0 / math.sqrt(3)
    expect = (0.34305 - u / w) / 10.5e-3
    assert floor_current(m, w, u) == pytest.approx(expect, rel=0.01)
    # below the speed where the magnet's voltage fits, nothing is needed
    assert floor_current(m, 0.5 * u / 0.34305, u) < 0.05


def test_search_at_1500_rpm_on_the_thesis_motor():
    m = load_preset(str(REPO_PRESETS / "sun2016-ipm-5kw.toml"))
    w = 1500 / 60 * 2 * math.pi * 5
    u = 300.0 / math.sqrt(3)
    floor = floor_current(m, w, u)
    res = {lim: search_peak(m, w, 300.0, 1e-4, limit=lim, margin=1.0, horizon_s=3e-3, seed=0,
                            iterations=60)
           for lim in ("circle", "hexagon")}
    for r in res.values():
        assert r["end_short_v"] <= 0.01 * u          # ends in a holdable state
        assert r["peak_a"] >= floor - 1e-6            # no hand-over beats the steady floor
    # overmodulation gives more voltage: never a worse peak (the search has some noise)
    assert res["hexagon"]["peak_a"] <= res["circle"]["peak_a"] + 0.2
    # a braking current left by a catch pulse makes it worse
    worse = search_peak(m, w, 300.0, 1e-4, limit="circle", margin=1.0, horizon_s=3e-3, seed=0,
                        iterations=60, i0=(-0.5, -5.0))
    assert worse["peak_a"] > res["circle"]["peak_a"]


def test_rotor_angle_matters_with_the_hexagon_only():
    # the voltage that shrinks the flux keeps about one stator direction: with the hexagon the
    # rotor angle at the start decides whether that is a corner or a side; the circle has none
    m = load_preset(str(REPO_PRESETS / "sun2016-ipm-5kw.toml"))
    w = 1500 / 60 * 2 * math.pi * 5
    kw = dict(margin=1.0, horizon_s=3e-3, seed=0, iterations=80, i0=(-0.69, -3.0))
    hexa = {d: search_peak(m, w, 300.0, 1e-4, limit="hexagon", theta0=math.radians(d), **kw)["peak_a"]
            for d in (-135.0, -165.0)}
    assert hexa[-165.0] - hexa[-135.0] > 0.8           # 13.6 A against 12.2 A
    circ = {d: search_peak(m, w, 300.0, 1e-4, limit="circle", theta0=math.radians(d), **kw)["peak_a"]
            for d in (-135.0, -165.0)}
    assert abs(circ[-165.0] - circ[-135.0]) < 0.3


def test_overmodulated_hold_lowers_the_floor():
    # an end state held with overmodulation (margin above 1, up to the hexagon's mean radius)
    m = load_preset(str(REPO_PRESETS / "sun2016-ipm-5kw.toml"))
    w = 1500 / 60 * 2 * math.pi * 5
    u = 300.0 / math.sqrt(3)
    assert floor_current(m, w, 1.049 * u) < floor_current(m, w, u) - 0.8   # 10.35 A against 11.33 A


def test_cli_json_and_below_base_speed(capsys):
    rc = cli.main(["fly-current", str(REPO_PRESETS / "sun2016-ipm-5kw.toml"), "--rpm", "300",
                   "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    row = out["rows"][0]
    assert row["search_circle_a"] == 0.0 and row["search_hexagon_a"] == 0.0
    assert row["floor_a"] < 0.05


@pytest.mark.parametrize("argv, key", [
    (["--rpm", "1500,x"], "--rpm"),
    (["--rpm", "nan"], "--rpm"),
    (["--limit", "square"], "--limit"),
    (["--vdc", "-5"], "--vdc"),
    (["--margin", "2"], "--margin"),
    (["--margin", "1.06"], "--margin"),
    (["--theta0-deg", "nan"], "--theta0-deg"),
    (["--i0", "1"], "--i0"),
    (["--seeds", "0"], "--seeds"),
])
def test_cli_rejects_bad_options(argv, key, capsys):
    rc = cli.main(["fly-current", str(REPO_PRESETS / "sun2016-ipm-5kw.toml")] + argv)
    assert rc == 2
    assert key in capsys.readouterr().err


def test_cli_refuses_a_measured_map_preset(capsys):
    # fly-current integrates the closed-form i(psi); a [flux_map] preset has none: exit 2, said why
    rc = cli.main(["fly-current", str(REPO_PRESETS / "baldor-5p6kw-pmsyrm.toml")])
    assert rc == 2
    assert "measured-map preset" in capsys.readouterr().err
