// The plant's period-level integrator for enabled periods (PlantConfig::Integrator::Taylor, the
// scenario default; internal to sim/src). Equations and measured errors: docs/plant.md "Taylor".
//
// Frame 0 is the rotor frame at the period start (electrical angle theta_e0); it does not turn, so
// there (4.1) reads
//     d psi/dt = u - Rs i,      i = F(psi, delta) = R(delta) f(R(-delta) psi),
// delta = theta_e(t) - theta_e0, and the switched voltage integrates exactly: psi(t) = psi(0) +
// W(t) - Rs int i, W = int u. The current map f is expanded to second order about the rotor-frame
// flux predicted for mid-period, x0 (G = di/dpsi, H its derivative: FluxModel::current_taylor):
//     f(x) = i0 + G dx + 1/2 H[dx, dx],      dx = x - x0.
// The flux is split into the smooth path of the mean voltage u_m and the PWM ripple
// r(t) = W(t) - t u_m (piecewise linear, zero at both ends, odd about mid-period for a centred
// pattern):  F(psi_s + r) = F(psi_s) + A r + 1/2 H~[r, r],  A = dF/dpsi = R G(x) R^T. So
//   int i   = Simpson over (0, Ts/2, Ts) of F on the smooth path + A M0 + A' M1 + 1/2 H~[S] + (Rs term),
//   int T_e = the same for 1.5 p psi x i,
// with the ripple's moments M0 = int r, M1 = int (t - Ts/2) r, S = int r r^T, accumulated interval
// by interval (a few operations each: no current is formed per interval). Third-order terms are odd
// about mid-period and cancel over it to leading order. Only the small Rs i term, the dead-time
// decisions and the torque integral see the expansion; at the period end the caller evaluates the
// model exactly, so i = f(psi) holds at every sample.
// The shaft: inside the period the angle is theta_m0 + w0 t + a0 t^2/2 + g E(t), with
// E(t) = int_0^t (t - s)(T_e(s) - T_e(0)) ds and g = d accel/d T_e (the torque's shape turns the
// rotor by ~1e-8 rad in a period, ~1e-6 A of current); at the end speed and angle come from the
// mechanics with the period's mean torque.
#pragma once
#include <array>

#include "mcsim/machine.hpp"
#include "mcsim/mechanics.hpp"

namespace mcsim::detail {

// The expansion point and the model there.
struct TaylorAnchor {
    Vec2 psi, i;              // psi_dq [Wb], i_dq = f(psi_dq) [A]
    double gdd, gdq, gqq;     // di/dpsi [1/H]
    double k[4];              // its derivative (FluxModel::current_taylor) [1/(H Wb)]
};

class TaylorStepper {
public:
    TaylorStepper(const Mechanics& mech, int pole_pairs, double rs) : mech_(mech), p_(pole_pairs), rs_(rs) {}

    // Starts a period of length Ts at the rotor-frame state (psi_dq, i_dq = f(psi_dq)), shaft
    // angle theta_m and speed omega_m (c0, s0: cos, sin of p theta_m); u_avg_ab is the period's
    // mean stationary-frame voltage (from the duties). Returns the rotor-frame flux predicted for
    // mid-period: the caller evaluates the model there and hands it to expand_about().
    Vec2 begin(const Vec2& psi_dq, const Vec2& i_dq, double theta_m, double omega_m, double c0, double s0,
               const Vec2& u_avg_ab, double Ts);
    void expand_about(const TaylorAnchor& a);
    // The period's voltage, interval by interval in time order: u_ab holds from the end of the
    // last interval to tau1 (from the period start). At most kMaxIntervals per period.
    static constexpr int kMaxIntervals = 24;
    void add_interval(double tau1, const Vec2& u_ab);
    // Phase currents predicted at tau (>= the end of the last interval) if u_ab holds until then:
    // what the dead-time decisions see (first order in the Rs drop: ~1e-3 A, which matters only
    // for a current within that of the zero band's edge).
    std::array<double, 3> predict_phase_currents(double tau, const Vec2& u_ab) const;
    // After the last interval (ending at Ts): the current, torque and angle integrals from the
    // smooth path and the ripple's moments, and the final flux.
    void integrate(double Ts);

    // The period's end: the shaft from the torque integral, and the rotor-frame flux at the final
    // angle, where the caller evaluates the model exactly.
    struct End {
        Vec2 psi_dq;
        double theta_m, omega_m;
        double c, s;  // cos, sin of p theta_m
    };
    End finish(double Ts) const;

private:
    // One point of the smooth path in frame 0: flux, expanded current, A = R(delta) G(x) R(-delta)
    // (symmetric) and D = di/d delta = J i - A J psi (the rotor turning under the frame-0 flux).
    struct Pt {
        double px, py, ix, iy;
        double axx, axy, ayy;
        double tx, ty;
    };
    void rotor_current(double px, double py, double c, double s, double* ird, double* irq, double h[3]) const;
    void current_at(double px, double py, double c, double s, double* ix, double* iy) const;
    void expand(double px, double py, double c, double s, Pt* o) const;
    // delta at tau given E(tau) (the shaft model at the top of this file).
    double delta_at(double tau, double e) const { return p_ * (tau * (w0_ + 0.5 * a0_ * tau) + g_ * e); }
    Vec2 to_frame0(const Vec2& u_ab) const {
        return Vec2(ce0_ * u_ab.x() + se0_ * u_ab.y(), -se0_ * u_ab.x() + ce0_ * u_ab.y());
    }

    const Mechanics& mech_;
    double p_, rs_;
    // expansion point (rotor frame)
    double x0d_ = 0, x0q_ = 0, i0d_ = 0, i0q_ = 0, gdd_ = 0, gdq_ = 0, gqq_ = 0, k_[4] = {0, 0, 0, 0};
    // period: frame 0 <-> stationary, the start flux and current (as the expansion has it), the
    // shaft at the start (the angle inside the period is theta_m0 + w0 t + a0 t^2/2 + g E(t))
    double ce0_ = 1, se0_ = 0, th0_ = 0, w0_ = 0, a0_ = 0;
    double g_ = 0;    // d accel/d T_e at the start [1/(kg m^2)]: 1/J, or 0 while the shaft is held
    Pt p0_{};
    double te0_ = 0;  // T_e at the start [N m]
    // the voltage integral W(t) = int_0^t u dt (frame 0) at the interval ends
    int n_ = 0;
    double t_[kMaxIntervals + 1] = {0}, wx_[kMaxIntervals + 1] = {0}, wy_[kMaxIntervals + 1] = {0};
    // results of integrate()
    double psx_ = 0, psy_ = 0;  // final frame-0 flux
    double int_te_ = 0;         // int T_e dt [N m s]
    double e_ = 0;              // E(Ts) = int (Ts - s)(T_e(s) - te0) ds [N m s^2]
};

}  // namespace mcsim::detail
