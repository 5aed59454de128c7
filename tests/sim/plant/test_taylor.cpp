// The period-level Taylor integrator (PlantConfig::Integrator::Taylor, sim/src/taylor.hpp, the
// scenario runner's default): its error against a 100x finer RK4 (an independent method) at high
// speed, at standstill under full voltage (the largest flux swing a period can have), in inertia
// mode; its dead-time decisions against the edge-by-edge Hermite; the linear model; where it hands
// the period to Hermite (tables, device drop, energy ledger). Figures: docs/plant.md "Taylor".
// The Taylor path keeps no energy ledger, so every run here switches it off (the runner does too).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "mcsim/fluxmap.hpp"
#include "plant_test_util.hpp"

using namespace mcsim;
using namespace plant_test;

namespace {
constexpr double kTs = 1e-4;
using I = PlantConfig::Integrator;

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
    double m = 0.0;
    for (size_t k = 0; k < a.size(); ++k) m = std::max(m, std::fabs(a[k] - b[k]));
    return m;
}
}  // namespace

// 785 rad/s electrical (1500 rpm x 5 pole pairs), no dead time, switching and averaged inverter.
TEST(PlantTaylor, ErrorAtHighSpeedAgainstFineRk4) {
    const auto u = make_voltages(300, kTs);
    const auto swi = InverterConfig::Mode::Switching, avg = InverterConfig::Mode::Averaged;
    const double e_sw = max_diff(run(swi, 2, u, kTs, I::Taylor, false), run(swi, 200, u, kTs, I::Rk4));
    const double e_avg = max_diff(run(avg, 2, u, kTs, I::Taylor, false), run(avg, 200, u, kTs, I::Rk4));
    std::printf("785 rad/s el., vs 100x finer RK4: Taylor switching %.3e A, averaged %.3e A\n", e_sw, e_avg);
    EXPECT_LT(e_sw, 3e-6);  // measured 1.4e-6 A (Hermite 7.4e-9, ripple 6.3e-7)
    EXPECT_LT(e_avg, 3e-6);
}

// Locked rotor, full voltage on the q axis from i = 0: every period the rotor-frame flux moves by
// ~vdc Ts / 3, the largest swing the expansion sees (and the saturated q axis its largest third
// derivative); then the same voltage on the d axis.
TEST(PlantTaylor, ErrorAtStandstillUnderFullVoltage) {
    auto go = [](I integ, int substeps) {
        PlantConfig c = base_config();
        c.inverter.mode = InverterConfig::Mode::Switching;
        c.inverter.t_dead = 0.0;
        c.mech.locked = true;
        c.integrator = integ;
        c.substeps = substeps;
        c.energy_ledger = integ != I::Taylor;
        Plant p(c, make_analytic_model(c.machine.sat));
        Traj t;
        for (int k = 0; k < 60; ++k) {
            const Vec2 u_dq = k < 30 ? Vec2(0.0, 80.0) : Vec2(-80.0, -20.0);
            p.step_period(kTs, duties_for(u_dq, c.inverter.vdc), true);
            t.i.push_back(p.i_dq());
        }
        return t;
    };
    const Traj ref = go(I::Rk4, 200);
    const double e = max_diff(go(I::Taylor, 1), ref);
    std::printf("standstill, 80 V steps: Taylor vs 100x finer RK4 %.3e A (i_q reaches %.1f A)\n", e, ref.i[29].y());
    EXPECT_GT(ref.i[29].y(), 10.0);  // the current did swing through the saturated range
    EXPECT_LT(e, 1e-6);  // measured 3.4e-7 A
}

// With the linear model the expansion is exact (H = 0): what is left is the period-level
// quadrature (Simpson on the smooth path, the ripple's coefficients taken linear in time).
TEST(PlantTaylor, LinearModelAgainstFineRk4) {
    const auto u = make_voltages(300, kTs);
    auto go = [&](I integ, int substeps) {
        PlantConfig c = high_speed_config(InverterConfig::Mode::Switching, substeps);
        c.integrator = integ;
        c.energy_ledger = integ != I::Taylor;
        Plant p(c, linear_model(c.machine));
        Traj t;
        for (const auto& v : u) {
            p.step_period(kTs, duties_for(v, 600.0), true);
            t.i.push_back(p.i_dq());
        }
        return t;
    };
    const double e = max_diff(go(I::Taylor, 1), go(I::Rk4, 200));
    std::printf("linear model, 785 rad/s el.: Taylor vs 100x finer RK4 %.3e A\n", e);
    EXPECT_LT(e, 2e-6);  // measured 8.4e-7 A
}

// 0.5 us dead time: the edges are decided with the current peeked along the interval in progress;
// currents cross zero every few periods at this speed, so decisions near the zero band occur. A
// decision that differed from the edge-by-edge one would show as ~vdc t_dead G ~ 1e-2 A.
TEST(PlantTaylor, DeadTimeDecisionsMatchEdgeByEdge) {
    const auto u = make_voltages(300, kTs);
    auto go = [&](I integ) {
        PlantConfig c = high_speed_config(InverterConfig::Mode::Switching, 2);
        c.inverter.t_dead = 0.5e-6;
        c.integrator = integ;
        c.predecide_edges = false;
        c.energy_ledger = integ != I::Taylor;
        return run_config(c, u, kTs);
    };
    const double e = max_diff(go(I::Taylor), go(I::Hermite));
    std::printf("dead time 0.5 us: Taylor vs edge-by-edge Hermite %.3e A\n", e);
    EXPECT_LT(e, 3e-6);  // measured 1.2e-6 A
}

// Inertia mode: the shaft is integrated once per period from the torque integral and the
// torque's first moment.
TEST(PlantTaylor, InertiaModeAgainstFineRk4) {
    std::vector<double> w_ref, w_t;
    const Traj ref = inertia_run(I::Rk4, 200, kTs, &w_ref);
    const Traj t = inertia_run(I::Taylor, 1, kTs, &w_t, false);
    const double ei = max_diff(t, ref), ew = max_abs_diff(w_t, w_ref);
    std::printf("inertia mode, 0.1 s, vs 100x finer RK4: Taylor %.3e A, %.3e rad/s (omega %.1f -> %.1f rad/s)\n", ei,
                ew, w_ref.front(), w_ref.back());
    EXPECT_GT(std::fabs(w_ref.back() - w_ref.front()), 10.0);
    // measured 3.0e-5 A, 1.4e-5 rad/s (Hermite 1.4e-7 A, 1.8e-7 rad/s; ripple 7.3e-5 A, 4.1e-5 rad/s):
    // the open-loop drive feeds the plant's angle back into its voltages and amplifies ~1e-8 rad/s
    // of speed error per period (docs/plant.md "Taylor").
    EXPECT_LT(ei, 1e-4);
    EXPECT_LT(ew, 5e-5);
}

// The energy ledger and device drops are not on the Taylor path: such a period goes edge by edge
// (Hermite), bit for bit.
TEST(PlantTaylor, LedgerAndDeviceDropGoEdgeByEdge) {
    const auto u = make_voltages(50, kTs);
    for (int variant = 0; variant < 2; ++variant) {
        PlantConfig c = high_speed_config(InverterConfig::Mode::Switching, 2);
        c.inverter.t_dead = 0.5e-6;
        c.energy_ledger = variant == 0;
        c.inverter.v_device = variant == 1 ? 0.7 : 0.0;
        Plant h(c, make_analytic_model(c.machine.sat));
        c.integrator = I::Taylor;
        Plant t(c, make_analytic_model(c.machine.sat));
        for (size_t k = 0; k < u.size(); ++k) {
            h.step_period(kTs, duties_for(u[k], 600.0), true);
            t.step_period(kTs, duties_for(u[k], 600.0), true);
            ASSERT_EQ(t.i_dq().x(), h.i_dq().x()) << "variant " << variant << ", period " << k;
            ASSERT_EQ(t.i_dq().y(), h.i_dq().y()) << "variant " << variant << ", period " << k;
        }
    }
}

// A table model has no closed-form third derivatives: every period goes edge by edge (Hermite),
// bit for bit.
TEST(PlantTaylor, TableModelGoesEdgeByEdge) {
    const auto u = make_voltages(50, kTs);
    PlantConfig c = high_speed_config(InverterConfig::Mode::Switching, 2);
    c.inverter.t_dead = 0.5e-6;
    c.energy_ledger = false;
    const auto analytic = make_analytic_model(c.machine.sat);
    const auto grid = default_flux_map_grid(20.0, 41);
    Plant h(c, make_table_model_from(*analytic, grid));
    c.integrator = I::Taylor;
    Plant t(c, make_table_model_from(*analytic, grid));
    for (size_t k = 0; k < u.size(); ++k) {
        h.step_period(kTs, duties_for(u[k], 600.0), true);
        t.step_period(kTs, duties_for(u[k], 600.0), true);
        ASSERT_EQ(t.i_dq().x(), h.i_dq().x()) << "period " << k;
        ASSERT_EQ(t.i_dq().y(), h.i_dq().y()) << "period " << k;
    }
}
