// Shaft mechanics for the plant: inertia with friction and load, dyno speed hold, locked rotor.
// The user profiles (std::function) are sampled once per PWM period (start and end) and
// interpolated linearly inside it, so the integrator's steps call no std::function.
#pragma once
#include "mcsim/plant.hpp"

namespace mcsim {

class Mechanics {
public:
    explicit Mechanics(const MechanicsConfig& cfg) : cfg_(cfg) {}
    // Samples the profiles for [t0, t0+Ts]. In Dyno mode returns the speed the shaft must have
    // at t0 (the dyno is stiff: the speed is imposed, not integrated); otherwise omega_now.
    double begin_period(double t0, double Ts, double omega_now);
    // d omega_m/dt at tau in [0, Ts] from the period start, given T_e and omega_m.
    // Inertia: J domega/dt = T_e - B omega - T_load(t); Dyno: slope of the profile; Locked: 0.
    double accel(double tau, double te, double omega) const {
        if (mode_ == Held) return 0.0;
        if (mode_ == Dyno) return slope_;
        const double tl = load0_ + slope_ * tau;
        if (cfg_.reactive_load) {
            // Friction-like load: at rest it holds the rotor as long as it can (stiction); the
            // restoring term pulls the residual speed to zero with a 1 ms time constant.
            const double drive = te - cfg_.friction * omega;
            const double atl = tl < 0.0 ? -tl : tl;
            if ((omega < kRest && omega > -kRest) && (drive <= atl && drive >= -atl)) return -omega * 1e3;
            const double dir = (omega >= kRest || (omega > -kRest && drive > 0.0)) ? 1.0 : -1.0;
            return (drive - atl * dir) * inv_j_;
        }
        return (te - cfg_.friction * omega - tl) * inv_j_;
    }
    // d accel/dt along the trajectory, given dT_e/dt and the accel itself (the plant's Hermite
    // integrator needs the end-point derivatives of omega' as well as omega').
    double jerk(double tau, double te, double te_dot, double omega, double alpha) const {
        if (mode_ != Inertia) return 0.0;  // Held: 0; Dyno: the profile is linear in the period
        if (cfg_.reactive_load) {
            const double drive = te - cfg_.friction * omega;
            const double tl = load0_ + slope_ * tau;  // |T_load| changes at slope_ sign(T_load)
            const double atl = tl < 0.0 ? -tl : tl;
            if ((omega < kRest && omega > -kRest) && (drive <= atl && drive >= -atl)) return -alpha * 1e3;
            const double dir = (omega >= kRest || (omega > -kRest && drive > 0.0)) ? 1.0 : -1.0;
            return (te_dot - cfg_.friction * alpha - dir * (tl < 0.0 ? -slope_ : slope_)) * inv_j_;
        }
        return (te_dot - cfg_.friction * alpha - slope_) * inv_j_;
    }
    // d(d omega/dt)/d T_e at (tau, T_e, omega): how a small extra torque (the switching ripple's,
    // for the plant's period-level steps) moves the shaft. 1/J while it turns freely, 0 while it
    // is held (locked, dyno, stiction of a reactive load).
    double ripple_gain(double tau, double te, double omega) const {
        if (mode_ != Inertia) return 0.0;
        if (cfg_.reactive_load) {
            const double drive = te - cfg_.friction * omega;
            const double tl = load0_ + slope_ * tau;
            const double atl = tl < 0.0 ? -tl : tl;
            if ((omega < kRest && omega > -kRest) && (drive <= atl && drive >= -atl)) return 0.0;
        }
        return inv_j_;
    }
    // Speed at the end of the period when imposed (Dyno), to remove the round-off of the ramp.
    bool speed_imposed() const { return mode_ != Inertia; }
    double omega_end() const { return omega_end_; }
    const MechanicsConfig& config() const { return cfg_; }

private:
    static constexpr double kRest = 1e-3;   // [rad/s] below this a reactive load may hold the rotor
    enum Mode { Inertia, Dyno, Held };
    double sample_load(double t);
    double sample_dyno(double t);

    MechanicsConfig cfg_;
    Mode mode_ = Inertia;
    double slope_ = 0, load0_ = 0, inv_j_ = 0, omega_end_ = 0;
    // The end sample of one period is the start sample of the next: one call per period.
    double cache_t_ = -1e300, cache_v_ = 0;
    bool cache_dyno_ = false;
};

}  // namespace mcsim
