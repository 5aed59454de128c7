// Two-point Hermite integration of the enabled plant: see hermite.hpp and docs/plant.md.
// Scalar code on purpose: this runs ~7 times per simulated PWM period and 2-vectors gain nothing
// from SIMD shuffles.
#include "hermite.hpp"

#include "mcsim/inverter.hpp"
#include "rotation.hpp"

namespace mcsim::detail {

namespace {
// o->g = R G R^T for the symmetric rotor-frame G, through the double angle of (o->c, o->s).
void set_jacobian(double gdd, double gdq, double gqq, HPoint* o) {
    const double c = o->c, s = o->s;
    const double c2 = c * c - s * s, s2 = 2.0 * c * s;
    const double sum = 0.5 * (gdd + gqq), dif = 0.5 * (gdd - gqq);
    o->gxx = sum + dif * c2 - gdq * s2;
    o->gyy = sum - dif * c2 + gdq * s2;
    o->gxy = dif * s2 + gdq * c2;
}
}  // namespace

void HermiteStepper::eval(double px, double py, HPoint* o) const {
    const double c = o->c, s = o->s;
    const double pd = c * px + s * py, pq = -s * px + c * py;
    double id, iq, gdd, gdq, gqq;
    if (fast_) {
        (*fast_)(pd, pq, &id, &iq, &gdd, &gdq, &gqq);
    } else {
        Vec2 i;
        Mat2 g;
        model_.current_jacobian(Vec2(pd, pq), &i, &g);
        id = i.x();
        iq = i.y();
        gdd = g(0, 0);
        gdq = g(0, 1);
        gqq = g(1, 1);
    }
    o->px = px;
    o->py = py;
    o->ix = c * id - s * iq;
    o->iy = s * id + c * iq;
    set_jacobian(gdd, gdq, gqq, o);
    o->te = 1.5 * p_ * (px * o->iy - py * o->ix);
}

void HermiteStepper::begin(const Vec2& psi_dq, const Vec2& i_dq, const Mat2& g_dq, double theta_m,
                           double omega_m, double c, double s, bool ledger) {
    a_.c = c;
    a_.s = s;
    a_.px = c * psi_dq.x() - s * psi_dq.y();
    a_.py = s * psi_dq.x() + c * psi_dq.y();
    a_.ix = c * i_dq.x() - s * i_dq.y();
    a_.iy = s * i_dq.x() + c * i_dq.y();
    set_jacobian(g_dq(0, 0), g_dq(0, 1), g_dq(1, 1), &a_);
    a_.th = theta_m;
    a_.w = omega_m;
    a_.te = 1.5 * p_ * (a_.px * a_.iy - a_.py * a_.ix);
    ledger_ = ledger;
    led_ = HLedger{};
}

Vec2 HermiteStepper::psi_dq() const {
    return Vec2(a_.c * a_.px + a_.s * a_.py, -a_.s * a_.px + a_.c * a_.py);
}

std::array<double, 3> HermiteStepper::phase_currents() const { return inverse_clarke(Vec2(a_.ix, a_.iy)); }

void HermiteStepper::interval(double tau0, double tau1, double ux, double uy) {
    const double h = tau1 - tau0;
    if (!(h > 0.0)) return;
    const HPoint& a = a_;
    const double kt = 1.5 * p_, h2 = h * h, h12 = h2 * (1.0 / 12.0), rs = rs_;

    // Derivatives at the start with this interval's voltage (J = [0 -1; 1 0]):
    //   psi' = u - Rs i,   i' = G (psi' - w_e J psi) + w_e J i,   T_e' = kt (psi' x i + psi x i').
    const double we_a = p_ * a.w;
    const double dpx_a = ux - rs * a.ix, dpy_a = uy - rs * a.iy;
    double vx = dpx_a + we_a * a.py, vy = dpy_a - we_a * a.px;
    const double dix_a = a.gxx * vx + a.gxy * vy - we_a * a.iy;
    const double diy_a = a.gxy * vx + a.gyy * vy + we_a * a.ix;
    const double dte_a = kt * (dpx_a * a.iy - dpy_a * a.ix + a.px * diy_a - a.py * dix_a);
    const double al_a = mech_.accel(tau0, a.te, a.w);
    const double jk_a = mech_.jerk(tau0, a.te, dte_a, a.w, al_a);

    // Predictor (Taylor with the start derivatives) and the one model evaluation.
    const double k2 = 0.5 * rs * h2;
    const double ppx = a.px + h * dpx_a - k2 * dix_a, ppy = a.py + h * dpy_a - k2 * diy_a;
    const double w_p = a.w + h * (al_a + 0.5 * h * jk_a);
    const double th_p = a.th + h * (a.w + h * (0.5 * al_a + h * (1.0 / 6.0) * jk_a));
    HPoint b;
    rotate_small(a.c, a.s, p_ * (th_p - a.th), &b.c, &b.s);
    eval(ppx, ppy, &b);
    const double we_p = p_ * w_p;
    const double dpx_p = ux - rs * b.ix, dpy_p = uy - rs * b.iy;
    vx = dpx_p + we_p * ppy;
    vy = dpy_p - we_p * ppx;
    const double dix_p = b.gxx * vx + b.gxy * vy - we_p * b.iy;
    const double diy_p = b.gxy * vx + b.gyy * vy + we_p * b.ix;
    const double dte_p = kt * (dpx_p * b.iy - dpy_p * b.ix + ppx * diy_p - ppy * dix_p);
    const double al_p = mech_.accel(tau1, b.te, w_p);
    const double jk_p = mech_.jerk(tau1, b.te, dte_p, w_p, al_p);

    // Corrector. Mechanics first, with the end-point derivatives taken at the prediction.
    b.w = a.w + 0.5 * h * (al_a + al_p) + h12 * (jk_a - jk_p);
    b.th = a.th + 0.5 * h * (a.w + b.w) + h12 * (al_a - al_p);
    const double dthe = p_ * (b.th - th_p);
    // d i_ab / d theta_e = J i - G J psi (the rotor turns under a fixed stator flux).
    const double dthx = -b.iy - (b.gxx * -ppy + b.gxy * ppx);
    const double dthy = b.ix - (b.gxy * -ppy + b.gyy * ppx);
    // psi_b = psi_a + u h - Rs [h/2 (i_a + i_b) + h^2/12 (i'_a - i'_b)] with
    // i_b = i_p + G dpsi + (di/dtheta_e) dthe, solved for dpsi: (I + Rs h/2 G) dpsi = r.
    const double hh = 0.5 * h;
    const double rx = a.px + h * ux - rs * (hh * (a.ix + b.ix + dthe * dthx) + h12 * (dix_a - dix_p)) - ppx;
    const double ry = a.py + h * uy - rs * (hh * (a.iy + b.iy + dthe * dthy) + h12 * (diy_a - diy_p)) - ppy;
    const double k = rs * hh;
    const double m00 = 1.0 + k * b.gxx, m01 = k * b.gxy, m11 = 1.0 + k * b.gyy;
    const double inv_det = 1.0 / (m00 * m11 - m01 * m01);
    const double dpx = (m11 * rx - m01 * ry) * inv_det, dpy = (m00 * ry - m01 * rx) * inv_det;
    b.px = ppx + dpx;
    b.py = ppy + dpy;
    b.ix += b.gxx * dpx + b.gxy * dpy + dthe * dthx;
    b.iy += b.gxy * dpx + b.gyy * dpy + dthe * dthy;
    b.te = kt * (b.px * b.iy - b.py * b.ix);
    // The mechanics once more with the corrected end torque: the acceleration enters omega at
    // first order, so the prediction's O(Rs h^3) torque error would otherwise cost an order.
    const double al_b = mech_.accel(tau1, b.te, b.w);
    const double w_b = a.w + 0.5 * h * (al_a + al_b) + h12 * (jk_a - jk_p);
    const double th_b = a.th + 0.5 * h * (a.w + w_b) + h12 * (al_a - al_b);
    const double dthe2 = p_ * (th_b - b.th);
    b.w = w_b;
    b.th = th_b;
    b.ix += dthe2 * dthx;
    b.iy += dthe2 * dthy;
    b.te = kt * (b.px * b.iy - b.py * b.ix);
    const double dth_all = dthe + dthe2;
    const double bc = b.c;
    b.c -= b.s * dth_all;  // first order is exact in double: |dth_all| is O(h^4)
    b.s += bc * dth_all;

    if (ledger_) {
        // Same rule throughout: the electrical input uses the very integral of i that moved psi.
        const double iix = hh * (a.ix + b.ix) + h12 * (dix_a - dix_p);
        const double iiy = hh * (a.iy + b.iy) + h12 * (diy_a - diy_p);
        led_.ein += 1.5 * (ux * iix + uy * iiy);
        led_.cu += 1.5 * rs *
                   (hh * (a.ix * a.ix + a.iy * a.iy + b.ix * b.ix + b.iy * b.iy) +
                    2.0 * h12 * (a.ix * dix_a + a.iy * diy_a - b.ix * dix_p - b.iy * diy_p));
        led_.mech += hh * (a.te * a.w + b.te * b.w) + h12 * (dte_a * a.w + a.te * al_a - dte_p * b.w - b.te * al_b);
        // u_dq = R(-theta_e) u_ab, d u_dq/dt = -w_e J u_dq.
        const double fax = a.c * ux + a.s * uy, fay = -a.s * ux + a.c * uy;
        const double fbx = b.c * ux + b.s * uy, fby = -b.s * ux + b.c * uy;
        const double we_b = p_ * b.w;
        led_.ud += hh * (fax + fbx) - h12 * (we_a * -fay - we_b * -fby);
        led_.uq += hh * (fay + fby) - h12 * (we_a * fax - we_b * fbx);
    }
    a_ = b;
}

}  // namespace mcsim::detail
