// The period-level integrator of the switching inverter (internal to sim/src).
//
// One PWM period is a handful of constant-voltage intervals. Instead of one Hermite step per
// interval (hermite.hpp), the period is split into `steps` equal steps; each step integrates the
// smooth path at its mean voltage and adds the ripple r(t) = int (u - u_mean) dt through its
// moments (RippleMoments): the current's response G r to first order, (1/2) H[r, r] to second,
// the torque's likewise. One model evaluation per step instead of ~7 per period.
//
// The dead-time edges are decided up front with currents predicted to first order from the
// period start, then checked against the step's reconstruction of the current at each edge:
// if a decision could have gone the other way (within `margin` of its threshold, or on the
// other side), the caller redoes the period edge by edge. Equations, errors and the fallback
// rate: docs/plant.md "Ripple moments".
#pragma once
#include <array>

#include "hermite.hpp"
#include "mcsim/inverter.hpp"

namespace mcsim::detail {

struct RipplePeriodOut {
    std::array<double, 3> v_int{{0, 0, 0}};  // int v_phase dt over the period [V s]
    double ux_int = 0, uy_int = 0;           // int u_ab dt [V s]
};

// Advances hs (already at the period start, begin() called) over [t0, t0 + Ts]. Returns false,
// with hs in an undefined state, when a dead-time decision is not certain; the caller then
// restarts hs and integrates edge by edge.
bool ripple_period(HermiteStepper& hs, PwmSequencer& seq, const InverterConfig& inv, double rs, double p,
                   double t0, double Ts, const std::array<double, 3>& duty, int steps, double margin,
                   RipplePeriodOut* out);

}  // namespace mcsim::detail
