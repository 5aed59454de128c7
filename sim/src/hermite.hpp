// The plant's integrator for periods with the outputs enabled (internal to sim/src).
//
// In the stationary frame the machine equation (4.1) reads d psi_ab/dt = u_ab - Rs i_ab: the
// voltage, constant between switching instants, integrates exactly and only the small Rs i term
// needs a quadrature. Per interval of constant voltage: one model evaluation (current and
// Jacobian) at a Taylor-predicted end point, then the implicit two-point Hermite rule
//     int_a^b f dt = h/2 (f_a + f_b) + h^2/12 (f'_a - f'_b)        (local error O(h^5))
// for psi, omega, theta and the energy ledger, with the end current corrected linearly about the
// prediction (the correction is O(Rs h^3 i''), so what the linearisation leaves is its square).
// Equations and measured errors: docs/plant.md "Integration method".
#pragma once
#include <array>

#include "mcsim/machine.hpp"
#include "mcsim/mechanics.hpp"
#include "analytic_eval.hpp"

namespace mcsim::detail {

// One integration point (stationary frame; G = d i_ab / d psi_ab is symmetric).
struct HPoint {  // no initialisers: one is built per interval, every field is written
    double px, py;       // psi_ab [Wb]
    double ix, iy;       // i_ab [A]
    double gxx, gxy, gyy;  // [1/H]
    double th, w, te;    // theta_m [rad], omega_m [rad/s], T_e [N m]
    double c, s;         // cos, sin of p theta_m
};

// The switching ripple of one step about its mean voltage (the period-level integrator, docs/
// plant.md "Ripple moments"): r(t) = int_0^t (u - u_mean) dt is zero at both ends of the step;
// the step integrates the smooth path at u_mean and adds what r does to int i, int T_e and the
// ledger through these moments (t from the step start).
struct RippleMoments {
    double m0x, m0y;       // int r dt [Wb s]
    double m1x, m1y;       // int t r dt [Wb s^2]
    double sxx, sxy, syy;  // int r r^T dt [Wb^2 s]
};

// What a ripple step leaves for the caller's check of its dead-time decisions: both end points
// and the smooth current's derivatives there (u_mean, no ripple).
struct StepEnds {
    HPoint a, b;
    double dix_a, diy_a, dix_b, diy_b;  // [A/s]
    double h;                           // [s]
    // Smooth current (cubic Hermite) plus the first-order ripple G(t) r at t in [0, h].
    void current_at(double t, double rx, double ry, double* ix, double* iy) const;
};

// Integrals over the intervals since begin(): three-phase energies [J] and int u_dq dt [V s].
struct HLedger {
    double ein = 0, cu = 0, mech = 0, ud = 0, uq = 0;
};

class HermiteStepper {
public:
    HermiteStepper(const FluxModel& model, const Mechanics& mech, int pole_pairs, double rs)
        : model_(model), fast_(model.analytic_eval()), mech_(mech), p_(pole_pairs), rs_(rs) {}

    // Starts at the rotor-frame state (psi, i = current(psi), g = di_dpsi(psi)) with c, s the
    // cos, sin of p theta_m. ledger = false skips the energy and u_dq integrals.
    void begin(const Vec2& psi_dq, const Vec2& i_dq, const Mat2& g_dq, double theta_m, double omega_m,
               double c, double s, bool ledger);
    // Advances [tau0, tau1] (from the period start, for the mechanics' profiles) at constant u_ab.
    // rp: the step is a ripple step at the mean voltage (ux, uy) with these moments; ends_ then
    // keeps the end points for StepEnds::current_at. Needs the analytic model's evaluation.
    void interval(double tau0, double tau1, double ux, double uy, const RippleMoments* rp = nullptr);
    bool ripple_capable() const { return fast_ != nullptr; }
    const StepEnds& ends() const { return ends_; }
    // Rotor-frame flux at the current point and the angle/speed; the caller re-evaluates the
    // model there so the state it keeps is exactly consistent.
    Vec2 psi_dq() const;
    const HPoint& point() const { return a_; }
    const HLedger& ledger() const { return led_; }
    std::array<double, 3> phase_currents() const;

private:
    // What the ripple adds over a step: int (i - i_smooth) dt (ix, iy), int (T_e - T_smooth) dt
    // (te1), int (h/2 - t)(T_e - T_smooth) dt (te2), and H[S] = the Hessian of i(psi) applied to
    // int r r^T dt (hx, hy).
    struct RippleTerms {
        double ix, iy, te1, te2, hx, hy;
    };
    RippleTerms ripple_terms(const RippleMoments& m, const HPoint& a, const HPoint& b, double h) const;
    void ripple_ledger(const RippleMoments& m, const HPoint& a, const HPoint& b, double h, const RippleTerms& rt,
                       double dix_a, double diy_a, double dix_b, double diy_b, double ux, double uy);
    void eval(double px, double py, HPoint* o) const;  // i, G, T_e at (psi_ab, o->c, o->s)

    const FluxModel& model_;
    const AnalyticEval* fast_;  // inlined evaluation when the model offers it
    const Mechanics& mech_;
    double p_, rs_;
    bool ledger_ = true;
    HPoint a_{};
    HLedger led_;
    StepEnds ends_{};
};

}  // namespace mcsim::detail
