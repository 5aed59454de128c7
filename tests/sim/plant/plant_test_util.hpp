// Helpers shared by the plant tests: thesis machine (Table 4.1), duty synthesis.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "mcsim/inverter.hpp"
#include "mcsim/machine.hpp"
#include "mcsim/plant.hpp"

namespace plant_test {

constexpr double kPi = 3.14159265358979323846;

// Table 4.1 constants, written out so that a preset-loader bug cannot mask a plant bug.
inline mcsim::MachineParams thesis_machine() {
    mcsim::MachineParams m;
    m.name = "sun2016-ipm-5kw";
    m.pole_pairs = 5;
    m.rs = 0.400;
    m.psi_pm = 0.34305;
    m.ld = 10.5e-3;
    m.lq = 12.9e-3;
    m.inertia = 0.013;
    m.friction = 1.3e-3;
    m.vdc_nominal = 300.0;
    m.f_sample = 10e3;
    m.sat.S = 2;
    m.sat.T = 2;
    m.sat.U = 1;
    m.sat.V = 0;
    m.sat.a_d0 = 86.58;
    m.sat.a_dd = 24.52;
    m.sat.a_q0 = 58.12;
    m.sat.a_qq = 774.0;
    m.sat.a_dq = 1441.3;
    m.sat.i_f = 30.69;
    return m;
}

inline std::unique_ptr<mcsim::FluxModel> linear_model(const mcsim::MachineParams& m) {
    return mcsim::make_linear_model(m.ld, m.lq, m.psi_pm);
}

inline mcsim::PlantConfig base_config() {
    mcsim::PlantConfig c;
    c.machine = thesis_machine();
    c.mech.inertia = c.machine.inertia;
    c.mech.friction = c.machine.friction;
    return c;
}

// Duties realising u_alpha_beta (period average) with min-max zero sequence.
inline std::array<double, 3> duties_for(const mcsim::Vec2& u_ab, double vdc) {
    const auto v = mcsim::inverse_clarke(u_ab);
    const double off = -0.5 * (std::max({v[0], v[1], v[2]}) + std::min({v[0], v[1], v[2]}));
    std::array<double, 3> d{};
    for (int k = 0; k < 3; ++k) d[k] = std::clamp(0.5 + (v[k] + off) / vdc, 0.0, 1.0);
    return d;
}

inline mcsim::Vec2 rotate(const mcsim::Vec2& x, double th) {
    const double c = std::cos(th), s = std::sin(th);
    return {c * x.x() - s * x.y(), s * x.x() + c * x.y()};
}

// Steady-state feed-forward voltage of the linear model for i_ref at electrical speed we,
// rotated into the stationary frame at the mid-period angle: an ideal open-loop current source.
inline std::array<double, 3> feedforward_duties(const mcsim::Plant& p, const mcsim::Vec2& i_ref, double Ts) {
    const auto& m = p.config().machine;
    const double we = p.omega_e();
    const mcsim::Vec2 u_dq(m.rs * i_ref.x() - we * m.lq * i_ref.y(),
                           m.rs * i_ref.y() + we * (m.ld * i_ref.x() + m.psi_pm));
    return duties_for(rotate(u_dq, p.theta_e() + 0.5 * we * Ts), p.config().inverter.vdc);
}

}  // namespace plant_test
