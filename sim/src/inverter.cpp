// Inverter model: see sim/include/mcsim/inverter.hpp and docs/plant.md (dead-time model).
#include "mcsim/inverter.hpp"

#include <algorithm>
#include <cmath>

namespace mcsim {

namespace {
double clamp01(double d) { return d < 0.0 ? 0.0 : (d > 1.0 ? 1.0 : d); }
}  // namespace

double device_drop(double i, const InverterConfig& cfg) {
    if (cfg.v_device == 0.0) return 0.0;
    const double band = cfg.i_zero_band > 0.0 ? cfg.i_zero_band : 1e-12;
    const double s = std::max(-1.0, std::min(1.0, i / band));
    return s * cfg.v_device;
}

double diode_phase_voltage(double i, const InverterConfig& cfg) {
    // A diode's forward drop also opposes the current, so the same device_drop applies.
    return (i > 0.0 ? -0.5 : 0.5) * cfg.vdc - device_drop(i, cfg);
}

std::array<double, 3> averaged_phase_voltages(const std::array<double, 3>& duty,
                                              const std::array<double, 3>& i_abc,
                                              const InverterConfig& cfg, double Ts) {
    std::array<double, 3> v{};
    const double dt_err = cfg.averaged_dead_time && Ts > 0.0 ? cfg.vdc * cfg.t_dead / Ts : 0.0;
    for (int k = 0; k < 3; ++k) {
        const double d = clamp01(duty[k]);
        v[k] = (d - 0.5) * cfg.vdc - device_drop(i_abc[k], cfg);
        // Same rule as the switching model: inside the zero band the commanded edge is taken.
        // Pulses shorter than t_dead are not swallowed here (an averaged model cannot tell).
        if (dt_err != 0.0 && d > 0.0 && d < 1.0) {
            if (i_abc[k] > cfg.i_zero_band) v[k] -= dt_err;
            else if (i_abc[k] < -cfg.i_zero_band) v[k] += dt_err;
        }
    }
    return v;
}

void PwmSequencer::insert(const Event& e) {
    int k = n_;
    while (k > next_ && ev_[k - 1].t > e.t) {
        ev_[k] = ev_[k - 1];
        --k;
    }
    ev_[k] = e;
    ++n_;
}

void PwmSequencer::cancel(int phase, Kind kind) {
    for (int k = next_; k < n_; ++k) {
        if (ev_[k].phase == phase && ev_[k].kind == kind) {
            for (int j = k; j + 1 < n_; ++j) ev_[j] = ev_[j + 1];
            --n_;
            return;
        }
    }
}

void PwmSequencer::sort_pending() {
    for (int k = next_ + 1; k < n_; ++k) {
        const Event e = ev_[k];
        int j = k;
        while (j > next_ && ev_[j - 1].t > e.t) {
            ev_[j] = ev_[j - 1];
            --j;
        }
        ev_[j] = e;
    }
}

void PwmSequencer::predecide(double t, const std::array<double, 3>& i_abc, double di_max) {
    if (t_dead_ <= 0.0 || undecided_ == 0) return;  // no dead time: every edge changes the voltage
    // One pass to find each phase's pending events (at most a rise, a fall and a delayed turn-on
    // per phase), then the decisions phase by phase: rise first, the fall depends on it.
    int rise[3] = {-1, -1, -1}, fall[3] = {-1, -1, -1}, high[3] = {-1, -1, -1};
    bool any = false;
    for (int k = next_; k < n_; ++k) {
        const Event& e = ev_[k];
        if (e.kind == CmdRise) rise[e.phase] = k, any = true;
        else if (e.kind == CmdFall) fall[e.phase] = k, any = true;
        else if (e.kind == SetHigh) high[e.phase] = k;
    }
    if (!any) return;  // usually everything was decided at the period start
    bool moved = false, dropped = false;
    for (int x = 0; x < 3; ++x) {
        const double i = i_abc[x];
        const double margin = std::fabs(i) - i_band_;
        if (rise[x] >= 0) {
            Event& e = ev_[rise[x]];
            if (margin - di_max * (e.t - t) <= 0.0) continue;  // and the fall waits for it
            if (i > 0.0) {
                e.t += t_dead_;
                moved = true;
            }
            e.kind = SetHigh;
            --undecided_;
            high[x] = rise[x];
        }
        if (fall[x] < 0) continue;
        Event& e = ev_[fall[x]];
        if (margin - di_max * (e.t - t) <= 0.0) continue;
        --undecided_;
        if (i < 0.0) {
            e.t = std::min(e.t + t_dead_, t_end_);
            e.kind = SetLow;
            moved = true;
        } else if (high[x] >= 0 && ev_[high[x]].t >= e.t) {
            // Swallowed pulse: the turn-on would come after the turn-off; both disappear.
            e.kind = Dropped;
            ev_[high[x]].kind = Dropped;
            dropped = true;
        } else {
            e.kind = SetLow;
        }
    }
    if (dropped) {
        int w = next_;
        for (int k = next_; k < n_; ++k)
            if (ev_[k].kind != Dropped) ev_[w++] = ev_[k];
        n_ = w;
    }
    if (moved) sort_pending();
}

void PwmSequencer::begin(double t0, double Ts, const std::array<double, 3>& duty,
                         const InverterConfig& cfg) {
    n_ = next_ = 0;
    undecided_ = 0;
    n_dec_ = 0;
    t_end_ = t0 + Ts;
    t_dead_ = cfg.t_dead > 0.0 ? cfg.t_dead : 0.0;
    i_band_ = cfg.i_zero_band;
    for (int k = 0; k < 3; ++k) {
        const double d = clamp01(duty[k]);
        // Centre-aligned: the high side is on for d*Ts centred at t0 + Ts/2; a period starts and
        // ends in V000 (all low) unless d = 1.
        if (d >= 1.0) {
            level_[k] = +1;
            continue;
        }
        level_[k] = -1;
        if (d <= 0.0) continue;
        insert({t0 + 0.5 * (1.0 - d) * Ts, static_cast<uint8_t>(k), CmdRise});
        insert({t0 + 0.5 * (1.0 + d) * Ts, static_cast<uint8_t>(k), CmdFall});
        undecided_ += 2;
    }
}

bool PwmSequencer::next_time(double* t) const {
    if (next_ >= n_ || ev_[next_].t >= t_end_) return false;
    *t = ev_[next_].t;
    return true;
}

void PwmSequencer::apply(double t, const std::array<double, 3>& i_abc) {
    // Every event due at t (coincident edges of different phases are common: equal duties).
    while (next_ < n_ && ev_[next_].t <= t) {
        const Event e = ev_[next_++];
        const int x = e.phase;
        const double i = i_abc[x];
        switch (e.kind) {
            case CmdRise:
                --undecided_;
                dec_[n_dec_++] = {t, i, i_band_, x};
                // Low side off now, high side on after t_dead. In the gap the diodes decide:
                // i < 0 flows through the upper diode, so the phase is already high.
                if (i > i_band_ && t_dead_ > 0.0) insert({t + t_dead_, e.phase, SetHigh});
                else level_[x] = +1;
                break;
            case CmdFall:
                --undecided_;
                dec_[n_dec_++] = {t, i, -i_band_, x};
                // High side off now, low side on after t_dead; i > 0 takes the lower diode at once.
                if (i < -i_band_ && t_dead_ > 0.0) {
                    insert({std::min(t + t_dead_, t_end_), e.phase, SetLow});
                } else {
                    cancel(x, SetHigh);  // a turn-on still waiting for its dead time never happens
                    level_[x] = -1;
                }
                break;
            case SetHigh: level_[x] = +1; break;
            case SetLow: level_[x] = -1; break;
            case Dropped: break;  // removed by predecide before it could be due
        }
    }
}

}  // namespace mcsim
