"""tools/mctools/machine.py against the simulator's magnetic model (the reference), point by point.

machine.py is a second implementation of the analytic saturation model (machines.md) used for the
preset figures; the C++ plant (sim/src/machine_analytic.cpp) is what the simulator integrates. The
`model-dump` tool (sim/tools/model_dump.cpp) prints the C++ model on a grid; this test evaluates the
same quantities with machine.py for both shipped presets and compares them.

The binary is looked up in $MCSIM_TOOLS_DIR, then in build/host/sim/tools (the host preset's build
directory, built by scripts/test.sh before pytest runs). Without it the tests skip.
"""

from __future__ import annotations

import csv
import io
import os
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mctools.machine import torque
from mctools.preset import load_preset

REPO = Path(__file__).resolve().parents[2]
PRESETS = ["sun2016-ipm-5kw", "brodatzki-35kw"]

# Both sides evaluate the same closed-form expressions in double precision, in a different order
# (numpy's ** vs repeated multiplication, the plant's factored evaluator). Observed differences are
# a few ulp (<= 1.1e-15 of the column scale); 1e-9 leaves room for that, while a coefficient error
# shows up in proportion (a_qq changed by 1e-7 relative moves psi_q by ~1e-8: caught).
RTOL = 1e-9
# psi = flux(i) is a Newton solve on both sides with different stopping rules: C++ stops when the
# step is < 1e-12 |psi|, machine.py when the current residual is < 1e-10 * i_f. A residual r moves
# psi by about L r: at most 3.1e-9 A * 13 mH = 4e-11 Wb for sun2016 (flux scale of the grid ~0.5 Wb)
# and 3e-8 A * 0.55 mH = 1.7e-11 Wb for brodatzki (~0.1 Wb), i.e. < 2e-10 of the column scale (in
# practice the last Newton step leaves both at round-off: observed ~2e-16). Quantities that go
# through flux(i) are therefore compared with RTOL relative to the point's value plus RTOL times the
# column's scale (its largest magnitude on the grid): psi_q, l_dq and the torque are 0 on the
# i_q = 0 line, where a purely relative test would demand exact zeros. Quantities computed directly
# at the C++ psi (current, Jacobian, inductances there, energy) only need a floor for round-off in
# terms that cancel (cur_d = G_d psi_d - i_f ~ 0 at i_d = 0): 1e-12 of the column scale.
COLUMN_ATOL = {"newton": RTOL, "direct": 1e-12}
# The preset's psi_pm_wb, ld_h, lq_h are the model's small-signal values rounded to 4-5 significant
# digits (largest rounding: lq_h of sun2016, 12.9e-3 vs 12.90097e-3, 7.5e-5 relative).
PRESET_ROUNDING_RTOL = 2e-4


def _find_model_dump() -> Path | None:
    candidates = []
    env = os.environ.get("MCSIM_TOOLS_DIR")
    if env:
        d = Path(env)
        candidates += [d] if d.is_absolute() else [Path.cwd() / d, REPO / d]
    candidates.append(REPO / "build" / "host" / "sim" / "tools")
    for d in candidates:
        exe = d / "model-dump"
        if exe.is_file() and os.access(exe, os.X_OK):
            return exe
    return None


MODEL_DUMP = _find_model_dump()
pytestmark = pytest.mark.skipif(
    MODEL_DUMP is None,
    reason="model-dump not built: looked in $MCSIM_TOOLS_DIR and build/host/sim/tools "
           "(build it with `cmake --build --preset host --target model-dump`)")


def run_dump(*args) -> dict[str, np.ndarray]:
    """Run model-dump and return its CSV as columns (the `input` column as a str array)."""
    proc = subprocess.run([str(MODEL_DUMP), *map(str, args)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, f"model-dump {' '.join(map(str, args))} failed:\n{proc.stderr}"
    rows = list(csv.reader(io.StringIO(proc.stdout)))
    header, body = rows[0], rows[1:]
    assert body, "model-dump printed no rows"
    cols = {name: [r[k] for r in body] for k, name in enumerate(header)}
    out = {"input": np.array(cols.pop("input"))}
    out.update({k: np.array(v, dtype=float) for k, v in cols.items()})
    return out


def assert_close(name, py, cpp, *, atol_scale):
    """|py - cpp| <= RTOL |cpp| + atol_scale * max|cpp| at every point, with a useful message."""
    py = np.asarray(py, dtype=float)
    cpp = np.asarray(cpp, dtype=float)
    assert py.shape == cpp.shape, name
    scale = max(float(np.max(np.abs(cpp))), np.finfo(float).tiny)
    tol = RTOL * np.abs(cpp) + atol_scale * scale
    err = np.abs(py - cpp)
    bad = ~(err <= tol)
    if np.any(bad):
        k = int(np.argmax(np.where(bad, err / tol, 0.0)))
        pytest.fail(f"{name}: {int(bad.sum())} of {cpp.size} points differ; worst at index {k}: "
                    f"python {py[k]!r} vs C++ {cpp[k]!r} (|diff| {err[k]:.3g}, tol {tol[k]:.3g})")


@pytest.fixture(scope="module", params=PRESETS)
def preset(request):
    path = REPO / "presets" / f"{request.param}.toml"
    with path.open("rb") as f:
        raw = tomllib.load(f)
    return path, load_preset(str(path)), raw


@pytest.fixture(scope="module")
def current_grid(preset):
    path, _, _ = preset
    # The default grid: i_d, i_q over +-1.5 * i_rated_peak, 21 x 21 (through i = 0).
    d = run_dump(path)
    assert np.all(d["input"] == "i")
    assert d["i_d_A"].size == 21 * 21
    return d


@pytest.fixture(scope="module")
def flux_grid(preset, current_grid):
    path, _, _ = preset
    # Covers the flux reached by the current grid, mirrored to negative psi_d (the magnet keeps
    # psi_d > 0 on the current grid, so the |psi_d|, sign(psi_d) branches need this grid).
    pd = 1.2 * float(np.max(np.abs(current_grid["psi_d_Wb"])))
    pq = 1.2 * float(np.max(np.abs(current_grid["psi_q_Wb"])))
    d = run_dump(path, "--psi-grid", -pd, pd, -pq, pq, "--n", 21)
    assert np.all(d["input"] == "psi")
    assert np.any(d["psi_d_Wb"] < 0) and np.any(d["psi_d_Wb"] == 0) and np.any(d["psi_q_Wb"] == 0)
    return d


def _compare_at_psi(m, d):
    """Everything machine.py computes directly at the C++ flux linkage (no Newton solve)."""
    sm = m.model
    psi_d, psi_q = d["psi_d_Wb"], d["psi_q_Wb"]
    cur_d, cur_q = sm.current(psi_d, psi_q)
    assert_close("current(psi)_d", cur_d, d["cur_d_A"], atol_scale=COLUMN_ATOL["direct"])
    assert_close("current(psi)_q", cur_q, d["cur_q_A"], atol_scale=COLUMN_ATOL["direct"])
    g_dd, g_dq, g_qq = sm.jacobian(psi_d, psi_q)
    assert_close("di_d/dpsi_d", g_dd, d["g_dd_per_H"], atol_scale=COLUMN_ATOL["direct"])
    assert_close("di_d/dpsi_q", g_dq, d["g_dq_per_H"], atol_scale=COLUMN_ATOL["direct"])
    assert_close("di_q/dpsi_q", g_qq, d["g_qq_per_H"], atol_scale=COLUMN_ATOL["direct"])
    # Inductances at the same psi: the 2x2 inverse of the Jacobian above.
    det = g_dd * g_qq - g_dq * g_dq
    assert_close("l_dd(psi)", g_qq / det, d["l_dd_H"], atol_scale=COLUMN_ATOL["direct"])
    assert_close("l_dq(psi)", -g_dq / det, d["l_dq_H"], atol_scale=COLUMN_ATOL["direct"])
    assert_close("l_qq(psi)", g_dd / det, d["l_qq_H"], atol_scale=COLUMN_ATOL["direct"])
    # Energy: machine.py's energy() has no offset, the C++ one is zero at psi0 = flux(0). The
    # subtraction cancels ~|W(psi0)| (a few J), so the floor is relative to that as well.
    psi0 = sm.psi_pm()
    w = sm.energy(psi_d, psi_q) - sm.energy(psi0, 0.0)
    w_scale = max(float(np.max(np.abs(d["energy_J"]))), abs(float(sm.energy(psi0, 0.0))))
    err = np.abs(w - d["energy_J"])
    assert np.all(err <= RTOL * np.abs(d["energy_J"]) + 1e-12 * w_scale), (
        f"energy: worst |diff| {err.max():.3g} J")


def test_current_grid_flux_of_current(preset, current_grid):
    """psi = flux(i), differential inductances at i and torque at i on the current grid."""
    _, m, _ = preset
    d = current_grid
    i_d, i_q = d["i_d_A"], d["i_q_A"]
    psi_d, psi_q = m.model.flux(i_d, i_q)
    assert_close("flux(i)_d", psi_d, d["psi_d_Wb"], atol_scale=COLUMN_ATOL["newton"])
    assert_close("flux(i)_q", psi_q, d["psi_q_Wb"], atol_scale=COLUMN_ATOL["newton"])
    l_dd, l_dq, l_qq = m.model.inductances(i_d, i_q)
    assert_close("l_dd(i)", l_dd, d["l_dd_H"], atol_scale=COLUMN_ATOL["newton"])
    assert_close("l_dq(i)", l_dq, d["l_dq_H"], atol_scale=COLUMN_ATOL["newton"])
    assert_close("l_qq(i)", l_qq, d["l_qq_H"], atol_scale=COLUMN_ATOL["newton"])
    assert_close("torque(i)", m.torque(i_d, i_q), d["torque_Nm"], atol_scale=COLUMN_ATOL["newton"])
    # The C++ flux really inverts its current map (else the comparison above would be vacuous).
    np.testing.assert_allclose(d["cur_d_A"], i_d, rtol=0, atol=1e-9 * np.max(np.abs(i_d)))
    np.testing.assert_allclose(d["cur_q_A"], i_q, rtol=0, atol=1e-9 * np.max(np.abs(i_q)))


def test_current_grid_at_cpp_flux(preset, current_grid):
    """current(psi), Jacobian, inductances and energy evaluated at the C++ psi = flux(i)."""
    _compare_at_psi(preset[1], current_grid)


def test_flux_grid_current_of_flux(preset, flux_grid):
    """i = current(psi) etc. on a flux grid through psi_d < 0, psi_d = 0 and psi_q = 0."""
    _, m, _ = preset
    d = flux_grid
    _compare_at_psi(m, d)
    t = torque(m.pole_pairs, d["psi_d_Wb"], d["psi_q_Wb"], d["i_d_A"], d["i_q_A"])
    assert_close("torque(psi)", t, d["torque_Nm"], atol_scale=COLUMN_ATOL["direct"])


def test_small_signal_at_zero_current(preset):
    """psi_pm, Ld, Lq at i = 0: machine.py == C++ (tightly), and both == the preset file."""
    path, m, raw = preset
    d = run_dump(path, "--i", 0, 0)
    psi_pm, ld, lq = m.small_signal()
    cpp = {"psi_pm": d["psi_d_Wb"][0], "ld": d["l_dd_H"][0], "lq": d["l_qq_H"][0]}
    assert d["psi_q_Wb"][0] == 0.0 and d["l_dq_H"][0] == 0.0
    for name, py in (("psi_pm", psi_pm), ("ld", ld), ("lq", lq)):
        assert py == pytest.approx(cpp[name], rel=RTOL), name
    assert cpp["psi_pm"] == pytest.approx(raw["psi_pm_wb"], rel=PRESET_ROUNDING_RTOL)
    assert cpp["ld"] == pytest.approx(raw["ld_h"], rel=PRESET_ROUNDING_RTOL)
    assert cpp["lq"] == pytest.approx(raw["lq_h"], rel=PRESET_ROUNDING_RTOL)
    # machine.py read the same parameters the C++ loader did.
    assert (m.pole_pairs, m.psi_pm_wb, m.ld_h, m.lq_h) == (
        raw["pole_pairs"], raw["psi_pm_wb"], raw["ld_h"], raw["lq_h"])


def test_model_dump_rejects_bad_arguments():
    for args in ([], ["sun2016-ipm-5kw", "--n", "1"], ["sun2016-ipm-5kw", "--i", "1"],
                 ["sun2016-ipm-5kw", "--bogus"], ["no-such-preset"],
                 ["sun2016-ipm-5kw", "--psi-grid", "1", "0", "0", "1"]):
        proc = subprocess.run([str(MODEL_DUMP), *args], capture_output=True, text=True, timeout=60)
        assert proc.returncode == 2, args
        assert proc.stderr.startswith("model-dump: "), args
        assert proc.stdout == "", args
