// Two-level three-phase inverter: centre-aligned PWM edge sequencing with dead time, averaged
// phase voltages, diode conduction. Used by the plant (sim/src/plant.cpp); see docs/plant.md.
// Phase voltages are relative to the DC-link midpoint; the machine sees them through the
// amplitude-invariant Clarke transform (2.4), which removes the common mode by construction.
#pragma once
#include <array>
#include <cstdint>
#include "mcsim/plant.hpp"

namespace mcsim {

// u_alpha_beta from three phase-to-midpoint voltages: (2.4) of the line-to-neutral voltages
// v_x - u_n, u_n = (v_a + v_b + v_c)/3; the zero sequence cancels, so u_n need not be formed.
inline Vec2 clarke_phase_voltages(const std::array<double, 3>& v) {
    constexpr double k = 0.57735026918962576451;  // 1/sqrt(3)
    return Vec2((2.0 * v[0] - v[1] - v[2]) * (1.0 / 3.0), (v[1] - v[2]) * k);
}

// Phase currents from i_alpha_beta (inverse of (2.4), zero sequence = 0 in a star winding).
inline std::array<double, 3> inverse_clarke(const Vec2& i_ab) {
    constexpr double h = 0.86602540378443864676;  // sqrt(3)/2
    return {i_ab.x(), -0.5 * i_ab.x() + h * i_ab.y(), -0.5 * i_ab.x() - h * i_ab.y()};
}

// Device on-state drop, opposing the current; linear inside the zero band so that a current
// hovering around 0 does not see a +-v_device chatter.
double device_drop(double i, const InverterConfig& cfg);

// Period-average phase voltages of the averaged inverter: (d_x - 0.5) vdc, optionally with the
// averaged dead-time error -sign(i_x) vdc t_dead/Ts (0 inside the zero band) and the device drop.
std::array<double, 3> averaged_phase_voltages(const std::array<double, 3>& duty,
                                              const std::array<double, 3>& i_abc,
                                              const InverterConfig& cfg, double Ts);

// Voltage of a phase whose both switches are off while it carries current: the freewheeling
// diode clamps it to the rail opposite to the current (i > 0 leaves the phase: low diode).
double diode_phase_voltage(double i, const InverterConfig& cfg);

// Switching events of one centre-aligned PWM period. Usage:
//   seq.begin(t0, Ts, duty, cfg);
//   while (seq.next_time(&te)) { integrate to te with seq.levels(); seq.apply(te, i_abc(te)); }
//   integrate to t0 + Ts.
// Commanded edges are decided at their instant with the phase current of that instant: a turn-on
// that must wait for the dead time is queued as a delayed level change (and cancelled if the
// commanded turn-off comes first: the pulse is swallowed).
class PwmSequencer {
public:
    void begin(double t0, double Ts, const std::array<double, 3>& duty, const InverterConfig& cfg);
    bool next_time(double* t) const;
    void apply(double t, const std::array<double, 3>& i_abc);
    // Decides now the pending commanded edges whose current sign cannot change before they are
    // due: |i_x| - di_max (t_k - t) > i_zero_band, di_max [A/s] a bound on |di_x/dt|. An edge
    // that only starts a dead time (no voltage change at t_k) then no longer splits the
    // integration; the outcome is the same as deciding at t_k.
    void predecide(double t, const std::array<double, 3>& i_abc, double di_max);
    // No commanded edge is left to decide: apply() and predecide() then need no currents.
    bool all_decided() const { return undecided_ == 0; }
    // The events due at next_time() include a commanded edge (apply() reads the currents).
    bool next_needs_currents() const {
        for (int k = next_; k < n_ && ev_[k].t <= ev_[next_].t; ++k)
            if (ev_[k].kind == CmdRise || ev_[k].kind == CmdFall) return true;
        return false;
    }
    // +1 high side (or upper diode) conducting, -1 low side (or lower diode).
    const std::array<int, 3>& levels() const { return level_; }
    // The commanded edges apply() decided since begin() (predecide()'s are not listed): when,
    // which phase, the current it was given and the threshold that current was compared with
    // (+i_zero_band for a rise, -i_zero_band for a fall). The plant's period-level integrator
    // decides with predicted currents and checks the decisions afterwards.
    struct Decision {
        double t, i, threshold;
        int phase;
    };
    int decision_count() const { return n_dec_; }
    const Decision& decision(int k) const { return dec_[k]; }

private:
    enum Kind : uint8_t { CmdRise, CmdFall, SetHigh, SetLow, Dropped };
    struct Event {
        double t;
        uint8_t phase;
        Kind kind;
    };
    void insert(const Event& e);
    void cancel(int phase, Kind kind);
    void sort_pending();

    Event ev_[12];
    int n_ = 0, next_ = 0;
    int undecided_ = 0;  // pending CmdRise/CmdFall events
    Decision dec_[6];
    int n_dec_ = 0;
    double t_end_ = 0, t_dead_ = 0, i_band_ = 0;
    std::array<int, 3> level_{{-1, -1, -1}};
};

}  // namespace mcsim
