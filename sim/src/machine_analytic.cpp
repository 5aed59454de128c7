// Energy-consistent analytic saturation model (machines.md "Analytic saturation model";
// self- and cross-saturation terms of Hinkkanen et al., IEEE TIA 2017):
//   i_d = G_d psi_d - i_f,  i_q = G_q psi_q
//   G_d = a_d0 + a_dd |psi_d|^S + a_dq/(V+2) |psi_d|^U |psi_q|^(V+2)
//   G_q = a_q0 + a_qq |psi_q|^T + a_dq/(U+2) |psi_d|^(U+2) |psi_q|^V
// Both currents are the gradient of one scalar (the energy below) so the Jacobian is symmetric.
#include "mcsim/machine.hpp"

#include "analytic_eval.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace mcsim {
namespace {

// |x|^e with the convention 0^0 = 1 (std::pow already does that; spelled out because V = 0 and
// U = 0 rely on it).
double apow(double x, double e)
{
    // The fitted exponents are small integers; repeated multiplication is exact and ~20x cheaper
    // than std::pow, which dominated the closed-loop simulation time.
    const double a = std::abs(x);
    if (e >= 0.0 && e <= 8.0 && e == std::floor(e)) {
        double r = 1.0;
        for (int k = static_cast<int>(e); k > 0; --k) r *= a;
        return r;
    }
    return std::pow(a, e);
}

class AnalyticModel final : public FluxModel {
public:
    explicit AnalyticModel(const SaturationParams& p) : p_(p) {
        auto fail = [](const std::string& what) {
            throw std::invalid_argument("make_analytic_model: " + what);
        };
        if (!(p.a_d0 > 0) || !(p.a_q0 > 0)) fail("a_d0 and a_q0 must be > 0 (1/H)");
        if (p.a_dd < 0 || p.a_qq < 0 || p.a_dq < 0) fail("a_dd, a_qq, a_dq must be >= 0");
        if (p.S < 0 || p.T < 0 || p.U < 0 || p.V < 0) fail("exponents S, T, U, V must be >= 0");
        if (!std::isfinite(p.i_f)) fail("i_f must be finite");
        auto as_int = [](double e, int& out) {
            out = static_cast<int>(e);
            return e == std::floor(e) && e <= 8.0;
        };
        int_exp_ = as_int(p.S, is_) && as_int(p.T, it_) && as_int(p.U, iu_) && as_int(p.V, iv_);
        cd_ = p.a_dq / (p.V + 2);
        cq_ = p.a_dq / (p.U + 2);
        ev_.a_d0 = p.a_d0;
        ev_.a_dd = p.a_dd;
        ev_.a_q0 = p.a_q0;
        ev_.a_qq = p.a_qq;
        ev_.a_dq = p.a_dq;
        ev_.i_f = p.i_f;
        ev_.cd = cd_;
        ev_.cq = cq_;
        ev_.s1 = p.S + 1;
        ev_.t1 = p.T + 1;
        ev_.u1 = p.U + 1;
        ev_.v1 = p.V + 1;
        ev_.s = is_;
        ev_.t = it_;
        ev_.u = iu_;
        ev_.v = iv_;
        psi0_ = Vec2(solve_psi_d0(), 0.0);
        w0_ = raw_energy(psi0_);
        l0_ = di_dpsi(psi0_).inverse();
    }

    Vec2 current(const Vec2& psi) const override {
        const double d = psi.x(), q = psi.y();
        if (int_exp_) {
            // The plant calls this ~30 times per PWM period: integer powers by multiplication,
            // coefficients precomputed. Same expression as the general branch below.
            const double ad = std::abs(d), aq = std::abs(q);
            const double du = ipow(ad, iu_), qv = ipow(aq, iv_);
            const double gd = p_.a_d0 + p_.a_dd * ipow(ad, is_) + cd_ * du * qv * aq * aq;
            const double gq = p_.a_q0 + p_.a_qq * ipow(aq, it_) + cq_ * du * ad * ad * qv;
            return {gd * d - p_.i_f, gq * q};
        }
        const double gd = p_.a_d0 + p_.a_dd * apow(d, p_.S) + p_.a_dq / (p_.V + 2) * apow(d, p_.U) * apow(q, p_.V + 2);
        const double gq = p_.a_q0 + p_.a_qq * apow(q, p_.T) + p_.a_dq / (p_.U + 2) * apow(d, p_.U + 2) * apow(q, p_.V);
        return {gd * d - p_.i_f, gq * q};
    }

    // Hessian of W: d/dpsi_d (G_d psi_d) = G_d + psi_d dG_d/dpsi_d, with d|x|^e/dx = e |x|^e / x,
    // so the powers combine to (e+1)-fold coefficients; the off-diagonal term
    // a_dq |psi_d|^U psi_d |psi_q|^V psi_q is the same from either side (reciprocity).
    Mat2 di_dpsi(const Vec2& psi) const override {
        const double d = psi.x(), q = psi.y();
        const double ad_u = apow(d, p_.U), aq_v = apow(q, p_.V);
        const double jdd = p_.a_d0 + (p_.S + 1) * p_.a_dd * apow(d, p_.S) +
                           (p_.U + 1) * p_.a_dq / (p_.V + 2) * ad_u * apow(q, p_.V + 2);
        const double jqq = p_.a_q0 + (p_.T + 1) * p_.a_qq * apow(q, p_.T) +
                           (p_.V + 1) * p_.a_dq / (p_.U + 2) * apow(d, p_.U + 2) * aq_v;
        const double jdq = p_.a_dq * ad_u * d * aq_v * q;
        Mat2 j;
        j << jdd, jdq, jdq, jqq;
        return j;
    }

    void current_jacobian(const Vec2& psi, Vec2* i, Mat2* g) const override {
        if (!int_exp_) {
            FluxModel::current_jacobian(psi, i, g);
            return;
        }
        double id, iq, gdd, gdq, gqq;
        ev_(psi.x(), psi.y(), &id, &iq, &gdd, &gdq, &gqq);
        *i = Vec2(id, iq);
        *g << gdd, gdq, gdq, gqq;
    }
    const detail::AnalyticEval* analytic_eval() const override { return int_exp_ ? &ev_ : nullptr; }
    bool current_taylor(const Vec2& psi, Vec2* i, Mat2* g, double k[4]) const override {
        if (!int_exp_) return false;
        current_jacobian(psi, i, g);
        ev_.third(psi.x(), psi.y(), k);
        return true;
    }

    // W(psi) - W(psi0), with W the closed-form antiderivative (raw_energy); dW/dpsi = i exactly.
    double energy(const Vec2& psi) const override { return raw_energy(psi) - w0_; }
    std::string kind() const override { return "analytic"; }

protected:
    // Small-signal linearisation around the no-current state; exact for the linear special case.
    Vec2 flux_initial_guess(const Vec2& i) const override { return psi0_ + l0_ * i; }

private:
    //   W = a_d0/2 psi_d^2 + a_dd/(S+2) |psi_d|^(S+2) + a_q0/2 psi_q^2 + a_qq/(T+2) |psi_q|^(T+2)
    //     + a_dq/((U+2)(V+2)) |psi_d|^(U+2) |psi_q|^(V+2) - i_f psi_d
    double raw_energy(const Vec2& psi) const {
        const double d = psi.x(), q = psi.y();
        return 0.5 * p_.a_d0 * d * d + p_.a_dd / (p_.S + 2) * apow(d, p_.S + 2) + 0.5 * p_.a_q0 * q * q +
               p_.a_qq / (p_.T + 2) * apow(q, p_.T + 2) +
               p_.a_dq / ((p_.U + 2) * (p_.V + 2)) * apow(d, p_.U + 2) * apow(q, p_.V + 2) - p_.i_f * d;
    }

    // psi_d at i = 0, psi_q = 0: (a_d0 + a_dd |x|^S) x = i_f. The left side is odd, increasing and
    // convex for x > 0, so Newton from x = i_f/a_d0 (which overshoots the root) decreases
    // monotonically onto it.
    double solve_psi_d0() const {
        double x = p_.i_f / p_.a_d0;
        for (int k = 0; k < 200; ++k) {
            const double f = (p_.a_d0 + p_.a_dd * apow(x, p_.S)) * x - p_.i_f;
            const double df = p_.a_d0 + (p_.S + 1) * p_.a_dd * apow(x, p_.S);
            const double dx = f / df;
            x -= dx;
            if (std::abs(dx) <= 1e-15 * std::abs(x)) break;
        }
        return x;
    }

    static double ipow(double a, int n) { return detail::AnalyticEval::ipow(a, n); }

    SaturationParams p_;
    detail::AnalyticEval ev_;
    bool int_exp_ = false;
    int is_ = 0, it_ = 0, iu_ = 0, iv_ = 0;
    double cd_ = 0, cq_ = 0;
    Vec2 psi0_;
    double w0_ = 0;
    Mat2 l0_;
};

}  // namespace

std::unique_ptr<FluxModel> make_analytic_model(const SaturationParams& p) {
    return std::make_unique<AnalyticModel>(p);
}

}  // namespace mcsim
