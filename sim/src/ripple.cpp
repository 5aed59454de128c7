// Period-level integration of the switching inverter through ripple moments: see ripple.hpp and
// docs/plant.md "Ripple moments".
#include "ripple.hpp"

#include <cmath>

namespace mcsim::detail {

namespace {

// The period's constant-voltage intervals: boundaries tb[0] = 0 < ... < tb[n] = Ts (from the
// period start), voltage u_k on [tb_k, tb_k+1], W_k = int_0^tb_k u dt.
struct Intervals {
    static constexpr int kMax = 16;  // 12 edges at most (6 commanded, 6 after a dead time)
    double tb[kMax + 1], ux[kMax], uy[kMax], wx[kMax + 1], wy[kMax + 1];
    int n = 0;

    void push(double t1, double vx, double vy) {
        const double len = t1 - tb[n];
        ux[n] = vx;
        uy[n] = vy;
        wx[n + 1] = wx[n] + vx * len;
        wy[n + 1] = wy[n] + vy * len;
        tb[++n] = t1;
    }
    // W(t) for t in [0, tb[n]]
    void w_at(double t, double* x, double* y) const {
        int k = 0;
        while (k + 1 < n && tb[k + 1] <= t) ++k;
        *x = wx[k] + ux[k] * (t - tb[k]);
        *y = wy[k] + uy[k] * (t - tb[k]);
    }
};

// Moments of r(t) = W(t) - W(A) - u_mean (t - A) over [A, B], t counted from A. r is linear on
// each piece, so every integral is exact: the trapezoid and its first and second moments.
RippleMoments moments(const Intervals& iv, double A, double B, double* umx, double* umy) {
    double wax, way, wbx, wby;
    iv.w_at(A, &wax, &way);
    iv.w_at(B, &wbx, &wby);
    const double h = B - A;
    const double mx = (wbx - wax) / h, my = (wby - way) / h;
    *umx = mx;
    *umy = my;
    RippleMoments m{0, 0, 0, 0, 0, 0, 0};
    double s0 = 0.0, r0x = 0.0, r0y = 0.0;
    for (int k = 0; k < iv.n; ++k) {
        const double x1 = iv.tb[k + 1];
        if (x1 <= A) continue;
        const double s1 = (x1 < B ? x1 : B) - A;
        const double len = s1 - s0;
        // r moves at u_k - u_mean over the piece
        const double r1x = r0x + (iv.ux[k] - mx) * len, r1y = r0y + (iv.uy[k] - my) * len;
        m.m0x += 0.5 * len * (r0x + r1x);
        m.m0y += 0.5 * len * (r0y + r1y);
        const double l6 = len * (1.0 / 6.0);
        m.m1x += l6 * (s0 * (2.0 * r0x + r1x) + s1 * (r0x + 2.0 * r1x));
        m.m1y += l6 * (s0 * (2.0 * r0y + r1y) + s1 * (r0y + 2.0 * r1y));
        const double l3 = len * (1.0 / 3.0);
        m.sxx += l3 * (r0x * r0x + r0x * r1x + r1x * r1x);
        m.syy += l3 * (r0y * r0y + r0y * r1y + r1y * r1y);
        m.sxy += l3 * (r0x * r0y + 0.5 * (r0x * r1y + r1x * r0y) + r1x * r1y);
        s0 = s1;
        r0x = r1x;
        r0y = r1y;
        if (x1 >= B) break;
    }
    return m;
}

}  // namespace

bool ripple_period(HermiteStepper& hs, PwmSequencer& seq, const InverterConfig& inv, double rs, double p,
                   double t0, double Ts, const std::array<double, 3>& duty, int steps, double margin,
                   RipplePeriodOut* out) {
    const HPoint a = hs.point();
    // Currents predicted for the decisions, first order from the start:
    //   i(t) ~ i_a + G_a (W(t) - Rs i_a t) + t w_e (J i_a - G_a J psi_a).
    const double we = p * a.w;
    const double rotx = we * (-a.iy - (a.gxy * a.px - a.gxx * a.py));
    const double roty = we * (a.ix - (a.gyy * a.px - a.gxy * a.py));
    const double half = 0.5 * inv.vdc;
    const std::array<double, 3> none{{0.0, 0.0, 0.0}};

    Intervals iv;
    iv.tb[0] = iv.wx[0] = iv.wy[0] = 0.0;
    out->v_int = {0.0, 0.0, 0.0};
    double te;
    seq.begin(t0, Ts, duty, inv);
    auto push = [&](double t1) {
        const double len = t1 - iv.tb[iv.n];
        if (!(len > 0.0)) return;
        const auto& lv = seq.levels();
        const Vec2 u = clarke_phase_voltages({lv[0] * half, lv[1] * half, lv[2] * half});
        for (int k = 0; k < 3; ++k) out->v_int[k] += lv[k] * half * len;
        iv.push(t1, u.x(), u.y());
    };
    while (seq.next_time(&te)) {
        const double tau = te - t0;
        push(tau);
        if (seq.all_decided()) {
            seq.apply(te, none);
            continue;
        }
        const double dx = iv.wx[iv.n] - rs * a.ix * tau;  // W(tau): tau is the last boundary
        const double dy = iv.wy[iv.n] - rs * a.iy * tau;
        const double ix = a.ix + a.gxx * dx + a.gxy * dy + tau * rotx;
        const double iy = a.iy + a.gxy * dx + a.gyy * dy + tau * roty;
        seq.apply(te, inverse_clarke(Vec2(ix, iy)));
    }
    push(Ts);
    out->ux_int = iv.wx[iv.n];
    out->uy_int = iv.wy[iv.n];

    const bool check = inv.t_dead > 0.0;
    int next_dec = 0;
    const double hstep = Ts / steps;
    for (int j = 0; j < steps; ++j) {
        const double A = j * hstep, B = j + 1 == steps ? Ts : (j + 1) * hstep;
        double umx, umy;
        const RippleMoments m = moments(iv, A, B, &umx, &umy);
        hs.interval(A, B, umx, umy, &m);
        if (!check) continue;
        // The decisions made inside this step, against the step's own reconstruction.
        const StepEnds& e = hs.ends();
        double wax, way;
        iv.w_at(A, &wax, &way);
        for (; next_dec < seq.decision_count(); ++next_dec) {
            const PwmSequencer::Decision& d = seq.decision(next_dec);
            const double tau = d.t - t0;
            if (tau >= B && j + 1 < steps) break;
            double wx, wy, ix, iy;
            iv.w_at(tau, &wx, &wy);
            e.current_at(tau - A, wx - wax - umx * (tau - A), wy - way - umy * (tau - A), &ix, &iy);
            const double post = inverse_clarke(Vec2(ix, iy))[d.phase] - d.threshold, pred = d.i - d.threshold;
            if (post * pred <= 0.0 || std::fabs(post) < margin) return false;
        }
    }
    return true;
}

}  // namespace mcsim::detail
