// The period-level ripple-moment integrator (PlantConfig::Integrator::Ripple, sim/src/ripple.hpp):
// its error against a 100x finer RK4 at high speed, with dead time against the edge-by-edge
// Hermite (and its fallback exercised), in inertia mode, and its energy ledger. Figures and why
// the bounds differ from the Hermite integrator's: docs/plant.md "Ripple moments".
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "plant_test_util.hpp"

using namespace mcsim;
using namespace plant_test;

namespace {
constexpr double kTs = 1e-4;
using I = PlantConfig::Integrator;
}  // namespace

// 785 rad/s electrical, no dead time: one step per period (the runner's setting) and two.
TEST(PlantRipple, ErrorAtHighSpeedAgainstFineRk4) {
    const auto u = make_voltages(300, kTs);
    const auto swi = InverterConfig::Mode::Switching;
    const Traj ref = run(swi, 200, u, kTs, I::Rk4);
    const double e1 = max_diff(run(swi, 1, u, kTs, I::Ripple), ref);
    const double e2 = max_diff(run(swi, 2, u, kTs, I::Ripple), ref);
    const double e_herm = max_diff(run(swi, 2, u, kTs), ref);
    std::printf("785 rad/s el., vs 100x finer RK4: ripple 1 step/period %.3e A, 2 steps %.3e A (Hermite %.3e A)\n",
                e1, e2, e_herm);
    EXPECT_LT(e1, 2e-6);
    EXPECT_LT(e2, 1e-6);
}

// With 0.5 us dead time the edges are decided from predicted currents and checked afterwards;
// currents cross zero every few periods here, so some periods must go back to the edge-by-edge
// path, and the trajectory must still match the edge-by-edge Hermite.
TEST(PlantRipple, DeadTimeDecisionsMatchEdgeByEdge) {
    const auto u = make_voltages(300, kTs);
    auto cfg = [](I integ, int substeps) {
        PlantConfig c = high_speed_config(InverterConfig::Mode::Switching, substeps);
        c.inverter.t_dead = 0.5e-6;
        c.integrator = integ;
        c.predecide_edges = false;
        return c;
    };
    const Traj ref = run_config(cfg(I::Hermite, 2), u, kTs);
    const PlantConfig c = cfg(I::Ripple, 1);
    Plant p(c, make_analytic_model(c.machine.sat));
    Traj t;
    for (const auto& v : u) {
        p.step_period(kTs, duties_for(v, 600.0), true);
        t.i.push_back(p.i_dq());
    }
    const auto& st = p.ripple_stats();
    const double e = max_diff(t, ref);
    std::printf("dead time 0.5 us: ripple vs edge-by-edge Hermite %.3e A; %lld of %lld periods redone edge by edge\n",
                e, st.fallbacks, st.periods);
    EXPECT_LT(e, 2e-6);  // a wrong decision would show as ~vdc t_dead G ~ 1e-2 A
    EXPECT_EQ(st.periods, 300);
    EXPECT_GT(st.fallbacks, 0);
    EXPECT_LT(st.fallbacks, 30);
}

// Inertia mode: the torque ripple's share of omega and theta comes from the moments. The known
// weak point of the method (docs/plant.md): ~1e-9 N m s of torque integral per period with the
// saturated model, 300x the Hermite's error, still 100x below an ADC count of current.
TEST(PlantRipple, InertiaModeAgainstFineRk4) {
    std::vector<double> w_ref, w_rp;
    const Traj ref = inertia_run(I::Rk4, 200, kTs, &w_ref);
    const Traj rp = inertia_run(I::Ripple, 1, kTs, &w_rp);
    double ew = 0.0;
    for (size_t k = 0; k < w_ref.size(); ++k) ew = std::max(ew, std::fabs(w_rp[k] - w_ref[k]));
    const double ei = max_diff(rp, ref);
    std::printf("inertia mode, 0.1 s, vs 100x finer RK4: ripple %.3e A, %.3e rad/s (omega %.1f -> %.1f rad/s)\n", ei,
                ew, w_ref.front(), w_ref.back());
    EXPECT_LT(ei, 2e-4);
    EXPECT_LT(ew, 1e-4);
}

// The ledger's ripple terms: electrical input = copper + magnetic + mechanical, accelerating under
// load with dead time (no device drop: that sends every period to the edge-by-edge path).
TEST(PlantRipple, EnergyBalance) {
    PlantConfig c = base_config();
    c.inverter.mode = InverterConfig::Mode::Switching;
    c.inverter.t_dead = 0.2e-6;
    c.mech.load_torque = [](double t) { return 3.0 * t; };
    c.integrator = I::Ripple;
    c.substeps = 1;
    Plant p(c, make_analytic_model(c.machine.sat));
    for (int k = 0; k < 3000; ++k) {
        const Vec2 iref = k < 2000 ? Vec2(0.0, 15.0) : Vec2(-8.0, 6.0);
        p.step_period(kTs, feedforward_duties(p, iref, kTs), true);
    }
    const auto& e = p.energy();
    const double res = e.electrical_in - e.copper_loss - e.magnetic - e.mech_out;
    std::printf("ripple energy [J]: in %.6f, copper %.6f, magnetic %.6f, mech %.6f, residual %.2e of input; "
                "%lld of %lld periods edge by edge\n",
                e.electrical_in, e.copper_loss, e.magnetic, e.mech_out, res / e.electrical_in,
                p.ripple_stats().fallbacks, p.ripple_stats().periods);
    EXPECT_GT(e.mech_out, 1.0);
    EXPECT_GT(std::fabs(e.magnetic), 1e-3);
    EXPECT_LT(p.ripple_stats().fallbacks * 10, p.ripple_stats().periods);
    EXPECT_LT(std::fabs(res / e.electrical_in), 1e-5);
}

// A device drop or a model without analytic third derivatives: every period edge by edge, and
// then the trajectory is the Hermite's, bit for bit.
TEST(PlantRipple, FallsBackWhereItDoesNotApply) {
    const auto u = make_voltages(50, kTs);
    PlantConfig c = high_speed_config(InverterConfig::Mode::Switching, 2);
    c.inverter.t_dead = 0.5e-6;
    c.inverter.v_device = 0.7;
    const Traj h = run_config(c, u, kTs);
    c.integrator = I::Ripple;
    Plant p(c, make_analytic_model(c.machine.sat));
    for (size_t k = 0; k < u.size(); ++k) {
        p.step_period(kTs, duties_for(u[k], 600.0), true);
        ASSERT_EQ(p.i_dq().x(), h.i[k].x()) << "period " << k;
        ASSERT_EQ(p.i_dq().y(), h.i[k].y()) << "period " << k;
    }
    EXPECT_EQ(p.ripple_stats().periods, 0);
}
