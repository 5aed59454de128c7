// Helpers shared by the plant tests: thesis machine (Table 4.1), duty synthesis.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

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

// High-speed integration runs (test_dynamics, test_ripple): 1500 rpm x 5 pole pairs on a dyno,
// one recorded voltage sequence replayed into every integrator.
using namespace mcsim;
struct Traj {
    std::vector<Vec2> i;
};

inline PlantConfig high_speed_config(InverterConfig::Mode mode, int substeps) {
    PlantConfig c = base_config();
    c.inverter.mode = mode;
    c.inverter.vdc = 600.0;  // back-EMF at 1500 rpm is 270 V peak: beyond a 300 V link
    c.inverter.t_dead = 0.0;
    c.mech.mode = MechanicsConfig::Mode::Dyno;
    const double w = 1500.0 * 2.0 * kPi / 60.0;
    c.mech.dyno_speed = [w](double) { return w; };
    c.omega_m0 = w;
    c.substeps = substeps;
    return c;
}

// Voltage sequence recorded from one run, replayed into the others so that all integrators see
// the same input.
inline std::vector<Vec2> make_voltages(int n, double Ts) {
    PlantConfig c = high_speed_config(InverterConfig::Mode::Averaged, 4);
    Plant p(c, make_analytic_model(c.machine.sat));
    std::vector<Vec2> u;
    for (int k = 0; k < n; ++k) {
        const auto d = feedforward_duties(p, Vec2(-3.0, 8.0), Ts);
        u.push_back(clarke_phase_voltages({(d[0] - 0.5) * 600.0, (d[1] - 0.5) * 600.0, (d[2] - 0.5) * 600.0}));
        p.step_period(Ts, d, true);
    }
    return u;
}

inline Traj run_config(const PlantConfig& c, const std::vector<Vec2>& u, double Ts) {
    Plant p(c, make_analytic_model(c.machine.sat));
    Traj t;
    for (const auto& v : u) {
        p.step_period(Ts, duties_for(v, 600.0), true);
        t.i.push_back(p.i_dq());
    }
    return t;
}

inline Traj run(InverterConfig::Mode mode, int substeps, const std::vector<Vec2>& u, double Ts,
                PlantConfig::Integrator integ = PlantConfig::Integrator::Hermite, bool ledger = true) {
    PlantConfig c = high_speed_config(mode, substeps);
    c.integrator = integ;
    c.energy_ledger = ledger;
    return run_config(c, u, Ts);
}

inline double max_diff(const Traj& a, const Traj& b) {
    double m = 0;
    for (size_t k = 0; k < a.i.size(); ++k) m = std::max(m, (a.i[k] - b.i[k]).norm());
    return m;
}

// Inertia mode (the mechanics integrated with the electrical state): 0.1 s of acceleration from
// 50 rad/s under a ramping load, open-loop synchronous current source; currents and speeds.
inline Traj inertia_run(PlantConfig::Integrator integ, int substeps, double Ts, std::vector<double>* w,
                        bool ledger = true) {
    PlantConfig c = base_config();
    c.inverter.mode = InverterConfig::Mode::Switching;
    c.inverter.t_dead = 0.0;
    c.mech.load_torque = [](double t) { return 5.0 + 50.0 * t; };
    c.omega_m0 = 50.0;
    c.integrator = integ;
    c.substeps = substeps;
    c.energy_ledger = ledger;
    Plant p(c, make_analytic_model(c.machine.sat));
    Traj t;
    for (int k = 0; k < 1000; ++k) {
        p.step_period(Ts, feedforward_duties(p, Vec2(-2.0, 12.0), Ts), true);
        t.i.push_back(p.i_dq());
        w->push_back(p.omega_m());
    }
    return t;
}

}  // namespace plant_test
