// Machine presets: the analytic fits reproduce the published figures (machines.md), the loader
// reports bad input by file, key and value.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "mcsim/machine.hpp"

using namespace mcsim;

namespace {

struct Range {
    double lo = 1e300, hi = -1e300;
    void add(double v) { lo = std::min(lo, v), hi = std::max(hi, v); }
};

// Differential self-inductance ranges over the motoring quarter disk i_d <= 0, i_q >= 0,
// |i| <= i_max -- the region machines.md's ranges refer to.
void inductance_ranges(const FluxModel& m, double i_max, Range& ldd, Range& lqq) {
    const int n = 120;
    for (int a = 0; a <= n; ++a)
        for (int b = 0; b <= n; ++b) {
            const Vec2 i(-i_max * a / n, i_max * b / n);
            if (i.norm() > i_max * (1 + 1e-12)) continue;
            const Mat2 l = m.l_diff(i);
            ldd.add(l(0, 0));
            lqq.add(l(1, 1));
        }
}

// Maximum torque per ampere at current magnitude i_mag: i = i_mag (-sin b, cos b), b in [0, pi/2];
// coarse scan then golden-section refinement (T(b) is unimodal there).
struct Mtpa {
    double torque, beta;
    Vec2 i;
};
Mtpa mtpa(const FluxModel& m, int p, double i_mag) {
    auto t_of = [&](double b) { return torque(m, p, i_mag * Vec2(-std::sin(b), std::cos(b))); };
    const int n = 90;
    int best = 0;
    for (int k = 1; k <= n; ++k)
        if (t_of(M_PI / 2 * k / n) > t_of(M_PI / 2 * best / n)) best = k;
    double a = M_PI / 2 * std::max(best - 1, 0) / n, b = M_PI / 2 * std::min(best + 1, n) / n;
    const double g = (std::sqrt(5.0) - 1) / 2;
    for (int it = 0; it < 80; ++it) {
        const double c = b - g * (b - a), d = a + g * (b - a);
        (t_of(c) > t_of(d) ? b : a) = (t_of(c) > t_of(d) ? d : c);
    }
    const double beta = 0.5 * (a + b);
    return {t_of(beta), beta, i_mag * Vec2(-std::sin(beta), std::cos(beta))};
}

std::string read_text(const std::string& path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// A copy of the sun2016 preset with the line starting with `key =` replaced (or removed).
std::string write_variant(const std::string& key, const std::string& new_line) {
    std::istringstream in(read_text(std::string(MCSIM_PRESET_DIR) + "/sun2016-ipm-5kw.toml"));
    std::ostringstream out;
    std::string line;
    bool hit = false;
    while (std::getline(in, line)) {
        if (line.rfind(key + " =", 0) == 0) {
            hit = true;
            if (!new_line.empty()) out << new_line << '\n';
        } else {
            out << line << '\n';
        }
    }
    EXPECT_TRUE(hit) << key;
    const std::string path = ::testing::TempDir() + "/mcsim_variant_" + key + ".toml";
    std::ofstream(path) << out.str();
    return path;
}

std::string load_error(const std::string& path) {
    try {
        load_machine_preset(path);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for " << path;
    return {};
}

}  // namespace

TEST(Presets, Sun2016ReproducesTable41AndFit) {
    const MachineParams mp = load_machine_preset("sun2016-ipm-5kw");
    EXPECT_EQ(mp.name, "sun2016-ipm-5kw");
    EXPECT_EQ(mp.pole_pairs, 5);
    EXPECT_DOUBLE_EQ(mp.rs, 0.4);
    EXPECT_DOUBLE_EQ(mp.inertia, 0.013);
    EXPECT_DOUBLE_EQ(mp.friction, 1.3e-3);
    EXPECT_DOUBLE_EQ(mp.i_rated_peak, 13.29);
    EXPECT_DOUBLE_EQ(mp.vdc_nominal, 300.0);
    EXPECT_DOUBLE_EQ(mp.f_sample, 10e3);
    const auto m = make_preset_model(mp);
    const SmallSignal s = small_signal(*m);
    std::printf("sun2016 fit at i = 0: psi_pm = %.6f Wb, Ld = %.4f mH, Lq = %.4f mH\n", s.psi_pm, 1e3 * s.ld,
                1e3 * s.lq);
    // The fit's coefficients carry 4-5 significant digits; that is the agreement to expect.
    EXPECT_NEAR(s.psi_pm, 0.34305, 5e-5);
    EXPECT_NEAR(s.ld, 10.5e-3, 0.01e-3);
    EXPECT_NEAR(s.lq, 12.9e-3, 0.01e-3);
    EXPECT_NEAR(s.psi_pm, mp.psi_pm, 5e-5);  // the preset's linear data agree with its fit
    EXPECT_NEAR(s.ld, mp.ld, 0.01e-3);
    EXPECT_NEAR(s.lq, mp.lq, 0.01e-3);

    Range ldd, lqq;
    inductance_ranges(*m, 13.3, ldd, lqq);
    std::printf("sun2016 |i| <= 13.3 A, i_d <= 0, i_q >= 0: l_dd %.3f-%.3f mH, l_qq %.3f-%.3f mH\n", 1e3 * ldd.lo,
                1e3 * ldd.hi, 1e3 * lqq.lo, 1e3 * lqq.hi);
    // Calibrated a_dq, a_qq, a_q0 (mctools fit-adq, presets/fits/sun2016-adq-fit.json;
    // docs/machine-models.md); machines.md's original fit gave 9.96-11.18, 8.38-16.2 mH.
    EXPECT_NEAR(ldd.lo, 10.14e-3, 0.01e-3);
    EXPECT_NEAR(ldd.hi, 11.18e-3, 0.01e-3);
    EXPECT_NEAR(lqq.lo, 10.91e-3, 0.01e-3);
    EXPECT_NEAR(lqq.hi, 13.99e-3, 0.05e-3);

    const Mtpa t = mtpa(*m, mp.pole_pairs, 13.29);
    std::printf("sun2016 MTPA at 13.29 A: %.3f N m at i = (%.2f, %.2f) A\n", t.torque, t.i.x(), t.i.y());
    EXPECT_NEAR(t.torque, 33.46, 0.05);  // machines.md's original fit: 32.5 N m
}

TEST(Presets, Brodatzki35kwReproducesFit) {
    const MachineParams mp = load_machine_preset("brodatzki-35kw");
    EXPECT_EQ(mp.pole_pairs, 4);
    EXPECT_DOUBLE_EQ(mp.i_rated_peak, 160.0);
    EXPECT_DOUBLE_EQ(mp.f_sample, 8000.0);
    const auto m = make_preset_model(mp);
    const SmallSignal s = small_signal(*m);
    std::printf("brodatzki fit at i = 0: psi_f = %.5f Wb, Ld = %.4f mH, Lq = %.4f mH\n", s.psi_pm, 1e3 * s.ld,
                1e3 * s.lq);
    EXPECT_NEAR(s.psi_pm, 0.0767, 5e-5);
    EXPECT_NEAR(s.psi_pm, mp.psi_pm, 5e-6);
    EXPECT_NEAR(s.ld, mp.ld, 0.1e-6);
    EXPECT_NEAR(s.lq, mp.lq, 0.1e-6);

    Range ldd, lqq;
    inductance_ranges(*m, 160.0, ldd, lqq);
    std::printf("brodatzki |i| <= 160 A, i_d <= 0, i_q >= 0: l_dd %.4f-%.4f mH, l_qq %.4f-%.4f mH\n",
                1e3 * ldd.lo, 1e3 * ldd.hi, 1e3 * lqq.lo, 1e3 * lqq.hi);
    EXPECT_NEAR(ldd.lo, 0.120e-3, 0.001e-3);
    EXPECT_NEAR(ldd.hi, 0.210e-3, 0.001e-3);
    EXPECT_NEAR(lqq.lo, 0.180e-3, 0.001e-3);
    EXPECT_NEAR(lqq.hi, 0.550e-3, 0.001e-3);

    const Mtpa t = mtpa(*m, mp.pole_pairs, std::hypot(55.0, 150.0));
    std::printf("brodatzki MTPA at %.1f A: %.3f N m at i = (%.2f, %.2f) A\n", std::hypot(55.0, 150.0), t.torque,
                t.i.x(), t.i.y());
    EXPECT_NEAR(t.torque, 79.3, 0.1);
    EXPECT_NEAR(t.i.x(), -55.0, 1.0);
    EXPECT_NEAR(t.i.y(), 150.0, 1.0);
}

TEST(Presets, LookupByNameAndByPath) {
    const MachineParams a = load_machine_preset("brodatzki-35kw");
    const MachineParams b = load_machine_preset(std::string(MCSIM_PRESET_DIR) + "/brodatzki-35kw.toml");
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.sat.a_dq, b.sat.a_dq);
    const std::string e = load_error("no-such-machine");
    EXPECT_NE(e.find("no-such-machine"), std::string::npos) << e;
    EXPECT_NE(e.find("not found"), std::string::npos) << e;
}

TEST(Presets, LoaderErrorsNameFileKeyValueAndExpectation) {
    struct Bad {
        std::string key, line;
        std::vector<std::string> must_contain;
    };
    const std::vector<Bad> cases = {
        {"ld_h", "ld_h = \"ten\"", {"'ld_h'", "ten", "string", "expected a number"}},
        {"ld_h", "ld_h = -1.0e-3", {"'ld_h'", "-0.001", ">= 1e-07 and <= 10 H"}},
        {"ld_h", "ld_h = 1e300", {"'ld_h'", "1e+300", "out of range", ">= 1e-07 and <= 10 H"}},
        {"lq_h", "lq_h = nan", {"'lq_h'", "nan", "out of range"}},
        {"inertia_kgm2", "inertia_kgm2 = inf", {"'inertia_kgm2'", "inf", "out of range"}},
        {"i_f", "i_f = -1e300", {"'saturation.i_f'", "out of range", ">= -100000 and <= 100000 A"}},
        {"pole_pairs", "pole_pairs = 2.5", {"'pole_pairs'", "2.5", "expected an integer"}},
        {"pole_pairs", "pole_pairs = 0", {"'pole_pairs'", "0", "[1, 100]"}},
        {"a_dq", "", {"'saturation.a_dq'", "missing"}},
        {"a_dd", "a_dd = -24.52", {"'saturation.a_dd'", "-24.52", ">= 0"}},
        {"name", "", {"'name'", "missing"}},
        {"rs_ohm", "rs_ohm = 0.4 0.5", {"TOML syntax error"}},
    };
    for (const Bad& c : cases) {
        const std::string path = write_variant(c.key, c.line);
        const std::string e = load_error(path);
        EXPECT_NE(e.find(path), std::string::npos) << "file not named: " << e;
        for (const std::string& s : c.must_contain) EXPECT_NE(e.find(s), std::string::npos) << "'" << s << "' not in: " << e;
        std::printf("  %s\n", e.c_str());
    }
}
