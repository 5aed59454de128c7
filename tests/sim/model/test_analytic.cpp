// Analytic saturation model (machines.md): gradient structure, Jacobian, energy, Newton inverse,
// saturation features, linear special case.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mcsim/machine.hpp"
#include "analytic_eval.hpp"

using namespace mcsim;

namespace {

SaturationParams sun2016() {
    SaturationParams p;
    p.S = 2, p.T = 2, p.U = 1, p.V = 0;
    p.a_d0 = 86.58, p.a_dd = 24.52, p.a_q0 = 58.12, p.a_qq = 774.0, p.a_dq = 1441.3, p.i_f = 30.69;
    return p;
}
SaturationParams brodatzki() {
    SaturationParams p;
    p.S = 2, p.T = 2, p.U = 1, p.V = 1;
    p.a_d0 = 1764.4, p.a_dd = 3.726e5, p.a_q0 = 1819.4, p.a_qq = 4.582e5, p.a_dq = 2.476, p.i_f = 303.1;
    return p;
}
// Non-integer exponents exercise the |x|^e branches that integer fits hide.
SaturationParams odd_exponents() {
    SaturationParams p = sun2016();
    p.S = 1.7, p.T = 2.6, p.U = 0.5, p.V = 0.8;
    return p;
}

Mat2 fd_jacobian(const FluxModel& m, const Vec2& psi, double h) {
    Mat2 j;
    for (int c = 0; c < 2; ++c) {
        Vec2 e = Vec2::Zero();
        e(c) = h;
        j.col(c) = (m.current(psi + e) - m.current(psi - e)) / (2 * h);
    }
    return j;
}

// psi samples around the operating region: psi0 + L0 * i for i up to 2x the rated peak, so both
// signs of psi_q and strong saturation are covered.
std::vector<Vec2> sample_flux(const FluxModel& m, double i_max, int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-2 * i_max, 2 * i_max);
    std::vector<Vec2> out;
    for (int k = 0; k < n; ++k) out.push_back(m.flux(Vec2(u(rng), u(rng))));
    return out;
}

struct Case {
    const char* name;
    SaturationParams p;
    double i_max;
};
const Case kCases[] = {{"sun2016", sun2016(), 13.29}, {"brodatzki", brodatzki(), 160.0},
                       {"odd_exponents", odd_exponents(), 13.29}};

}  // namespace

TEST(AnalyticModel, ReciprocityAndJacobianMatchFiniteDifferences) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.name);
        const auto m = make_analytic_model(c.p);
        double worst = 0;
        for (const Vec2& psi : sample_flux(*m, c.i_max, 200, 1)) {
            const Mat2 j = m->di_dpsi(psi);
            EXPECT_EQ(j(0, 1), j(1, 0));  // symmetric by construction, bit for bit
            const Mat2 fd = fd_jacobian(*m, psi, 1e-6 * std::max(psi.norm(), 1e-3));
            const double err = (fd - j).norm() / j.norm();
            worst = std::max(worst, err);
            // FD reciprocity, independent of the analytic Jacobian.
            EXPECT_NEAR(fd(0, 1), fd(1, 0), 1e-6 * j.norm());
        }
        std::printf("[%s] max relative |J_fd - J| / |J| = %.2e\n", c.name, worst);
        EXPECT_LT(worst, 1e-7);
    }
}

// The third derivatives the plant's ripple integrator uses (d/dpsi of the Jacobian) against
// central differences of the analytic Jacobian, for the integer-exponent presets (the only
// models that offer the inlined evaluator).
TEST(AnalyticModel, ThirdDerivativesMatchFiniteDifferences) {
    for (const Case& c : kCases) {
        const auto m = make_analytic_model(c.p);
        const detail::AnalyticEval* ev = m->analytic_eval();
        if (c.p.S != std::floor(c.p.S)) {
            EXPECT_EQ(ev, nullptr) << c.name;
            continue;
        }
        SCOPED_TRACE(c.name);
        ASSERT_NE(ev, nullptr);
        double worst = 0;
        for (const Vec2& psi : sample_flux(*m, c.i_max, 200, 2)) {
            double k[4];
            ev->third(psi.x(), psi.y(), k);
            const double h = 1e-6 * std::max(psi.norm(), 1e-3);
            const Mat2 dd = (m->di_dpsi(psi + Vec2(h, 0)) - m->di_dpsi(psi - Vec2(h, 0))) / (2 * h);
            const Mat2 dq = (m->di_dpsi(psi + Vec2(0, h)) - m->di_dpsi(psi - Vec2(0, h))) / (2 * h);
            // symmetric tensor: d gdq/dd = d gdd/dq and d gqq/dd = d gdq/dq
            const double fd[4] = {dd(0, 0), 0.5 * (dd(0, 1) + dq(0, 0)), 0.5 * (dq(0, 1) + dd(1, 1)), dq(1, 1)};
            const double scale = std::fabs(k[0]) + std::fabs(k[1]) + std::fabs(k[2]) + std::fabs(k[3]);
            for (int n = 0; n < 4; ++n) worst = std::max(worst, std::fabs(fd[n] - k[n]) / scale);
        }
        std::printf("[%s] max relative third-derivative error vs finite differences = %.2e\n", c.name, worst);
        EXPECT_LT(worst, 1e-6);
    }
}

TEST(AnalyticModel, EnergyGradientIsCurrent) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.name);
        const auto m = make_analytic_model(c.p);
        EXPECT_NEAR(m->energy(m->flux(Vec2::Zero())), 0.0, 1e-15);
        for (const Vec2& psi : sample_flux(*m, c.i_max, 100, 2)) {
            const double h = 1e-6 * psi.norm();
            const Vec2 g((m->energy(psi + Vec2(h, 0)) - m->energy(psi - Vec2(h, 0))) / (2 * h),
                         (m->energy(psi + Vec2(0, h)) - m->energy(psi - Vec2(0, h))) / (2 * h));
            const Vec2 i = m->current(psi);
            EXPECT_LT((g - i).norm(), 1e-6 * std::max(i.norm(), c.i_max)) << "psi = " << psi.transpose();
        }
        // Path independence: integrate i . dpsi along an L-shaped path (Simpson, fine) and compare.
        const Vec2 psi0 = m->flux(Vec2::Zero());
        const Vec2 psi1 = m->flux(Vec2(-0.8 * c.i_max, 1.1 * c.i_max));
        auto line = [&](const Vec2& a, const Vec2& b) {
            const int n = 2000;
            double w = 0;
            for (int k = 0; k <= n; ++k) {
                const double wt = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
                w += wt * m->current(a + (b - a) * (double(k) / n)).dot(b - a);
            }
            return w / (3.0 * n);
        };
        const Vec2 corner(psi1.x(), psi0.y());
        const double w_path = line(psi0, corner) + line(corner, psi1);
        EXPECT_NEAR(w_path, m->energy(psi1), 1e-9 * std::abs(m->energy(psi1)));
    }
}

TEST(AnalyticModel, FluxNewtonConvergesToRelative1e12) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.name);
        const auto m = make_analytic_model(c.p);
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> u(-3 * c.i_max, 3 * c.i_max);
        for (int k = 0; k < 300; ++k) {
            const Vec2 i(u(rng), u(rng));
            const Vec2 psi = m->flux(i);
            // One more exact Newton step must not move psi by more than 1e-12 relative.
            const Vec2 dpsi = m->di_dpsi(psi).inverse() * (i - m->current(psi));
            EXPECT_LE(dpsi.norm(), 1e-12 * psi.norm()) << "i = " << i.transpose();
        }
    }
}

TEST(AnalyticModel, DAxisSaturationIsAsymmetricInId) {
    const auto m = make_analytic_model(sun2016());
    for (double id : {5.0, 10.0, 13.3}) {
        const double l_pos = m->l_diff(Vec2(id, 0))(0, 0), l_neg = m->l_diff(Vec2(-id, 0))(0, 0);
        std::printf("sun2016 l_dd(+%.1f A) = %.3f mH, l_dd(-%.1f A) = %.3f mH\n", id, 1e3 * l_pos, id, 1e3 * l_neg);
        // Magnetising current saturates further (smaller l_dd) than demagnetising current.
        EXPECT_LT(l_pos, l_neg - 0.01 * l_neg);
    }
}

TEST(AnalyticModel, CrossSaturationLowersPsiDWithIq) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.name);
        const auto m = make_analytic_model(c.p);
        for (double id : {-0.5 * c.i_max, 0.0, 0.5 * c.i_max}) {
            double prev = m->flux(Vec2(id, 0)).x();
            for (int k = 1; k <= 10; ++k) {
                const double psi_d = m->flux(Vec2(id, 0.15 * k * c.i_max)).x();
                EXPECT_LT(psi_d, prev) << "id = " << id << ", iq step " << k;
                prev = psi_d;
            }
        }
    }
}

TEST(AnalyticModel, LinearIsTheSpecialCaseWithoutSaturation) {
    const double ld = 10.5e-3, lq = 12.9e-3, psi_pm = 0.34305;
    const auto lin = make_linear_model(ld, lq, psi_pm);
    const SaturationParams p = linear_saturation_params(ld, lq, psi_pm);
    EXPECT_DOUBLE_EQ(p.a_d0, 1 / ld);
    EXPECT_DOUBLE_EQ(p.a_q0, 1 / lq);
    EXPECT_EQ(p.a_dd, 0.0);
    EXPECT_EQ(p.a_qq, 0.0);
    EXPECT_EQ(p.a_dq, 0.0);
    const auto an = make_analytic_model(p);
    const SmallSignal s = small_signal(*an);
    EXPECT_NEAR(s.psi_pm, psi_pm, 1e-15);
    EXPECT_NEAR(s.ld, ld, 1e-15);
    EXPECT_NEAR(s.lq, lq, 1e-15);
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-30, 30);
    for (int k = 0; k < 50; ++k) {
        const Vec2 i(u(rng), u(rng));
        const Vec2 psi = lin->flux(i);
        EXPECT_NEAR((psi - Vec2(ld * i.x() + psi_pm, lq * i.y())).norm(), 0, 1e-15);
        EXPECT_NEAR((an->flux(i) - psi).norm(), 0, 1e-13);
        EXPECT_NEAR((an->current(psi) - lin->current(psi)).norm(), 0, 1e-11);
        EXPECT_NEAR((an->di_dpsi(psi) - lin->di_dpsi(psi)).norm(), 0, 1e-12);
        EXPECT_NEAR(an->energy(psi), lin->energy(psi), 1e-12 * (1 + lin->energy(psi)));
        EXPECT_NEAR((lin->l_diff(i) - Vec2(ld, lq).asDiagonal().toDenseMatrix()).norm(), 0, 1e-15);
    }
    EXPECT_EQ(lin->kind(), "linear");
    EXPECT_EQ(an->kind(), "analytic");
}

TEST(AnalyticModel, RejectsInvalidParameters) {
    SaturationParams p = sun2016();
    p.a_d0 = 0;
    EXPECT_THROW(make_analytic_model(p), std::invalid_argument);
    p = sun2016();
    p.a_dq = -1;
    EXPECT_THROW(make_analytic_model(p), std::invalid_argument);
    EXPECT_THROW(make_linear_model(0, 1e-3, 0.1), std::invalid_argument);
}
