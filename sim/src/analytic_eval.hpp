// The analytic saturation model's current and Jacobian for integer exponents (internal to
// sim/src): one inline function shared by AnalyticModel and the plant's integrator, which calls it
// directly instead of through the FluxModel interface (~8 times per simulated PWM period).
//   i_d = G_d psi_d - i_f,  i_q = G_q psi_q   (machine.hpp; Jacobian = Hessian of the energy)
#pragma once
#include <cmath>

namespace mcsim::detail {

struct AnalyticEval {
    double a_d0 = 0, a_dd = 0, a_q0 = 0, a_qq = 0, a_dq = 0, i_f = 0;
    double cd = 0, cq = 0;            // a_dq/(V+2), a_dq/(U+2)
    double s1 = 1, t1 = 1, u1 = 1, v1 = 1;  // S+1, T+1, U+1, V+1
    int s = 0, t = 0, u = 0, v = 0;

    static double ipow(double a, int n) {
        switch (n) {  // the fitted exponents are 0..3: a predictable branch, no loop
            case 0: return 1.0;
            case 1: return a;
            case 2: return a * a;
            case 3: return a * a * a;
            default: {
                double r = 1.0;
                for (; n > 0; --n) r *= a;
                return r;
            }
        }
    }

    void operator()(double d, double q, double* id, double* iq, double* gdd, double* gdq, double* gqq) const {
        const double ad = std::fabs(d), aq = std::fabs(q);
        const double du = ipow(ad, u), qv = ipow(aq, v);
        const double ds = a_dd * ipow(ad, s), qt = a_qq * ipow(aq, t);
        const double xd = cd * du * qv * aq * aq, xq = cq * du * ad * ad * qv;
        *id = (a_d0 + ds + xd) * d - i_f;
        *iq = (a_q0 + qt + xq) * q;
        *gdd = a_d0 + s1 * ds + u1 * xd;
        *gqq = a_q0 + t1 * qt + v1 * xq;
        *gdq = a_dq * du * d * qv * q;
    }

    // Third derivatives of the energy (d/dpsi of the Jacobian above; a symmetric tensor, so four
    // numbers): k[0] = d gdd/dd, k[1] = d gdd/dq = d gdq/dd, k[2] = d gdq/dq = d gqq/dd,
    // k[3] = d gqq/dq. d|x|^n/dx = n |x|^(n-1) sgn(x), written without a division by x.
    void third(double d, double q, double k[4]) const {
        const double ad = std::fabs(d), aq = std::fabs(q);
        const double sd = d < 0.0 ? -1.0 : 1.0, sq = q < 0.0 ? -1.0 : 1.0;
        const double du = ipow(ad, u), qv = ipow(aq, v);
        // n |x|^(n-1) sgn(x) for the exponents in play (0 when n = 0)
        auto dpow = [](double a, double sg, int n) { return n == 0 ? 0.0 : n * ipow(a, n - 1) * sg; };
        const double ddu = dpow(ad, sd, u), dqv = dpow(aq, sq, v);
        k[0] = s1 * a_dd * dpow(ad, sd, s) + u1 * cd * ddu * qv * aq * aq;
        k[1] = a_dq * (ddu * d + du) * qv * q;
        k[2] = a_dq * du * d * (dqv * q + qv);
        k[3] = t1 * a_qq * dpow(aq, sq, t) + v1 * cq * du * ad * ad * dqv;
    }
};

}  // namespace mcsim::detail
