// Shaft mechanics, see sim/include/mcsim/mechanics.hpp.
#include "mcsim/mechanics.hpp"

#include <stdexcept>

namespace mcsim {

double Mechanics::sample_load(double t) {
    if (!cfg_.load_torque) return 0.0;
    if (t == cache_t_ && !cache_dyno_) return cache_v_;
    return cfg_.load_torque(t);
}

double Mechanics::sample_dyno(double t) {
    if (t == cache_t_ && cache_dyno_) return cache_v_;
    return cfg_.dyno_speed(t);
}

double Mechanics::begin_period(double t0, double Ts, double omega_now) {
    if (cfg_.locked) {
        mode_ = Held;
        slope_ = 0.0;
        omega_end_ = 0.0;
        return 0.0;
    }
    if (cfg_.mode == MechanicsConfig::Mode::Dyno) {
        if (!cfg_.dyno_speed) throw std::invalid_argument("MechanicsConfig: Dyno mode without dyno_speed");
        mode_ = Dyno;
        const double w0 = sample_dyno(t0);
        const double w1 = cfg_.dyno_speed(t0 + Ts);
        slope_ = (w1 - w0) / Ts;
        omega_end_ = w1;
        cache_t_ = t0 + Ts;
        cache_v_ = w1;
        cache_dyno_ = true;
        return w0;
    }
    mode_ = Inertia;
    if (!(cfg_.inertia > 0.0)) throw std::invalid_argument("MechanicsConfig: inertia must be > 0");
    inv_j_ = 1.0 / cfg_.inertia;
    load0_ = sample_load(t0);
    const double l1 = cfg_.load_torque ? cfg_.load_torque(t0 + Ts) : 0.0;
    slope_ = (l1 - load0_) / Ts;
    cache_t_ = t0 + Ts;
    cache_v_ = l1;
    cache_dyno_ = false;
    return omega_now;
}

}  // namespace mcsim
