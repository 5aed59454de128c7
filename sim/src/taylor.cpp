// Period-level integration of the enabled plant: the smooth path plus the ripple's moments with a
// local expansion of the current map. See taylor.hpp and docs/plant.md "Taylor".
#include "taylor.hpp"

#include "mcsim/inverter.hpp"
#include "rotation.hpp"

namespace mcsim::detail {

namespace {
inline double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }
}  // namespace

// The expansion in the rotor frame at a frame-0 flux and (cos, sin) of delta:
// i_r = i0 + (G + 1/2 H[dx]) dx,  dx = R(-delta) psi - x0  (H[dx] dx = H[dx, dx]), and H[dx].
void TaylorStepper::rotor_current(double px, double py, double c, double s, double* ird, double* irq,
                                  double h[3]) const {
    const double xd = c * px + s * py - x0d_, xq = -s * px + c * py - x0q_;
    h[0] = k_[0] * xd + k_[1] * xq;
    h[1] = k_[1] * xd + k_[2] * xq;
    h[2] = k_[2] * xd + k_[3] * xq;
    *ird = i0d_ + (gdd_ + 0.5 * h[0]) * xd + (gdq_ + 0.5 * h[1]) * xq;
    *irq = i0q_ + (gdq_ + 0.5 * h[1]) * xd + (gqq_ + 0.5 * h[2]) * xq;
}

void TaylorStepper::current_at(double px, double py, double c, double s, double* ix, double* iy) const {
    double ird, irq, h[3];
    rotor_current(px, py, c, s, &ird, &irq, h);
    *ix = c * ird - s * irq;
    *iy = s * ird + c * irq;
}

// The current, A = R G(x) R^T (G(x) = G + H[dx], symmetric: through the double angle) and
// D = J i - A J psi at a frame-0 flux and (cos, sin) of delta.
void TaylorStepper::expand(double px, double py, double c, double s, Pt* o) const {
    double ird, irq, h[3];
    rotor_current(px, py, c, s, &ird, &irq, h);
    o->px = px;
    o->py = py;
    o->ix = c * ird - s * irq;
    o->iy = s * ird + c * irq;
    const double g_dd = gdd_ + h[0], g_dq = gdq_ + h[1], g_qq = gqq_ + h[2];
    const double c2 = c * c - s * s, s2 = 2.0 * c * s;
    const double sum = 0.5 * (g_dd + g_qq), dif = 0.5 * (g_dd - g_qq);
    o->axx = sum + dif * c2 - g_dq * s2;
    o->ayy = sum - dif * c2 + g_dq * s2;
    o->axy = dif * s2 + g_dq * c2;
    o->tx = -o->iy - (-o->axx * py + o->axy * px);
    o->ty = o->ix - (-o->axy * py + o->ayy * px);
}

Vec2 TaylorStepper::begin(const Vec2& psi_dq, const Vec2& i_dq, double theta_m, double omega_m, double c0,
                          double s0, const Vec2& u_avg_ab, double Ts) {
    p0_.px = psi_dq.x();
    p0_.py = psi_dq.y();
    ce0_ = c0;
    se0_ = s0;
    th0_ = theta_m;
    w0_ = omega_m;
    const double te = 1.5 * p_ * cross(p0_.px, p0_.py, i_dq.x(), i_dq.y());
    a0_ = mech_.accel(0.0, te, w0_);
    g_ = mech_.ripple_gain(0.0, te, w0_);
    n_ = 0;
    t_[0] = wx_[0] = wy_[0] = 0.0;
    // Half a period at the mean voltage, seen from the rotor there (a centred pattern's ripple is
    // zero at mid-period; dead time moves the mean by ~vdc t_dead/Ts, which shifts the expansion
    // point by ~0.1 mWb and costs nothing but that).
    const Vec2 u = to_frame0(u_avg_ab);
    const double hm = 0.5 * Ts;
    const double px = p0_.px + hm * (u.x() - rs_ * i_dq.x()), py = p0_.py + hm * (u.y() - rs_ * i_dq.y());
    double c, s;
    rotate_small(1.0, 0.0, delta_at(hm, 0.0), &c, &s);
    return Vec2(c * px + s * py, -s * px + c * py);
}

void TaylorStepper::expand_about(const TaylorAnchor& a) {
    x0d_ = a.psi.x();
    x0q_ = a.psi.y();
    i0d_ = a.i.x();
    i0q_ = a.i.y();
    gdd_ = a.gdd;
    gdq_ = a.gdq;
    gqq_ = a.gqq;
    for (int k = 0; k < 4; ++k) k_[k] = a.k[k];
    // The start point as the expansion has it: Simpson wants one smooth current (the exact start
    // value differs by the expansion's third-order error).
    expand(p0_.px, p0_.py, 1.0, 0.0, &p0_);
    te0_ = 1.5 * p_ * cross(p0_.px, p0_.py, p0_.ix, p0_.iy);
}

void TaylorStepper::add_interval(double tau1, const Vec2& u_ab) {
    const double h = tau1 - t_[n_];
    if (!(h > 0.0) || n_ >= kMaxIntervals) return;  // the sequencer gives at most 13
    const Vec2 u = to_frame0(u_ab);
    t_[n_ + 1] = tau1;
    wx_[n_ + 1] = wx_[n_] + h * u.x();
    wy_[n_ + 1] = wy_[n_] + h * u.y();
    ++n_;
}

std::array<double, 3> TaylorStepper::predict_phase_currents(double tau, const Vec2& u_ab) const {
    const Vec2 u = to_frame0(u_ab);
    const double h = tau - t_[n_];
    double c, s, ix, iy;
    rotate_small(1.0, 0.0, delta_at(tau, 0.0), &c, &s);
    current_at(p0_.px + wx_[n_] + h * u.x() - rs_ * tau * p0_.ix, p0_.py + wy_[n_] + h * u.y() - rs_ * tau * p0_.iy, c,
               s, &ix, &iy);
    return inverse_clarke(Vec2(ce0_ * ix - se0_ * iy, se0_ * ix + ce0_ * iy));
}

void TaylorStepper::integrate(double Ts) {
    const double kt = 1.5 * p_, rs = rs_, tm = 0.5 * Ts, inv_ts = 1.0 / Ts;
    // The ripple's moments: r = W - t u_m is linear on each interval, so they are exact.
    const double umx = wx_[n_] * inv_ts, umy = wy_[n_] * inv_ts;
    double m0x = 0, m0y = 0, m1x = 0, m1y = 0, sxx = 0, sxy = 0, syy = 0;
    double rax = 0.0, ray = 0.0;  // r(0) = 0
    for (int k = 0; k < n_; ++k) {
        const double ta = t_[k], tb = t_[k + 1], h = tb - ta;
        const double rbx = wx_[k + 1] - tb * umx, rby = wy_[k + 1] - tb * umy;
        m0x += 0.5 * h * (rax + rbx);
        m0y += 0.5 * h * (ray + rby);
        const double wa = (1.0 / 6.0) * h * (2.0 * (ta - tm) + (tb - tm)), wb = (1.0 / 6.0) * h * ((ta - tm) + 2.0 * (tb - tm));
        m1x += wa * rax + wb * rbx;
        m1y += wa * ray + wb * rby;
        const double h3 = (1.0 / 3.0) * h;
        sxx += h3 * (rax * rax + rax * rbx + rbx * rbx);
        sxy += h3 * (rax * ray + 0.5 * (rax * rby + rbx * ray) + rbx * rby);
        syy += h3 * (ray * ray + ray * rby + rby * rby);
        rax = rbx;
        ray = rby;
    }

    // H~[S] at mid-period: S into the rotor frame (double angle), the third derivatives, back.
    double cm, sm, cT, sT;
    rotate_small(1.0, 0.0, delta_at(tm, 0.0), &cm, &sm);
    rotate_small(1.0, 0.0, delta_at(Ts, 0.0), &cT, &sT);
    double hsx, hsy;
    {
        const double c2 = cm * cm - sm * sm, s2 = 2.0 * cm * sm;
        const double sum = 0.5 * (sxx + syy), dif = 0.5 * (sxx - syy);
        const double sdd = sum + dif * c2 + sxy * s2, sqq = sum - dif * c2 - sxy * s2, sdq = sxy * c2 - dif * s2;
        const double hd = k_[0] * sdd + 2.0 * k_[1] * sdq + k_[2] * sqq;
        const double hq = k_[1] * sdd + 2.0 * k_[2] * sdq + k_[3] * sqq;
        hsx = cm * hd - sm * hq;
        hsy = sm * hd + cm * hq;
    }
    // The ripple's mean current (constant over the period, so part of the smooth path's Rs drop),
    // with A at the expansion point seen at mid-period.
    Pt pm, pT;
    expand(x0d_ * cm - x0q_ * sm, x0d_ * sm + x0q_ * cm, cm, sm, &pm);
    const double irx = (pm.axx * m0x + pm.axy * m0y + 0.5 * hsx) * inv_ts;
    const double iry = (pm.axy * m0x + pm.ayy * m0y + 0.5 * hsy) * inv_ts;

    // The smooth path at Ts/2 and Ts: Euler for its Rs drop, then corrected once with Simpson's
    // integral of the smooth current (the growth of i - i(0) is ~linear, so the point at Ts/2
    // takes a quarter of the correction at Ts).
    const double vx = umx - rs * (p0_.ix + irx), vy = umy - rs * (p0_.iy + iry);
    expand(p0_.px + tm * vx, p0_.py + tm * vy, cm, sm, &pm);
    expand(p0_.px + Ts * vx, p0_.py + Ts * vy, cT, sT, &pT);
    {
        const double k6 = Ts * (1.0 / 6.0);
        const double dx = -rs * (k6 * (4.0 * pm.ix + pT.ix - 5.0 * p0_.ix));
        const double dy = -rs * (k6 * (4.0 * pm.iy + pT.iy - 5.0 * p0_.iy));
        pm.px += 0.25 * dx;
        pm.py += 0.25 * dy;
        pm.ix += 0.25 * (pm.axx * dx + pm.axy * dy);
        pm.iy += 0.25 * (pm.axy * dx + pm.ayy * dy);
        pT.px += dx;
        pT.py += dy;
        pT.ix += pT.axx * dx + pT.axy * dy;
        pT.iy += pT.axy * dx + pT.ayy * dy;
    }

    // Torque. Linear in r: c . r with c = (psi_x A_xy - psi_y A_xx + i_y, psi_x A_yy - psi_y A_xy - i_x)
    // (psi x A r + r x i), taken linear in t between the ends; second order: r x A r and
    // psi x 1/2 H~[r, r]. E by the weights of int_0^Ts (Ts - s) f ds on (0, Ts/2, Ts): Ts^2 (1/6, 1/3, 0).
    auto cvec = [](const Pt& q, double* cx, double* cy) {
        *cx = q.px * q.axy - q.py * q.axx + q.iy;
        *cy = q.px * q.ayy - q.py * q.axy - q.ix;
    };
    double c0x, c0y, cmx, cmy, cTx, cTy;
    cvec(p0_, &c0x, &c0y);
    cvec(pm, &cmx, &cmy);
    cvec(pT, &cTx, &cTy);
    const double q2 = pm.axy * (sxx - syy) + (pm.ayy - pm.axx) * sxy + 0.5 * cross(pm.px, pm.py, hsx, hsy);
    // the ripple current's own Rs drop (eps = -Rs A int (r - M0/Ts)): int A eps = Rs A^2 M1, and in
    // the torque c . int eps = c . Rs A M1
    const double aex = rs * (pm.axx * m1x + pm.axy * m1y), aey = rs * (pm.axy * m1x + pm.ayy * m1y);
    auto torque_integrals = [&](double* int_te, double* e_end, double* e_mid) {
        const double f0 = 0.0;
        const double fm = kt * cross(pm.px, pm.py, pm.ix, pm.iy) - te0_;
        const double fT = kt * cross(pT.px, pT.py, pT.ix, pT.iy) - te0_;
        const double lin = cmx * m0x + cmy * m0y + ((cTx - c0x) * m1x + (cTy - c0y) * m1y) * inv_ts + cmx * aex + cmy * aey;
        *int_te = Ts * te0_ + Ts * (1.0 / 6.0) * (f0 + 4.0 * fm + fT) + kt * (lin + q2);
        *e_end = Ts * Ts * (f0 * (1.0 / 6.0) + fm * (1.0 / 3.0)) +
                 kt * (cmx * (tm * m0x - m1x) + cmy * (tm * m0y - m1y) + tm * q2);
        *e_mid = Ts * Ts * (1.0 / 24.0) * (2.0 * f0 + fm);  // the smooth part, linear torque
    };
    double e_mid;
    torque_integrals(&int_te_, &e_, &e_mid);
    // The angle the points were taken at left out g E: the current follows through D.
    const double ddm = p_ * g_ * e_mid, ddT = p_ * g_ * e_;
    if (ddm != 0.0 || ddT != 0.0) {
        pm.ix += pm.tx * ddm;
        pm.iy += pm.ty * ddm;
        pT.ix += pT.tx * ddT;
        pT.iy += pT.ty * ddT;
        torque_integrals(&int_te_, &e_, &e_mid);
    }

    // int i, and the final flux (the voltage part exactly).
    const double dax = (pT.axx - p0_.axx) * inv_ts, daxy = (pT.axy - p0_.axy) * inv_ts, day = (pT.ayy - p0_.ayy) * inv_ts;
    const double iix = Ts * (1.0 / 6.0) * (p0_.ix + 4.0 * pm.ix + pT.ix) + pm.axx * m0x + pm.axy * m0y + dax * m1x +
                       daxy * m1y + 0.5 * hsx + pm.axx * aex + pm.axy * aey;
    const double iiy = Ts * (1.0 / 6.0) * (p0_.iy + 4.0 * pm.iy + pT.iy) + pm.axy * m0x + pm.ayy * m0y + daxy * m1x +
                       day * m1y + 0.5 * hsy + pm.axy * aex + pm.ayy * aey;
    psx_ = p0_.px + wx_[n_] - rs * iix;
    psy_ = p0_.py + wy_[n_] - rs * iiy;
}

TaylorStepper::End TaylorStepper::finish(double Ts) const {
    // Speed from the mechanics at the mean torque and the mean speed (w0 + Ts a0/2 + g E/Ts):
    // exact for the linear inertia law. Angle: the start acceleration, the torque's shape inside
    // the period (g E), and what load and friction change over it, taken as growing linearly from
    // the start: sh = mean accel - a0 - g (mean T_e - te0), of which the angle sees Ts^2/3.
    const double te_mean = int_te_ / Ts;
    const double a_mean = mech_.accel(0.5 * Ts, te_mean, w0_ + 0.5 * Ts * a0_ + g_ * e_ / Ts);
    const double sh = a_mean - a0_ - g_ * (te_mean - te0_);
    End e;
    e.omega_m = w0_ + Ts * a_mean;
    e.theta_m = th0_ + Ts * (w0_ + 0.5 * Ts * a0_) + g_ * e_ + Ts * Ts * (1.0 / 3.0) * sh;
    const double d1 = p_ * (e.theta_m - th0_);
    double c1, s1;
    rotate_small(1.0, 0.0, d1, &c1, &s1);
    e.psi_dq = Vec2(c1 * psx_ + s1 * psy_, -s1 * psx_ + c1 * psy_);
    rotate_small(ce0_, se0_, d1, &e.c, &e.s);
    return e;
}

}  // namespace mcsim::detail
