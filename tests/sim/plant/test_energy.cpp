// (3) Energy ledger: electrical input = copper loss + delta magnetic energy + mechanical output,
// with the switching inverter (dead time, device drop) and the analytic saturation model.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "plant_test_util.hpp"

using namespace mcsim;
using namespace plant_test;

namespace {
double run_and_residual(int substeps, bool print) {
    PlantConfig c = base_config();
    c.inverter.mode = InverterConfig::Mode::Switching;
    c.inverter.t_dead = 0.2e-6;
    c.inverter.v_device = 0.5;
    c.mech.load_torque = [](double t) { return 3.0 * t; };
    c.substeps = substeps;
    Plant p(c, make_analytic_model(c.machine.sat));
    const double Ts = 1e-4;
    // 0.3 s: accelerate with a synchronous open-loop current source, then field-weakening-like
    // negative d current (stores and returns magnetic energy), so every term is exercised.
    for (int k = 0; k < 3000; ++k) {
        const Vec2 iref = k < 2000 ? Vec2(0.0, 15.0) : Vec2(-8.0, 6.0);
        p.step_period(Ts, feedforward_duties(p, iref, Ts), true);
    }
    const auto& e = p.energy();
    const double res = e.electrical_in - e.copper_loss - e.magnetic - e.mech_out;
    if (print)
        std::printf("energy [J]: in %.6f, copper %.6f, magnetic %.6f, mech %.6f, residual %.3e "
                    "(%.2e of input), w = %.2f rad/s\n",
                    e.electrical_in, e.copper_loss, e.magnetic, e.mech_out, res, res / e.electrical_in,
                    p.omega_m());
    EXPECT_GT(e.copper_loss, 0.1);
    EXPECT_GT(std::fabs(e.magnetic), 1e-3);
    EXPECT_GT(e.mech_out, 1.0);
    return res / e.electrical_in;
}
}  // namespace

TEST(PlantEnergy, BalanceWithSwitchingInverterAndSaturation) {
    const double rel = run_and_residual(2, true);
    EXPECT_LT(std::fabs(rel), 1e-3);  // the brief's bound; measured 1.3e-7 (Hermite truncation at 3200 rpm)
    EXPECT_LT(std::fabs(rel), 1e-6);
}

TEST(PlantEnergy, MagneticTermIsThreeHalvesOfModelEnergy) {
    PlantConfig c = base_config();
    c.inverter.mode = InverterConfig::Mode::Averaged;
    c.mech.locked = true;
    Plant p(c, make_analytic_model(c.machine.sat));
    for (int k = 0; k < 500; ++k) p.step_period(1e-4, duties_for(Vec2(4.0, 0.0), c.inverter.vdc), true);
    const double w = p.model().energy(p.psi_dq()) - p.model().energy(p.psi_no_current());
    EXPECT_NEAR(p.energy().magnetic, 1.5 * w, 1e-12);
    EXPECT_EQ(p.energy().mech_out, 0.0);  // locked: no mechanical output
    const auto& e = p.energy();
    EXPECT_NEAR(e.electrical_in - e.copper_loss - e.magnetic, 0.0, 1e-9 * e.electrical_in);
}
