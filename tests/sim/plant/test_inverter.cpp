// Inverter: dead-time voltage error (4), switching vs averaged trajectories (5), sequencing, and
// the Taylor path's CentredPwm against the general PwmSequencer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <vector>

#include "mcsim/centred_pwm.hpp"
#include "plant_test_util.hpp"

using namespace mcsim;
using namespace plant_test;

namespace {
// Locked rotor at theta = 0 with a DC current vector along alpha (phase a): i_a = I, i_b = i_c = -I/2.
Plant dc_plant(InverterConfig::Mode mode, double u_alpha, std::array<double, 3>* duty) {
    PlantConfig c = base_config();
    c.inverter.mode = mode;
    c.inverter.t_dead = 1e-6;
    c.inverter.averaged_dead_time = true;
    c.mech.locked = true;
    Plant p(c, linear_model(c.machine));
    *duty = duties_for(Vec2(u_alpha, 0.0), c.inverter.vdc);
    for (int k = 0; k < 3000; ++k) p.step_period(1e-4, *duty, true);
    return p;
}
}  // namespace

// (4) Per phase, the period-average voltage error is -sign(i) vdc t_dead / Ts (= 3 V here).
TEST(PlantInverter, DeadTimeVoltageError) {
    for (auto mode : {InverterConfig::Mode::Switching, InverterConfig::Mode::Averaged}) {
        for (double ua : {10.0, -10.0}) {
            std::array<double, 3> d{};
            Plant p = dc_plant(mode, ua, &d);
            const auto i = p.i_abc();
            const auto v = p.v_phase_avg_last();
            const double expect = 300.0 * 1e-6 / 1e-4;
            for (int k = 0; k < 3; ++k) {
                ASSERT_GT(std::fabs(i[k]), 2.0);  // far outside the zero band, ripple included
                const double err = v[k] - (d[k] - 0.5) * 300.0;
                EXPECT_NEAR(err, -(i[k] > 0 ? 1.0 : -1.0) * expect, 1e-9) << "phase " << k;
            }
            // The current settles where the reduced voltage puts it: u_alpha - 4 V for i_a > 0.
            EXPECT_NEAR(p.i_dq().x(), (ua - (ua > 0 ? 4.0 : -4.0)) / 0.4, 0.05);
        }
    }
}

// Inside the zero band the commanded edges are taken: no error with zero current.
TEST(PlantInverter, NoDeadTimeErrorAtZeroCurrent) {
    PlantConfig c = base_config();
    c.inverter.t_dead = 1e-6;
    c.mech.locked = true;
    Plant p(c, linear_model(c.machine));
    p.step_period(1e-4, {0.3, 0.3, 0.3}, true);
    const auto v = p.v_phase_avg_last();
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(v[k], (0.3 - 0.5) * 300.0, 1e-9);
    EXPECT_NEAR(p.i_dq().norm(), 0.0, 1e-12);
}

// A pulse shorter than the dead time with i > 0 is swallowed: the phase stays low.
TEST(PlantInverter, ShortPulseSwallowedByDeadTime) {
    InverterConfig cfg;
    cfg.t_dead = 2e-6;
    PwmSequencer s;
    s.begin(0.0, 1e-4, {0.01, 0.5, 0.0}, cfg);  // phase a: 1 us pulse
    double t, high_a = 0, last = 0;
    int lv_a = s.levels()[0];
    while (s.next_time(&t)) {
        if (lv_a > 0) high_a += t - last;
        last = t;
        s.apply(t, {5.0, -2.5, -2.5});
        lv_a = s.levels()[0];
    }
    EXPECT_EQ(high_a, 0.0);
    EXPECT_EQ(s.levels()[0], -1);
}

// (5) Switching and averaged inverters give the same current at the V000 centre samples
// within the ripple (dyno 600 rpm, no dead time, synchronous voltage).
TEST(PlantInverter, SwitchingMatchesAveragedWithinRipple) {
    auto cfg = [](InverterConfig::Mode mode) {
        PlantConfig c = base_config();
        c.inverter.mode = mode;
        c.inverter.t_dead = 0.0;
        c.mech.mode = MechanicsConfig::Mode::Dyno;
        const double w = 600.0 * 2.0 * kPi / 60.0;
        c.mech.dyno_speed = [w](double) { return w; };
        c.omega_m0 = w;
        return c;
    };
    const PlantConfig ca = cfg(InverterConfig::Mode::Averaged), cs = cfg(InverterConfig::Mode::Switching);
    Plant pa(ca, make_analytic_model(ca.machine.sat)), ps(cs, make_analytic_model(cs.machine.sat));
    const double Ts = 1e-4;
    double max_diff = 0.0;
    for (int k = 0; k < 2000; ++k) {
        const auto d = feedforward_duties(pa, Vec2(-2.0, 6.0), Ts);
        pa.step_period(Ts, d, true);
        ps.step_period(Ts, d, true);
        max_diff = std::max(max_diff, (pa.i_dq() - ps.i_dq()).norm());
    }
    // Peak-to-peak ripple scale: (vdc/2) (Ts/2) / L ~ 0.7 A.
    const double ripple = 150.0 * 0.5e-4 / 10.5e-3;
    std::printf("switching vs averaged: max |i_dq diff| at samples %.4f A (ripple scale %.2f A)\n",
                max_diff, ripple);
    EXPECT_LT(max_diff, 0.1 * ripple);
    EXPECT_GT(pa.i_dq().norm(), 5.0);
}

// predecide() must give the same voltage timeline as deciding at each commanded edge; with
// constant currents the prediction is exact (di_max = 0), so the timelines must be identical.
TEST(PlantInverter, PredecideMatchesEdgeDecisions) {
    InverterConfig cfg;
    cfg.t_dead = 2e-6;
    const double Ts = 1e-4;
    uint64_t st = 12345;
    auto rnd = [&st] {
        st = st * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(st >> 11) * (1.0 / 9007199254740992.0);
    };
    for (int trial = 0; trial < 2000; ++trial) {
        std::array<double, 3> d, i;
        for (int k = 0; k < 3; ++k) {
            const double r = rnd();
            d[k] = r < 0.1 ? rnd() * 0.05 : (r > 0.9 ? 1.0 - rnd() * 0.05 : rnd());  // short pulses too
            i[k] = (rnd() - 0.5) * 10.0;
        }
        if (trial % 7 == 0) i[trial % 3] = 0.01;  // inside the zero band
        auto timeline = [&](bool pre) {
            PwmSequencer s;
            s.begin(0.0, Ts, d, cfg);
            if (pre) s.predecide(0.0, i, 0.0);
            std::array<double, 3> high{0, 0, 0};
            double last = 0.0, t;
            auto lv = s.levels();
            while (s.next_time(&t)) {
                for (int k = 0; k < 3; ++k) high[k] += lv[k] > 0 ? t - last : 0.0;
                last = t;
                s.apply(t, i);
                if (pre) s.predecide(t, i, 0.0);
                lv = s.levels();
            }
            for (int k = 0; k < 3; ++k) high[k] += lv[k] > 0 ? Ts - last : 0.0;
            return high;
        };
        const auto a = timeline(false), b = timeline(true);
        for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], b[k], 1e-15) << "trial " << trial << " phase " << k;
        // and the dead-time rule itself: on-time error -sign(i) t_dead unless swallowed/clipped
        for (int k = 0; k < 3; ++k) {
            if (std::fabs(i[k]) <= cfg.i_zero_band || d[k] * Ts < 2 * cfg.t_dead || d[k] > 0.9) continue;
            EXPECT_NEAR(a[k] - d[k] * Ts, (i[k] > 0 ? -1.0 : 1.0) * cfg.t_dead, 1e-15);
        }
    }
}

// CentredPwm (the Taylor path's sequencer) must change the levels at exactly the instants and to
// exactly the levels PwmSequencer does, asking for currents at the same instants, for any duties
// (0, 1, ties, pulses shorter than the dead time), dead times (none, short, longer than some
// pulses, turn-offs within t_dead of the period end) and currents that cross the zero band inside
// the period.
TEST(PlantInverter, CentredPwmMatchesPwmSequencer) {
    uint64_t st = 987654321;
    auto rnd = [&st] {
        st = st * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(st >> 11) * (1.0 / 9007199254740992.0);
    };
    const double Ts = 1e-4;
    struct Change {
        double tau;
        std::array<int, 3> lv;
        bool operator==(const Change& o) const { return tau == o.tau && lv == o.lv; }
    };
    int swallowed = 0, near_end = 0, band_hits = 0, changes = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        InverterConfig cfg;
        const double dead[] = {0.0, 0.5e-6, 2e-6, 20e-6};
        cfg.t_dead = dead[trial % 4];
        const double t0 = (trial % 3) * 0.1234567 + trial * Ts;
        std::array<double, 3> d, a, b;
        for (int k = 0; k < 3; ++k) {
            const double r = rnd();
            d[k] = r < 0.1 ? rnd() * 0.05 : (r > 0.9 ? 1.0 - rnd() * 0.05 : rnd());
            if (r < 0.03) d[k] = 0.0;
            if (r > 0.97) d[k] = 1.0;
            a[k] = (rnd() - 0.5) * 6.0;
            b[k] = (rnd() - 0.5) * 2e5;  // [A/s]: up to 10 A over the period, so signs change
        }
        if (trial % 5 == 0) d[1] = d[0];  // coincident edges
        if (trial % 11 == 0) d[2] = -0.2;  // out of range: clamped
        if (trial % 13 == 0) d[0] = 1.3;
        auto cur = [&](double tau) {
            std::array<double, 3> i;
            for (int k = 0; k < 3; ++k) i[k] = a[k] + b[k] * tau;
            if (trial % 7 == 0) i[trial % 3] = 0.5 * cfg.i_zero_band;  // inside the band
            return i;
        };
        // The general sequencer, driven as the Taylor path drove it before CentredPwm.
        std::vector<Change> ref, got;
        std::vector<double> ref_q, got_q;
        PwmSequencer s;
        s.begin(t0, Ts, d, cfg);
        auto lv = s.levels();
        double te;
        while (s.next_time(&te)) {
            const double tau = te - t0;
            const bool need = s.next_needs_currents();
            if (need && cfg.t_dead > 0.0) ref_q.push_back(tau);
            s.apply(te, need ? cur(tau) : std::array<double, 3>{0.0, 0.0, 0.0});
            if (s.levels() != lv) ref.push_back({tau, lv = s.levels()});
        }
        CentredPwm c;
        c.begin(t0, Ts, d, cfg);
        PwmSequencer s0;
        s0.begin(t0, Ts, d, cfg);
        ASSERT_EQ(c.levels(), s0.levels()) << "trial " << trial;  // at the period start
        c.walk(
            [&](double tau, unsigned mask) {
                got_q.push_back(tau);
                EXPECT_NE(mask, 0u);
                return cur(tau);
            },
            [&](double tau, const std::array<int, 3>& l) { got.push_back({tau, l}); });
        ASSERT_EQ(ref.size(), got.size()) << "trial " << trial;
        for (size_t k = 0; k < ref.size(); ++k) ASSERT_TRUE(ref[k] == got[k]) << "trial " << trial << " change " << k;
        ASSERT_EQ(ref_q, got_q) << "trial " << trial;
        EXPECT_EQ(s.levels(), c.levels()) << "trial " << trial;
        changes += static_cast<int>(got.size());
        // what the trials covered
        for (int k = 0; k < 3; ++k) {
            const double dk = d[k] < 0.0 ? 0.0 : (d[k] > 1.0 ? 1.0 : d[k]);
            if (dk > 0.0 && dk < 1.0 && cfg.t_dead > dk * Ts) ++swallowed;
            if (dk > 0.0 && dk < 1.0 && 0.5 * (1.0 + dk) * Ts + cfg.t_dead > Ts) ++near_end;
        }
        if (trial % 7 == 0 && cfg.t_dead > 0.0) ++band_hits;
    }
    std::printf("CentredPwm == PwmSequencer: 20000 periods, %d level changes; pulses shorter than t_dead %d, "
                "turn-offs within t_dead of the period end %d, zero-band currents %d\n",
                changes, swallowed, near_end, band_hits);
    EXPECT_GT(swallowed, 100);
    EXPECT_GT(near_end, 100);
}
