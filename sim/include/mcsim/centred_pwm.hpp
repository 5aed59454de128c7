// The switching levels of one centre-aligned PWM period, walked edge by edge for a period-level
// integrator (the plant's Taylor path, sim/src/plant.cpp). Same edge times, dead-time rules and
// floating-point arithmetic as PwmSequencer (inverter.hpp), which stays the general sequencer
// (predecision, the decision record, the Hermite and ripple paths); the test
// sim_plant_inverter checks that both give the same level changes at the same instants.
//
// Why a second one: in a centred pattern every commanded turn-on falls in the first half and
// every turn-off in the second, so the commanded edges are one sorted list of at most six, and
// the dead-time delayed level changes come out in time order by themselves (a commanded edge
// plus the same t_dead). Two short queues merged in place replace the event
// array with its insertions and the per-event calls, which cost the Taylor path a fifth of its
// time.
#pragma once
#include <algorithm>
#include <array>
#include <limits>

#include "mcsim/inverter.hpp"

namespace mcsim {

class CentredPwm {
public:
    // As PwmSequencer::begin: duties clamped to [0, 1]; the high side is on for d Ts centred at
    // t0 + Ts/2; a phase with d = 1 stays high, d = 0 low.
    void begin(double t0, double Ts, const std::array<double, 3>& duty, const InverterConfig& cfg) {
        t0_ = t0;
        t_end_ = t0 + Ts;
        t_dead_ = cfg.t_dead > 0.0 ? cfg.t_dead : 0.0;
        band_ = cfg.i_zero_band;
        n_ = 0;
        Edge fall[3];
        for (int x = 0; x < 3; ++x) {
            const double d = duty[x] < 0.0 ? 0.0 : (duty[x] > 1.0 ? 1.0 : duty[x]);
            if (d >= 1.0) {
                level_[x] = +1;
                continue;
            }
            level_[x] = -1;
            if (d <= 0.0) continue;
            insert(cmd_, {t0 + 0.5 * (1.0 - d) * Ts, x, +1});
            insert(fall, {t0 + 0.5 * (1.0 + d) * Ts, x, -1});
            ++n_;
        }
        // Every turn-on is due by mid-period and every turn-off from then on, so the commanded
        // edges are one sorted list: the turn-ons, then the turn-offs.
        for (int k = 0; k < n_; ++k) cmd_[n_ + k] = fall[k];
    }

    // +1 high side (or upper diode) conducting, -1 low side (or lower diode): at the period start
    // after begin(), at the period end after walk().
    const std::array<int, 3>& levels() const { return level_; }

    // Walks the period in time order. At an instant with commanded edges, and only when there is
    // a dead time (otherwise the current decides nothing), currents(tau, mask) returns the phase
    // currents [A] at tau = t - t0 [s] (mask bit x: phase x has a commanded edge there; only those
    // entries are read). change(tau, levels) is called after the levels changed at tau, with
    // 0 < tau < Ts. Edges at or after t0 + Ts do not happen in this period (as in PwmSequencer).
    template <class Currents, class Change>
    void walk(Currents&& currents, Change&& change) {
        constexpr double inf = std::numeric_limits<double>::infinity();
        // The delayed level changes, one queue in time order: a delayed turn-on comes at most
        // Ts/2 + t_dead, a delayed turn-off at least that late.
        Edge late[6];
        bool live[6] = {true, true, true, true, true, true};  // a turn-on not cancelled by its turn-off
        int pending[3] = {-1, -1, -1};  // each phase's delayed turn-on in late[]
        int nd = 0, kd = 0, kc = 0;
        const int nc = 2 * n_;
        for (;;) {
            while (kd < nd && !live[kd]) ++kd;
            const double tc = kc < nc ? cmd_[kc].t : inf, td = kd < nd ? late[kd].t : inf;
            const double te = tc < td ? tc : td;
            if (!(te < t_end_)) break;
            const int b0 = level_[0], b1 = level_[1], b2 = level_[2];
            if (tc == te) {
                std::array<double, 3> ia{{0.0, 0.0, 0.0}};
                int kend = kc + 1;
                unsigned mask = 1u << cmd_[kc].x;
                for (; kend < nc && cmd_[kend].t <= te; ++kend) mask |= 1u << cmd_[kend].x;
                if (t_dead_ > 0.0) ia = currents(te - t0_, mask);
                // A turn-on before a turn-off of the same phase (PwmSequencer's order).
                for (; kc < kend; ++kc) {
                    const int x = cmd_[kc].x;
                    if (cmd_[kc].lv > 0) {
                        // i > 0 keeps the lower diode conducting through the dead time.
                        if (t_dead_ > 0.0 && ia[x] > band_) {
                            pending[x] = nd;
                            late[nd++] = {te + t_dead_, x, +1};
                        } else {
                            level_[x] = +1;
                        }
                    } else if (t_dead_ > 0.0 && ia[x] < -band_) {
                        late[nd++] = {te + t_dead_, x, -1};  // if at or after t0 + Ts: not in this period
                    } else {
                        // Turned off at once: a turn-on still in its dead time never happens.
                        if (pending[x] >= kd) live[pending[x]] = false;
                        level_[x] = -1;
                    }
                }
            }
            for (; kd < nd && late[kd].t <= te; ++kd)
                if (live[kd]) level_[late[kd].x] = late[kd].lv;
            if (level_[0] != b0 || level_[1] != b1 || level_[2] != b2) change(te - t0_, level_);
        }
    }

private:
    struct Edge {
        double t;
        int x;   // phase
        int lv;  // the level it sets (commanded: +1 a turn-on, -1 a turn-off)
    };
    // Sorted by time; equal times keep the phase order (as PwmSequencer's insertion).
    void insert(Edge* list, Edge e) const {
        int k = n_;
        while (k > 0 && list[k - 1].t > e.t) {
            list[k] = list[k - 1];
            --k;
        }
        list[k] = e;
    }

    Edge cmd_[6] = {};  // the commanded edges in time order
    int n_ = 0;  // phases with 0 < d < 1
    double t0_ = 0, t_end_ = 0, t_dead_ = 0, band_ = 0;
    std::array<int, 3> level_{{-1, -1, -1}};
};

}  // namespace mcsim
