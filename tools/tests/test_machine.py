import math

import numpy as np
import pytest

from mctools.machine import Machine, SaturationModel, machine_from_dict

# machines.md, sun2016-ipm-5kw (inline so the test does not depend on presets/)
SUN = dict(S=2, T=2, U=1, V=0, a_d0=86.58, a_dd=24.52, a_q0=58.12, a_qq=774.0, a_dq=1441.3,
           i_f=30.69)
BRODATZKI = dict(S=2, T=2, U=1, V=1, a_d0=1764.4, a_dd=3.726e5, a_q0=1819.4, a_qq=4.582e5,
                 a_dq=2.476, i_f=303.1)


def sun_machine():
    return machine_from_dict(dict(
        name="sun2016-ipm-5kw", pole_pairs=5, rs_ohm=0.4, psi_pm_wb=0.34305, ld_h=10.5e-3,
        lq_h=12.9e-3, inertia_kgm2=0.013, friction_nms=1.3e-3, i_rated_peak_a=13.29,
        torque_rated_nm=29.7, vdc_nominal_v=300.0, f_sample_hz=1e4, saturation=SUN))


@pytest.fixture(params=["sun", "brodatzki"])
def model(request):
    return SaturationModel.from_mapping(SUN if request.param == "sun" else BRODATZKI)


def test_small_signal_at_zero_current():
    psi_pm, ld, lq = sun_machine().small_signal()
    assert psi_pm == pytest.approx(0.34305, rel=1e-3)
    assert ld == pytest.approx(10.5e-3, rel=0.01)
    assert lq == pytest.approx(12.9e-3, rel=0.01)


def test_flux_inverts_current_map(model):
    i_d, i_q = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(-1, 1, 9))
    scale = 13.29 if model.i_f < 100 else 160.0
    psi_d, psi_q = model.flux(scale * i_d, scale * i_q)
    back_d, back_q = model.current(psi_d, psi_q)
    np.testing.assert_allclose(back_d, scale * i_d, atol=1e-8)
    np.testing.assert_allclose(back_q, scale * i_q, atol=1e-8)


def test_reciprocity_and_jacobian_against_finite_differences(model):
    rng = np.random.default_rng(1)
    pm = model.psi_pm()
    psi_d = pm * rng.uniform(0.5, 1.2, 50)
    psi_q = pm * rng.uniform(-1.0, 1.0, 50)
    g_dd, g_dq, g_qq = model.jacobian(psi_d, psi_q)
    h = 1e-6 * pm
    did_dpsiq = (model.current(psi_d, psi_q + h)[0] - model.current(psi_d, psi_q - h)[0]) / (2 * h)
    diq_dpsid = (model.current(psi_d + h, psi_q)[1] - model.current(psi_d - h, psi_q)[1]) / (2 * h)
    did_dpsid = (model.current(psi_d + h, psi_q)[0] - model.current(psi_d - h, psi_q)[0]) / (2 * h)
    diq_dpsiq = (model.current(psi_d, psi_q + h)[1] - model.current(psi_d, psi_q - h)[1]) / (2 * h)
    # Reciprocity: the current map is the gradient of an energy, so the mixed
    # derivatives agree (numerically, independent of the analytic Jacobian).
    np.testing.assert_allclose(did_dpsiq, diq_dpsid, rtol=1e-6, atol=1e-6 * np.abs(g_dd).max())
    np.testing.assert_allclose(did_dpsid, g_dd, rtol=1e-6)
    np.testing.assert_allclose(diq_dpsiq, g_qq, rtol=1e-6)
    np.testing.assert_allclose(did_dpsiq, g_dq, rtol=1e-5, atol=1e-6 * np.abs(g_dd).max())


def test_current_is_gradient_of_energy(model):
    psi_d, psi_q = 0.9 * model.psi_pm(), -0.4 * model.psi_pm()
    h = 1e-6 * model.psi_pm()
    i_d, i_q = model.current(psi_d, psi_q)
    dw_d = (model.energy(psi_d + h, psi_q) - model.energy(psi_d - h, psi_q)) / (2 * h)
    dw_q = (model.energy(psi_d, psi_q + h) - model.energy(psi_d, psi_q - h)) / (2 * h)
    assert dw_d == pytest.approx(float(i_d), rel=1e-6, abs=1e-6)
    assert dw_q == pytest.approx(float(i_q), rel=1e-6, abs=1e-6)


def test_cross_saturation_lowers_psi_d():
    m = SaturationModel.from_mapping(SUN)
    psi_d0, _ = m.flux(0.0, 0.0)
    psi_d1, _ = m.flux(0.0, 13.0)
    assert psi_d1 < psi_d0


def test_d_axis_saturation_is_asymmetric():
    # Polarity detection relies on |l_dd(+i)| != |l_dd(-i)|: positive i_d saturates more.
    m = SaturationModel.from_mapping(SUN)
    l_pos = m.inductances(10.0, 0.0)[0]
    l_neg = m.inductances(-10.0, 0.0)[0]
    assert l_pos < l_neg


def test_mtpa_sun2016_rated():
    p = sun_machine().mtpa(13.29)
    assert p.torque_nm == pytest.approx(32.5, abs=0.1)
    assert math.hypot(p.i_d, p.i_q) == pytest.approx(13.29)
    assert p.i_d < 0 < p.i_q
    # It is a maximum: neighbouring current angles give less torque.
    m = sun_machine()
    for db in (-0.02, 0.02):
        b = math.atan2(p.i_q, p.i_d) + db
        assert float(m.torque(13.29 * math.cos(b), 13.29 * math.sin(b))) < p.torque_nm


def test_mtpa_brodatzki():
    m = machine_from_dict(dict(name="b", pole_pairs=4, rs_ohm=0.01, psi_pm_wb=0.0767,
                               ld_h=120e-6, lq_h=550e-6, saturation=BRODATZKI))
    p = m.mtpa(160.0)
    assert p.torque_nm == pytest.approx(79.3, abs=0.2)
    assert p.i_d == pytest.approx(-55, abs=1.5)
    assert p.i_q == pytest.approx(150, abs=1.5)


def test_linear_model_matches_closed_form_mtpa():
    ld, lq, psi, p, I = 10e-3, 20e-3, 0.3, 4, 10.0
    m = Machine("lin", p, 0.1, psi, ld, lq, SaturationModel.linear(ld, lq, psi))
    # Closed-form MTPA for constant inductances.
    dl = ld - lq
    i_d = (psi - math.sqrt(psi**2 + 8 * dl**2 * I**2)) / (4 * (lq - ld))
    i_q = math.sqrt(I**2 - i_d**2)
    t = 1.5 * p * (psi * i_q + dl * i_d * i_q)
    pt = m.mtpa(I)
    assert pt.torque_nm == pytest.approx(t, rel=1e-9)
    assert pt.i_d == pytest.approx(i_d, abs=1e-5)


def test_base_speed_noload():
    m = sun_machine()
    expected = 300 / math.sqrt(3) / 0.34305 / 5 * 60 / (2 * math.pi)
    assert expected == pytest.approx(964, abs=1)
    assert m.base_speed_rpm() == pytest.approx(expected, rel=1e-3)
    p = m.mtpa(13.29)
    assert m.base_speed_rpm(p.i_d, p.i_q) < m.base_speed_rpm()


def test_inductance_ranges_match_machines_md():
    (ldd_lo, ldd_hi), (lqq_lo, lqq_hi) = sun_machine().inductance_ranges(13.3)
    assert ldd_lo == pytest.approx(9.96e-3, rel=0.01)
    assert ldd_hi == pytest.approx(11.18e-3, rel=0.01)
    assert lqq_lo == pytest.approx(8.38e-3, rel=0.01)
    assert lqq_hi == pytest.approx(16.2e-3, rel=0.01)


def test_preset_dict_errors():
    with pytest.raises(ValueError, match="required"):
        machine_from_dict({"name": "x"})
    with pytest.raises(ValueError, match="unknown saturation"):
        SaturationModel.from_mapping({**SUN, "a_zz": 1.0})
