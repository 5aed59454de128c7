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

// Second order in r (the current's curvature, (1/2) H[r, r]) matters: with the thesis machine's
// cross-saturation it shifts the mean current by ~1e-4 A, which Rs turns into a drift.
HermiteStepper::RippleTerms HermiteStepper::ripple_terms(const RippleMoments& m, const HPoint& a, const HPoint& b,
                                                         double h) const {
    RippleTerms o;
    const double inv_h = 1.0 / h, kt = 1.5 * p_;
    const double n1x = m.m1x * inv_h, n1y = m.m1y * inv_h;
    // H[S]: the mean of both ends (r r^T is symmetric about the step's middle for a centred
    // pulse pattern, and H turns with the rotor by ~w_e h within the step).
    const double sum = 0.5 * (m.sxx + m.syy), dif = 0.5 * (m.sxx - m.syy);
    o.hx = o.hy = 0.0;
    for (const HPoint* pt : {&a, &b}) {
        // S to the rotor frame (double angle), the third derivatives there, the result back.
        const double c = pt->c, s = pt->s, c2 = c * c - s * s, s2 = 2.0 * c * s;
        const double sdd = sum + dif * c2 + m.sxy * s2, sqq = sum - dif * c2 - m.sxy * s2;
        const double sdq = m.sxy * c2 - dif * s2;
        double k[4];
        fast_->third(c * pt->px + s * pt->py, -s * pt->px + c * pt->py, k);
        const double hd = k[0] * sdd + 2.0 * k[1] * sdq + k[2] * sqq;
        const double hq = k[1] * sdd + 2.0 * k[2] * sdq + k[3] * sqq;
        o.hx += 0.5 * (c * hd - s * hq);
        o.hy += 0.5 * (s * hd + c * hq);
    }
    // int G r dt with G linear in t between the ends, plus (1/2) H[S].
    const double dgxx = b.gxx - a.gxx, dgxy = b.gxy - a.gxy, dgyy = b.gyy - a.gyy;
    o.ix = a.gxx * m.m0x + a.gxy * m.m0y + dgxx * n1x + dgxy * n1y + 0.5 * o.hx;
    o.iy = a.gxy * m.m0x + a.gyy * m.m0y + dgxy * n1x + dgyy * n1y + 0.5 * o.hy;
    // The ripple current's own Rs drop ripples the flux by eps(t) = -Rs G int_0^t r, which the
    // Hermite rule sees only through its end value: what it misses is
    //   int eps dt - h/2 eps(h) = Rs G (M1 - h/2 M0) = e,
    // in the current as G e and in the torque as c . e.
    const double vx = m.m1x - 0.5 * h * m.m0x, vy = m.m1y - 0.5 * h * m.m0y;
    const double ex = rs_ * (a.gxx * vx + a.gxy * vy), ey = rs_ * (a.gxy * vx + a.gyy * vy);
    o.ix += a.gxx * ex + a.gxy * ey;
    o.iy += a.gxy * ex + a.gyy * ey;
    // T_e = kt psi x i: first order c . r with c = G J psi - J i (linear in t), second order
    // r x G r (mean G) and psi x (1/2) H[r, r].
    const double cax = a.gxy * a.px - a.gxx * a.py + a.iy, cay = a.gyy * a.px - a.gxy * a.py - a.ix;
    const double cbx = b.gxy * b.px - b.gxx * b.py + b.iy, cby = b.gyy * b.px - b.gxy * b.py - b.ix;
    const double gxy = 0.5 * (a.gxy + b.gxy), gdiff = 0.5 * (b.gyy + a.gyy - b.gxx - a.gxx);
    const double second = gxy * (m.sxx - m.syy) + gdiff * m.sxy + 0.5 * (a.px * o.hy - a.py * o.hx);
    o.te1 = kt * (cax * (m.m0x + ex) + cay * (m.m0y + ey) + (cbx - cax) * n1x + (cby - cay) * n1y + second);
    // theta(h) = theta_0 + h omega_0 + int (h - t) alpha dt; the Hermite rule's h/2 (w_a + w_b)
    // already holds h/2 of the ripple's int alpha (through w_b), hence (h/2 - t). For a centred
    // pulse pattern r(h - t) = -r(t): int (h - t) r r^T dt = h/2 S and int (h - t) t r dt = 0;
    // both are kept at that.
    o.te2 = kt * (cax * (h * m.m0x - m.m1x) + cay * (h * m.m0y - m.m1y) + 0.5 * h * second) - 0.5 * h * o.te1;
    return o;
}

// The ledger's share of the ripple (docs/plant.md "Ripple moments"). With u = u_mean + r':
//   int u.i = u_mean . int i - int r . i' (r is 0 at both ends), i' = i_smooth' + (G r)',
//   int r . (G r)' = 1/2 int r G' r;  int |i|^2 = smooth + 2 int i.(G r + H[r,r]/2) + int |G r|^2;
//   int R(-theta) r' dt = w_e J int R(-theta) r dt.
void HermiteStepper::ripple_ledger(const RippleMoments& m, const HPoint& a, const HPoint& b, double h,
                                   const RippleTerms& rt, double dix_a, double diy_a, double dix_b,
                                   double diy_b, double ux, double uy) {
    const double inv_h = 1.0 / h;
    const double n1x = m.m1x * inv_h, n1y = m.m1y * inv_h;
    const double dgxx = b.gxx - a.gxx, dgxy = b.gxy - a.gxy, dgyy = b.gyy - a.gyy;
    const double r_di = dix_a * m.m0x + diy_a * m.m0y + (dix_b - dix_a) * n1x + (diy_b - diy_a) * n1y +
                        0.5 * inv_h * (dgxx * m.sxx + 2.0 * dgxy * m.sxy + dgyy * m.syy);
    led_.ein += 1.5 * (ux * rt.ix + uy * rt.iy - r_di);
    const double gax = a.gxx * a.ix + a.gxy * a.iy, gay = a.gxy * a.ix + a.gyy * a.iy;
    const double gbx = b.gxx * b.ix + b.gxy * b.iy, gby = b.gxy * b.ix + b.gyy * b.iy;
    const double gxx = a.gxx, gxy = a.gxy, gyy = a.gyy;
    const double g2xx = gxx * gxx + gxy * gxy, g2xy = gxy * (gxx + gyy), g2yy = gxy * gxy + gyy * gyy;
    led_.cu += 1.5 * rs_ *
               (2.0 * (gax * m.m0x + gay * m.m0y + (gbx - gax) * n1x + (gby - gay) * n1y) +
                0.5 * ((a.ix + b.ix) * rt.hx + (a.iy + b.iy) * rt.hy) +
                g2xx * m.sxx + 2.0 * g2xy * m.sxy + g2yy * m.syy);
    led_.mech += 0.5 * (a.w + b.w) * rt.te1;
    // R(-theta) r at both ends of the linear interpolation, then w_e J of the integral.
    const double rax = a.c * m.m0x + a.s * m.m0y, ray = -a.s * m.m0x + a.c * m.m0y;
    const double qx = (b.c - a.c) * n1x + (b.s - a.s) * n1y, qy = -(b.s - a.s) * n1x + (b.c - a.c) * n1y;
    const double we = 0.5 * p_ * (a.w + b.w);
    led_.ud += -we * (ray + qy);
    led_.uq += we * (rax + qx);
}

void StepEnds::current_at(double t, double rx, double ry, double* ix, double* iy) const {
    const double x = t / h, x2 = x * x, x3 = x2 * x;
    const double h00 = 2 * x3 - 3 * x2 + 1, h10 = (x3 - 2 * x2 + x) * h, h01 = 3 * x2 - 2 * x3, h11 = (x3 - x2) * h;
    const double gxx = a.gxx + x * (b.gxx - a.gxx), gxy = a.gxy + x * (b.gxy - a.gxy), gyy = a.gyy + x * (b.gyy - a.gyy);
    *ix = h00 * a.ix + h10 * dix_a + h01 * b.ix + h11 * dix_b + gxx * rx + gxy * ry;
    *iy = h00 * a.iy + h10 * diy_a + h01 * b.iy + h11 * diy_b + gxy * rx + gyy * ry;
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

void HermiteStepper::interval(double tau0, double tau1, double ux, double uy, const RippleMoments* rp) {
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

    // Ripple step: what r adds to int i (cix, ciy) and, through the torque, to omega and theta.
    RippleTerms rt{0, 0, 0, 0, 0, 0};
    double gm = 0.0;
    if (rp) {
        rt = ripple_terms(*rp, a, b, h);
        gm = mech_.ripple_gain(tau0, a.te, a.w);
    }

    // Corrector. Mechanics first, with the end-point derivatives taken at the prediction.
    b.w = a.w + 0.5 * h * (al_a + al_p) + h12 * (jk_a - jk_p) + gm * rt.te1;
    b.th = a.th + 0.5 * h * (a.w + b.w) + h12 * (al_a - al_p) + gm * rt.te2;
    const double dthe = p_ * (b.th - th_p);
    // d i_ab / d theta_e = J i - G J psi (the rotor turns under a fixed stator flux).
    const double dthx = -b.iy - (b.gxx * -ppy + b.gxy * ppx);
    const double dthy = b.ix - (b.gxy * -ppy + b.gyy * ppx);
    // psi_b = psi_a + u h - Rs [h/2 (i_a + i_b) + h^2/12 (i'_a - i'_b)] with
    // i_b = i_p + G dpsi + (di/dtheta_e) dthe, solved for dpsi: (I + Rs h/2 G) dpsi = r.
    const double hh = 0.5 * h;
    const double rx = a.px + h * ux - rs * (hh * (a.ix + b.ix + dthe * dthx) + h12 * (dix_a - dix_p) + rt.ix) - ppx;
    const double ry = a.py + h * uy - rs * (hh * (a.iy + b.iy + dthe * dthy) + h12 * (diy_a - diy_p) + rt.iy) - ppy;
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
    const double w_b = a.w + 0.5 * h * (al_a + al_b) + h12 * (jk_a - jk_p) + gm * rt.te1;
    const double th_b = a.th + 0.5 * h * (a.w + w_b) + h12 * (al_a - al_b) + gm * rt.te2;
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
        if (rp) ripple_ledger(*rp, a, b, h, rt, dix_a, diy_a, dix_p, diy_p, ux, uy);
    }
    if (rp) ends_ = StepEnds{a, b, dix_a, diy_a, dix_p, diy_p, h};
    a_ = b;
}

}  // namespace mcsim::detail
