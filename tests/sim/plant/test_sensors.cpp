// (6) Sensors: ADC quantisation, noise rms, gain/offset, determinism, encoder counts and index.
#include <gtest/gtest.h>

#include <cmath>

#include "mcsim/sensors.hpp"
#include "plant_test_util.hpp"

using namespace mcsim;
using namespace plant_test;

namespace {
Plant locked_plant(double theta_m) {
    PlantConfig c = base_config();
    c.mech.locked = true;
    c.theta_m0 = theta_m;
    return Plant(c, linear_model(c.machine));
}
// theta = 0: i_a = i_d.
void set_current(Plant& p, double i_a) {
    p.reset_state(p.model().flux(Vec2(i_a, 0.0)), 0.0, 0.0);
}
}  // namespace

TEST(PlantSensors, QuantisationStep) {
    AdcConfig a;
    a.i_noise_rms = 0.0;
    a.vdc_noise_rel = 0.0;
    Sensors s(a, EncoderConfig{}, 1);
    Plant p = locked_plant(0.0);
    const double q = s.amps_per_count();
    EXPECT_NEAR(q, 50.0 / 4095.0, 1e-15);
    EXPECT_EQ(s.offset_counts(), 2048.0);
    for (int n = -100; n <= 100; ++n) {
        set_current(p, n * q + 0.3 * q);  // within a step: rounds down to n
        EXPECT_EQ(s.sample_adc(p).i[0], 2048 + n);
        set_current(p, n * q + 0.7 * q);
        EXPECT_EQ(s.sample_adc(p).i[0], 2048 + n + 1);
    }
    set_current(p, 40.0);
    EXPECT_EQ(s.sample_adc(p).i[0], 4095);
    EXPECT_EQ(s.sample_adc(p).i[1], 2048 - std::lround(20.0 / q));  // i_b = -20 A: in range
    set_current(p, -60.0);
    EXPECT_EQ(s.sample_adc(p).i[0], 0);
    EXPECT_EQ(s.sample_adc(p).vdc, static_cast<uint16_t>(std::lround(300.0 / s.volts_per_count())));
}

TEST(PlantSensors, NoiseRmsGainOffsetAndSeed) {
    AdcConfig a;
    a.i_noise_rms = 0.3;
    a.gain_err[1] = 0.02;
    a.offset_err[2] = 0.25;
    a.vdc_noise_rel = 0.01;
    Sensors s(a, EncoderConfig{}, 42), s2(a, EncoderConfig{}, 42), s3(a, EncoderConfig{}, 43);
    Plant p = locked_plant(0.0);
    set_current(p, 10.0);  // i = (10, -5, -5)
    const int n = 40000;
    double m[3] = {0, 0, 0}, m2[3] = {0, 0, 0}, mv = 0, mv2 = 0;
    bool differs = false;
    for (int k = 0; k < n; ++k) {
        const auto x = s.sample_adc(p), y = s2.sample_adc(p), z = s3.sample_adc(p);
        for (int j = 0; j < 3; ++j) {
            ASSERT_EQ(x.i[j], y.i[j]);
            differs |= x.i[j] != z.i[j];
            const double amps = (x.i[j] - s.offset_counts()) * s.amps_per_count();
            m[j] += amps;
            m2[j] += amps * amps;
        }
        const double v = x.vdc * s.volts_per_count();
        mv += v;
        mv2 += v * v;
    }
    EXPECT_TRUE(differs);
    const double expect_mean[3] = {10.0, -5.0 * 1.02, -5.0 + 0.25};
    const double q = s.amps_per_count();
    const double expect_rms = std::sqrt(0.3 * 0.3 + q * q / 12.0);
    for (int j = 0; j < 3; ++j) {
        const double mean = m[j] / n, rms = std::sqrt(m2[j] / n - mean * mean);
        EXPECT_NEAR(mean, expect_mean[j], 0.01) << j;
        EXPECT_NEAR(rms, expect_rms, 0.03 * expect_rms) << j;
    }
    const double vmean = mv / n, vrms = std::sqrt(mv2 / n - vmean * vmean);
    EXPECT_NEAR(vmean, 300.0, 0.1);
    EXPECT_NEAR(vrms, 3.0, 0.1);
}

TEST(PlantSensors, EncoderCountsAndIndex) {
    EncoderConfig e;
    e.lines = 1000;
    e.offset_rad = 0.5;
    Sensors s(AdcConfig{}, e, 7);
    Plant p = locked_plant(0.0);
    auto at = [&](double th) {
        p.reset_state(p.psi_dq(), th, 0.0);
        return s.sample_qep(p);
    };
    const double cnt = 2.0 * kPi / 4000.0;  // rad per count
    auto q = at(0.5 - 0.3);
    EXPECT_FALSE(q.index_seen);
    EXPECT_EQ(q.count, static_cast<uint32_t>(std::floor(-0.3 / cnt) + 4000));
    q = at(0.5 - 0.5 * cnt);
    EXPECT_EQ(q.count, 3999u);
    EXPECT_FALSE(q.index_seen);
    q = at(0.5 + 0.5 * cnt);  // passes the index forwards
    EXPECT_EQ(q.count, 0u);
    EXPECT_TRUE(q.index_seen);
    EXPECT_EQ(q.index_count, 0u);
    q = at(0.5 + 1234.2 * cnt);
    EXPECT_EQ(q.count, 1234u);
    q = at(0.5 + 2.0 * kPi + 10.5 * cnt);  // a turn later: mod 4*lines
    EXPECT_EQ(q.count, 10u);
    EXPECT_TRUE(q.index_seen);

    Sensors r(AdcConfig{}, e, 7);  // backwards pass latches the last count
    p.reset_state(p.psi_dq(), 0.6, 0.0);
    EXPECT_FALSE(r.sample_qep(p).index_seen);
    p.reset_state(p.psi_dq(), 0.4, 0.0);
    q = r.sample_qep(p);
    EXPECT_TRUE(q.index_seen);
    EXPECT_EQ(q.index_count, 3999u);
}

// A diverged plant (NaN/inf currents, Vdc or angle) must not reach a float-to-integer conversion
// out of range (UB): the ADC reads its rails (NaN: the low rail, 0), the encoder holds its count.
TEST(PlantSensors, NonFiniteInputsClampToTheRails) {
    AdcConfig a;
    a.i_noise_rms = 0.0;
    a.vdc_noise_rel = 0.0;
    Sensors s(a, EncoderConfig{}, 1);
    Plant p = locked_plant(0.0);
    const uint16_t top = uint16_t((1u << a.bits) - 1u);
    const double nan = std::nan(""), inf = INFINITY;
    p.reset_state(Vec2(nan, nan), 0.0, 0.0);
    p.set_vdc(nan);
    AdcSample q = s.sample_adc(p);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(q.i[k], 0u) << k;
    EXPECT_EQ(q.vdc, 0u);
    p.set_vdc(inf);
    EXPECT_EQ(s.sample_adc(p).vdc, top);
    p.set_vdc(-inf);
    EXPECT_EQ(s.sample_adc(p).vdc, 0u);
    p.set_vdc(1e300);
    EXPECT_EQ(s.sample_adc(p).vdc, top);

    EncoderConfig e;
    e.lines = 1000;
    Sensors r(AdcConfig{}, e, 1);
    Plant pe = locked_plant(0.0);
    pe.reset_state(pe.psi_dq(), 1234.2 * 2.0 * kPi / 4000.0, 0.0);
    EXPECT_EQ(r.sample_qep(pe).count, 1234u);
    for (const double th : {nan, inf, -inf}) {
        pe.reset_state(pe.psi_dq(), th, 0.0);
        EXPECT_EQ(r.sample_qep(pe).count, 1234u) << th;  // held
    }
    for (const double th : {1e300, -1e300, 1e20}) {
        pe.reset_state(pe.psi_dq(), th, 0.0);
        EXPECT_LT(r.sample_qep(pe).count, 4000u) << th;
    }
}
