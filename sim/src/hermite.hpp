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
    void interval(double tau0, double tau1, double ux, double uy);
    // Rotor-frame flux at the current point and the angle/speed; the caller re-evaluates the
    // model there so the state it keeps is exactly consistent.
    Vec2 psi_dq() const;
    const HPoint& point() const { return a_; }
    const HLedger& ledger() const { return led_; }
    std::array<double, 3> phase_currents() const;

private:
    void eval(double px, double py, HPoint* o) const;  // i, G, T_e at (psi_ab, o->c, o->s)

    const FluxModel& model_;
    const AnalyticEval* fast_;  // inlined evaluation when the model offers it
    const Mechanics& mech_;
    double p_, rs_;
    bool ledger_ = true;
    HPoint a_{};
    HLedger led_;
};

}  // namespace mcsim::detail
