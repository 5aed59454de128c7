// The plant: flux-linkage state model (4.1)/(4.5) integrated between switching instants (Hermite,
// hermite.hpp; RK4 as the reference and with the outputs disabled), inverter, mechanics and the
// energy ledger. Equations and measured errors:
// docs/plant.md.
#include "mcsim/plant.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "mcsim/centred_pwm.hpp"
#include "mcsim/inverter.hpp"
#include "mcsim/mechanics.hpp"
#include "rotation.hpp"
#include "hermite.hpp"
#include "taylor.hpp"

namespace mcsim {

using detail::rotate_angle;
using detail::rotate_small;

namespace {

constexpr double kPi = 3.14159265358979323846;

// RK4 state: the machine state plus the integrands of the energy ledger and of the period-average
// terminal voltage, so that they are integrated with the same order as the state they belong to
// (the ledger then balances to the integration error, not to a quadrature error on top of it).
struct St {
    double pd, pq, th, w;    // psi_dq [Wb], theta_m [rad], omega_m [rad/s]
    double ein, cu, mech;    // [J] (already x1.5 where it applies)
    double ud, uq;           // integral of u_dq [V s]
};

inline void axpy(St& y, const St& x, double a, const St& k) {
    y.pd = x.pd + a * k.pd;
    y.pq = x.pq + a * k.pq;
    y.th = x.th + a * k.th;
    y.w = x.w + a * k.w;
    y.ein = x.ein + a * k.ein;
    y.cu = x.cu + a * k.cu;
    y.mech = x.mech + a * k.mech;
    y.ud = x.ud + a * k.ud;
    y.uq = x.uq + a * k.uq;
}

}  // namespace

struct Plant::Impl {
    PlantConfig cfg;
    std::unique_ptr<FluxModel> model;
    Mechanics mech;
    PwmSequencer seq;
    CentredPwm cpwm;  // the Taylor path's sequencer (same edges as seq)

    // state
    double t = 0;
    Vec2 psi = Vec2::Zero();
    Vec2 i = Vec2::Zero();  // always model->current(psi) (0 when floating)
    double th = 0, w = 0;
    bool floating = false;
    bool latched[3] = {false, false, false};
    // A phase that starts to conduct from i = 0 when a floating machine's back-EMF exceeds the
    // link: the direction its diode conducts (-1: out of the terminal into the upper diode, +1:
    // in from the lower one), until its current has left the zero band.
    int seed[3] = {0, 0, 0};
    // Open-phase fault: the disconnected phase (-1 none) and its stationary-frame direction
    // (i_x = e_x . i_ab).
    int open = -1;
    Vec2 e_open = Vec2::Zero();

    Vec2 psi0 = Vec2::Zero();
    double w_init = 0;  // W(psi) at the last reset
    EnergyLedger ledger;
    Vec2 u_dq_avg = Vec2::Zero(), u_ab_avg = Vec2::Zero();
    std::array<double, 3> v_avg{{0, 0, 0}};

    // Enabled periods: the Hermite integrator's point and the Jacobian at the period end (kept
    // for the next period while the state is not changed in between).
    detail::HermiteStepper hs;
    Mat2 g_dq = Mat2::Identity();
    bool g_valid = false;
    double c_end = 1, s_end = 0;  // cos, sin of p th after an enabled period
    // The Taylor path: its stepper and whether the model offers the expansion.
    detail::TaylorStepper ts;
    Mat2 g_tay = Mat2::Identity();  // di/dpsi at its expansion point (this period's)
    bool taylor_ok = false;
    bool cs_end_valid = false;
    unsigned cs_carried = 0;

    // per-period constants used by the stages
    double p = 1, rs = 0, th_base = 0, c0 = 1, s0 = 0;
    double th_step = 0, c_step = 1, s_step = 0;  // angle at the start of the current RK4 step
    Vec2 u_ab = Vec2::Zero();

    Impl(const PlantConfig& c, std::unique_ptr<FluxModel> m)
        : cfg(c), model(std::move(m)), mech(c.mech), hs(*model, mech, c.machine.pole_pairs, c.machine.rs),
          ts(mech, c.machine.pole_pairs, c.machine.rs) {
        Vec2 i0;
        Mat2 g0;
        double k[4];
        taylor_ok = model->current_taylor(model->flux(Vec2::Zero()), &i0, &g0, k);
    }

    void sincos_at(double theta_m, double* c, double* s) const {
        rotate_angle(c0, s0, p * (theta_m - th_base), c, s);
    }

    std::array<double, 3> phase_currents() const {
        double c, s;
        rotate_small(c_step, s_step, p * (th - th_step), &c, &s);  // th is near the last step start
        return inverse_clarke(Vec2(c * i.x() - s * i.y(), s * i.x() + c * i.y()));
    }

    // (4.1) in the rotor frame with the stationary-frame voltage u_ab rotated by the stage angle.
    void deriv(const St& x, const Vec2& ii, double tau, St& dx) const {
        double c, s;
        rotate_small(c_step, s_step, p * (x.th - th_step), &c, &s);
        const double we = p * x.w;
        double ud, uq;
        if (floating) {
            // Open terminals with zero current: the terminal voltage is the speed voltage of the
            // held flux, d psi/dt = 0.
            ud = -we * x.pq;
            uq = we * x.pd;
            dx.pd = dx.pq = 0.0;
        } else {
            ud = c * u_ab.x() + s * u_ab.y();
            uq = -s * u_ab.x() + c * u_ab.y();
            if (open >= 0) open_phase_voltage(x, ii, c, s, we, &ud, &uq);
            dx.pd = ud - rs * ii.x() + we * x.pq;
            dx.pq = uq - rs * ii.y() - we * x.pd;
        }
        const double te = 1.5 * p * (x.pd * ii.y() - x.pq * ii.x());
        dx.th = x.w;
        dx.w = mech.accel(tau, te, x.w);
        dx.ein = 1.5 * (ud * ii.x() + uq * ii.y());
        dx.cu = 1.5 * rs * ii.squaredNorm();
        dx.mech = te * x.w;
        dx.ud = ud;
        dx.uq = uq;
    }

    // Open phase: the terminal voltage's component along the open phase's direction e (rotor
    // frame e_r) is not the inverter's but whatever keeps e_r . i = 0: from
    // d/dt (e_r . i) = -w_e n_r . i + e_r . G (u_n n_r + lambda e_r - Rs i - w_e J psi) = 0,
    // n_r = J e_r, u_n = n_r . u (set by the two connected phases only). The constraint drifts
    // by the integration error; project_open() removes that at the period end.
    void open_phase_voltage(const St& x, const Vec2& ii, double c, double s, double we, double* ud,
                            double* uq) const {
        const Vec2 er(c * e_open.x() + s * e_open.y(), -s * e_open.x() + c * e_open.y());
        const Vec2 nr(-er.y(), er.x());
        const double un = nr.x() * *ud + nr.y() * *uq;
        const Mat2 g = model->di_dpsi(Vec2(x.pd, x.pq));
        const Vec2 b(-rs * ii.x() + we * x.pq, -rs * ii.y() - we * x.pd);
        const double den = er.dot(g * er);
        const double lam = den > 0.0 ? (we * nr.dot(ii) - er.dot(g * (un * nr + b))) / den : 0.0;
        *ud = un * nr.x() + lam * er.x();
        *uq = un * nr.y() + lam * er.y();
    }

    // Open phase: move psi along e_r (Newton on e_r . current(psi) = 0) so that the open phase's
    // current is 0 to round-off; returns the change of the three-phase magnetic energy [J].
    double project_open() {
        if (open < 0 || floating) return 0.0;
        const double c = std::cos(p * th), s = std::sin(p * th);
        const Vec2 er(c * e_open.x() + s * e_open.y(), -s * e_open.x() + c * e_open.y());
        const double w0 = model->energy(psi);
        for (int it = 0; it < 30; ++it) {
            const double r = er.dot(i);
            if (std::fabs(r) <= 1e-13 * (1.0 + i.norm())) break;
            const double den = er.dot(model->di_dpsi(psi) * er);
            if (!(den > 0.0)) break;
            psi -= er * (r / den);
            i = model->current(psi);
        }
        g_valid = false;
        return 1.5 * (model->energy(psi) - w0);
    }

    Vec2 current_of(double pd, double pq) const {
        return floating ? Vec2::Zero() : model->current(Vec2(pd, pq));
    }

    // Classical RK4 from tau to tau+h with the voltage u_ab held (stationary frame).
    void rk4(St& x, double tau, double h) {
        St k1, k2, k3, k4, y;
        th_step = x.th;
        sincos_at(th_step, &c_step, &s_step);
        deriv(x, i, tau, k1);
        axpy(y, x, 0.5 * h, k1);
        deriv(y, current_of(y.pd, y.pq), tau + 0.5 * h, k2);
        axpy(y, x, 0.5 * h, k2);
        deriv(y, current_of(y.pd, y.pq), tau + 0.5 * h, k3);
        axpy(y, x, h, k3);
        deriv(y, current_of(y.pd, y.pq), tau + h, k4);
        const double a = h / 6.0;
        x.pd += a * (k1.pd + 2 * k2.pd + 2 * k3.pd + k4.pd);
        x.pq += a * (k1.pq + 2 * k2.pq + 2 * k3.pq + k4.pq);
        x.th += a * (k1.th + 2 * k2.th + 2 * k3.th + k4.th);
        x.w += a * (k1.w + 2 * k2.w + 2 * k3.w + k4.w);
        x.ein += a * (k1.ein + 2 * k2.ein + 2 * k3.ein + k4.ein);
        x.cu += a * (k1.cu + 2 * k2.cu + 2 * k3.cu + k4.cu);
        x.mech += a * (k1.mech + 2 * k2.mech + 2 * k3.mech + k4.mech);
        x.ud += a * (k1.ud + 2 * k2.ud + 2 * k3.ud + k4.ud);
        x.uq += a * (k1.uq + 2 * k2.uq + 2 * k3.uq + k4.uq);
        psi = Vec2(x.pd, x.pq);
        th = x.th;
        w = x.w;
        i = current_of(x.pd, x.pq);
    }

    // One interval with constant phase voltages v (to the DC midpoint), n RK4 steps.
    void interval(St& x, double tau0, double tau1, const std::array<double, 3>& v, int n) {
        const double len = tau1 - tau0;
        if (!(len > 0.0)) return;
        u_ab = clarke_phase_voltages(v);
        for (int k = 0; k < 3; ++k) v_avg[k] += v[k] * len;
        u_ab_avg += u_ab * len;
        const double h = len / n;
        for (int k = 0; k < n; ++k) rk4(x, tau0 + k * h, h);
    }

    int steps_for(double len, double h_max) const {
        if (len <= h_max * (1.0 + 1e-9)) return 1;  // nearly always: skips the libm ceil
        const int n = static_cast<int>(std::ceil(len / h_max - 1e-9));
        return n < 1 ? 1 : n;
    }

    std::array<double, 3> switched_voltages(const std::array<int, 3>& lv, const std::array<double, 3>& ia) const {
        const double half = 0.5 * cfg.inverter.vdc;
        std::array<double, 3> v{{lv[0] * half, lv[1] * half, lv[2] * half}};
        if (cfg.inverter.v_device != 0.0)
            for (int k = 0; k < 3; ++k) v[k] -= device_drop(ia[k], cfg.inverter);
        return v;
    }

    // Bound on |di_x/dt| over this period, for the dead-time decisions taken ahead of their edge
    // (PwmSequencer::predecide; the Taylor path's start-current shortcut). From (4.1) in the
    // stationary frame: di_ab/dt = R(theta) (G (u - Rs i - w_e J psi) + w_e J i), G = di/dpsi (g:
    // exact at the period start on the Hermite path, at mid-period on the Taylor path),
    // |u_ab| <= 2/3 (vdc + 2 v_device) (phase voltages within the rails and one device drop
    // beyond them), |di_x/dt| <= |di_ab/dt|, |G|_2 <= |G|_1; x2 margin for the change of G
    // (saturation) and of the state in the period.
    double current_rate_bound(const Mat2& g) const {
        const double gn = std::max(std::fabs(g(0, 0)) + std::fabs(g(0, 1)), std::fabs(g(1, 0)) + std::fabs(g(1, 1)));
        const double we = std::fabs(p * w);
        const double in = i.norm();
        const double u_max = (2.0 / 3.0) * (cfg.inverter.vdc + 2.0 * std::fabs(cfg.inverter.v_device));
        return 2.0 * (gn * (u_max + rs * in + we * psi.norm()) + we * in);
    }

    // Enabled periods (hermite.hpp): start from the rotor-frame state, end by re-evaluating the
    // model at the final flux so that i = current(psi) holds exactly between periods.
    void hermite_begin() {  // th is the period's base angle here: its cos, sin are c0, s0
        if (!g_valid) model->current_jacobian(psi, &i, &g_dq);
        hs.begin(psi, i, g_dq, th, w, c0, s0, cfg.energy_ledger);
    }

    void hermite_end() {
        const auto& pt = hs.point();
        psi = hs.psi_dq();
        th = pt.th;
        w = pt.w;
        model->current_jacobian(psi, &i, &g_dq);
        g_valid = true;
        c_end = pt.c;
        s_end = pt.s;
        cs_end_valid = true;
    }

    void hermite_intervals(double tau0, double tau1, const std::array<double, 3>& v, int n) {
        const Vec2 u = clarke_phase_voltages(v);
        const double len = tau1 - tau0;
        if (!(len > 0.0)) return;
        if (cfg.energy_ledger) {
            for (int k = 0; k < 3; ++k) v_avg[k] += v[k] * len;
            u_ab_avg += u * len;
        }
        if (n == 1) {
            hs.interval(tau0, tau1, u.x(), u.y());
            return;
        }
        const double h = len / n;
        for (int k = 0; k < n; ++k) hs.interval(tau0 + k * h, k + 1 == n ? tau1 : tau0 + (k + 1) * h, u.x(), u.y());
    }

    // Outputs enabled, Taylor path (taylor.hpp): the period's voltage intervals recorded in one
    // pass (a commanded edge decided with the current predicted for its instant; only a voltage
    // change ends an interval), then integrated at once. The model is evaluated twice: the
    // expansion at mid-period and the exact current at the end.
    void taylor_period(double t0, double Ts, const std::array<double, 3>& duty) {
        const InverterConfig& inv = cfg.inverter;
        const double half = 0.5 * inv.vdc;
        const std::array<double, 3> none{{0.0, 0.0, 0.0}};
        {
            // The duties' mean voltage (zero currents: no dead-time term; no device drop here).
            detail::TaylorAnchor a;
            a.psi = ts.begin(psi, i, th, w, c0, s0, clarke_phase_voltages(averaged_phase_voltages(duty, none, inv, Ts)), Ts);
            model->current_taylor(a.psi, &a.i, &g_tay, a.k);
            a.gdd = g_tay(0, 0);
            a.gdq = g_tay(0, 1);
            a.gqq = g_tay(1, 1);
            ts.expand_about(a);
        }
        auto u_of = [half](const std::array<int, 3>& lv) {
            return clarke_phase_voltages({lv[0] * half, lv[1] * half, lv[2] * half});
        };
        if (inv.mode == InverterConfig::Mode::Averaged) {
            const auto i_start = ts.predict_phase_currents(0.0, Vec2::Zero());
            ts.add_interval(Ts, clarke_phase_voltages(averaged_phase_voltages(duty, i_start, inv, Ts)));
        } else {
            cpwm.begin(t0, Ts, duty, inv);
            Vec2 u = u_of(cpwm.levels());
            // A dead-time decision only asks whether the phase current is above +i_zero_band (a
            // turn-on) or below -i_zero_band (a turn-off). Where the start current is farther
            // from the band than the current can move by then (current_rate_bound, plus 1 mA for
            // the prediction's own error, ~1e-6 A), its sign answers: same decision, no prediction.
            const std::array<double, 3> i0 = inverse_clarke(Vec2(c0 * i.x() - s0 * i.y(), s0 * i.x() + c0 * i.y()));
            const double rate = inv.t_dead > 0.0 ? current_rate_bound(g_tay) : 0.0;
            auto currents = [&](double tau, unsigned mask) {
                const double reach = inv.i_zero_band + 1e-3 + rate * tau;
                for (int x = 0; x < 3; ++x)
                    if ((mask >> x & 1u) && !(std::fabs(i0[x]) > reach)) return ts.predict_phase_currents(tau, u);
                return i0;
            };
            cpwm.walk(currents, [&](double tau, const std::array<int, 3>& lv) {
                ts.add_interval(tau, u);  // u held from the last change to tau
                u = u_of(lv);
            });
            ts.add_interval(Ts, u);
        }
        ts.integrate(Ts);
        const detail::TaylorStepper::End e = ts.finish(Ts);
        psi = e.psi_dq;
        th = e.theta_m;
        w = e.omega_m;
        i = model->current(psi);
        g_valid = false;  // the Hermite path keeps its own Jacobian
        c_end = e.c;
        s_end = e.s;
        cs_end_valid = true;
    }

    // Outputs enabled: the period's voltage intervals (switching edges with dead time, or the
    // averaged voltages) integrated by Hermite (or RK4 on request) into x's ledger fields.
    void enabled_period(St& x, double t0, double Ts, const std::array<double, 3>& duty) {
        const InverterConfig& inv = cfg.inverter;
        // Taylor: no energy ledger and no device drop on that path (docs/plant.md); otherwise
        // (and for tables) the period goes edge by edge.
        if (cfg.integrator == PlantConfig::Integrator::Taylor && taylor_ok && !cfg.energy_ledger &&
            inv.v_device == 0.0 && open < 0) {
            taylor_period(t0, Ts, duty);
            return;
        }
        // Hermite by default; classical RK4 on request (the independent reference of the tests)
        // and with an open phase (its constraint lives in deriv()).
        const bool rk4 = cfg.integrator == PlantConfig::Integrator::Rk4 || open >= 0;
        if (rk4) {
            g_dq = model->di_dpsi(psi);
            g_valid = false;
        } else {
            hermite_begin();
        }
        auto currents = [&] { return rk4 ? phase_currents() : hs.phase_currents(); };
        auto advance = [&](double a, double b, const std::array<double, 3>& v, int n) {
            if (rk4) interval(x, a, b, v, n);
            else hermite_intervals(a, b, v, n);
        };
        if (inv.mode == InverterConfig::Mode::Averaged) {
            advance(0.0, Ts, averaged_phase_voltages(duty, currents(), inv, Ts), cfg.substeps);
        } else {
            const double h_max = Ts / cfg.substeps;
            seq.begin(t0, Ts, duty, inv);
            const double di_max = inv.t_dead > 0.0 ? current_rate_bound(g_dq) : 0.0;
            const bool pre = cfg.predecide_edges;
            if (pre) seq.predecide(t0, currents(), di_max);
            double tau = 0.0, te;
            const bool drop = inv.v_device != 0.0;
            const std::array<double, 3> none{{0.0, 0.0, 0.0}};  // what the decided edges need
            while (seq.next_time(&te)) {
                const double tau_e = te - t0;
                if (tau_e > tau) {
                    advance(tau, tau_e, switched_voltages(seq.levels(), drop ? currents() : none),
                            steps_for(tau_e - tau, h_max));
                    tau = tau_e;
                }
                if (seq.all_decided()) {
                    seq.apply(te, none);
                    continue;
                }
                const auto ia = currents();
                seq.apply(te, ia);
                if (pre) seq.predecide(te, ia, di_max);
            }
            advance(tau, Ts, switched_voltages(seq.levels(), drop ? currents() : none), steps_for(Ts - tau, h_max));
        }
        if (!rk4) finish_hermite(x);
    }

    void finish_hermite(St& x) {
        hermite_end();
        const detail::HLedger& led = hs.ledger();
        x.ein = led.ein;
        x.cu = led.cu;
        x.mech = led.mech;
        x.ud = led.ud;
        x.uq = led.uq;
    }

    // Floating terminals clamp again once the back-EMF's line-to-line peak exceeds the link plus
    // two diode drops: the phases with the largest and smallest back-EMF conduct (uncontrolled
    // generation into the link), the third stays open.
    void reconduct() {
        double c, s;
        sincos_at(th, &c, &s);
        const double we = p * w;
        const Vec2 e_dq(-we * psi.y(), we * psi.x());
        const auto e = inverse_clarke(Vec2(c * e_dq.x() - s * e_dq.y(), s * e_dq.x() + c * e_dq.y()));
        int hi = 0, lo = 0;
        for (int k = 1; k < 3; ++k) {
            if (e[k] > e[hi]) hi = k;
            if (e[k] < e[lo]) lo = k;
        }
        if (!(e[hi] - e[lo] > cfg.inverter.vdc + 2.0 * std::fabs(cfg.inverter.v_device))) return;
        floating = false;
        latched[0] = latched[1] = latched[2] = true;
        latched[hi] = latched[lo] = false;
        seed[0] = seed[1] = seed[2] = 0;
        seed[hi] = -1;   // out of the terminal with the highest back-EMF, into the upper diode
        seed[lo] = +1;   // into the one with the lowest, from the lower diode
        i = model->current(psi);
    }

    void go_floating(St& x) {
        // Snap the residual current (below the zero band) to exactly 0: the energy it held goes
        // back to the DC link through the diodes, booked as (negative) electrical input.
        const double dw = 1.5 * (model->energy(psi0) - model->energy(psi));
        x.ein += dw;
        psi = psi0;
        x.pd = psi0.x();
        x.pq = psi0.y();
        floating = true;
        i = Vec2::Zero();
    }

    void disabled_period(St& x, double Ts) {
        // All switches off. Conducting phases are clamped by their diodes; a phase whose current
        // reaches 0 is latched open. Simplification (docs/plant.md): an open phase is given the
        // voltage that cancels its speed voltage, 1.5 e_x + (sum of the others)/2, which keeps its
        // current near 0 for a non-salient machine; once two phases are open the third carries
        // no current either and the terminals float (psi = flux(0), i = 0). Valid while the
        // back-EMF line-to-line peak stays below Vdc (otherwise the diodes would conduct again).
        const int n = cfg.substeps * 8 > 32 ? cfg.substeps * 8 : 32;
        const double h = Ts / n;
        double tau = 0.0;
        auto count_latched = [&] { return int(latched[0]) + int(latched[1]) + int(latched[2]); };
        while (tau < Ts * (1 - 1e-12)) {
            if (floating && open < 0) reconduct();
            if (!floating) {
                const auto ia = phase_currents();
                for (int k = 0; k < 3; ++k) {
                    if (seed[k] != 0 && std::fabs(ia[k]) > cfg.inverter.i_zero_band) seed[k] = 0;
                    if (seed[k] == 0 && std::fabs(ia[k]) <= cfg.inverter.i_zero_band) latched[k] = true;
                }
                if (count_latched() >= 2) go_floating(x);
            }
            const double step = std::min(h, Ts - tau);
            if (floating) {
                // Mechanics only; the voltage average is the speed voltage (see deriv).
                const St x0 = x;
                rk4(x, tau, step);
                double c, s;
                sincos_at(th - 0.5 * step * w, &c, &s);
                const double ud = (x.ud - x0.ud) / step, uq = (x.uq - x0.uq) / step;
                const Vec2 uab(c * ud - s * uq, s * ud + c * uq);
                u_ab_avg += uab * step;
                const auto vabc = inverse_clarke(uab);
                for (int k = 0; k < 3; ++k) v_avg[k] += vabc[k] * step;
                tau += step;
                continue;
            }
            const auto ia = phase_currents();
            std::array<double, 3> v{};
            double sum_conducting = 0.0;
            for (int k = 0; k < 3; ++k) {
                if (latched[k]) continue;
                // a seeded phase conducts the way its back-EMF drives it, also at i = 0
                v[k] = seed[k] == 0 ? diode_phase_voltage(ia[k], cfg.inverter)
                                    : diode_phase_voltage(seed[k] * 2.0 * cfg.inverter.i_zero_band, cfg.inverter);
                sum_conducting += v[k];
            }
            if (count_latched() == 1) {
                double c, s;
                sincos_at(th, &c, &s);
                const double we = p * w;
                const Vec2 e_dq(-we * psi.y(), we * psi.x());
                const auto e = inverse_clarke(Vec2(c * e_dq.x() - s * e_dq.y(), s * e_dq.x() + c * e_dq.y()));
                for (int k = 0; k < 3; ++k)
                    if (latched[k]) {
                        // An open terminal cannot leave the rails without its diode conducting.
                        const double half = 0.5 * cfg.inverter.vdc;
                        v[k] = std::max(-half, std::min(half, 1.5 * e[k] + 0.5 * sum_conducting));
                    }
            }
            // Trial step; if a conducting phase current changes sign, redo up to the secant
            // estimate of its zero crossing and latch it there.
            const St xs = x;
            const Vec2 psis = psi, is = i;
            const double ths = th, ws = w;
            const auto vs_avg = v_avg;
            const Vec2 uab_s = u_ab_avg;
            interval(x, tau, tau + step, v, 1);
            const auto ib = phase_currents();
            double frac = 1.0;
            int who = -1;
            for (int k = 0; k < 3; ++k) {
                if (latched[k] || ia[k] * ib[k] > 0.0) continue;
                if (seed[k] != 0 && ib[k] * seed[k] > 0.0) continue;   // leaving 0 the seeded way
                const double f = ia[k] / (ia[k] - ib[k]);
                if (f < frac) {
                    frac = f;
                    who = k;
                }
            }
            if (who >= 0 && frac < 1.0) {
                x = xs;
                psi = psis;
                i = is;
                th = ths;
                w = ws;
                v_avg = vs_avg;
                u_ab_avg = uab_s;
                const double part = std::max(frac, 1e-6) * step;
                interval(x, tau, tau + part, v, 1);
                tau += part;
            } else {
                tau += step;
            }
            if (who >= 0) latched[who] = true;
        }
    }
};

Plant::Plant(const PlantConfig& cfg, std::unique_ptr<FluxModel> model) {
    if (!model) throw std::invalid_argument("Plant: null FluxModel");
    if (cfg.substeps < 1) throw std::invalid_argument("Plant: substeps must be >= 1");
    if (cfg.machine.pole_pairs < 1) throw std::invalid_argument("Plant: pole_pairs must be >= 1");
    impl_ = std::make_shared<Impl>(cfg, std::move(model));
    Impl& m = *impl_;
    m.p = cfg.machine.pole_pairs;
    m.rs = cfg.machine.rs;
    m.psi0 = m.model->flux(Vec2::Zero());
    reset_state(m.psi0, cfg.theta_m0, cfg.omega_m0);
}

void Plant::reset_state(const Vec2& psi_dq, double theta_m, double omega_m) {
    Impl& m = *impl_;
    m.psi = psi_dq;
    m.th = theta_m;
    m.w = m.cfg.mech.locked ? 0.0 : omega_m;
    m.floating = false;
    m.g_valid = false;
    m.cs_end_valid = false;
    m.latched[0] = m.latched[1] = m.latched[2] = false;
    m.seed[0] = m.seed[1] = m.seed[2] = 0;
    m.i = m.model->current(psi_dq);
    m.w_init = m.model->energy(psi_dq);
    m.ledger = EnergyLedger{};
}

void Plant::step_period(double Ts, const std::array<double, 3>& duty, bool outputs_enabled) {
    if (!(Ts > 0.0)) throw std::invalid_argument("Plant::step_period: Ts must be > 0");
    Impl& m = *impl_;
    const double t0 = m.t;
    if (m.cfg.vdc_profile) m.cfg.inverter.vdc = std::max(0.0, m.cfg.vdc_profile(t0 + 0.5 * Ts));
    const double w_start = m.mech.begin_period(t0, Ts, m.w);
    if (m.mech.speed_imposed()) m.w = w_start;
    m.th_base = m.th_step = m.th;
    if (m.cs_end_valid && (++m.cs_carried & 63) != 0) {
        // The integrator's rotated pair (to round-off); libm re-bases it every 64th period.
        m.c0 = m.c_step = m.c_end;
        m.s0 = m.s_step = m.s_end;
    } else {
        m.c0 = m.c_step = std::cos(m.p * m.th);
        m.s0 = m.s_step = std::sin(m.p * m.th);
    }
    m.v_avg = {0.0, 0.0, 0.0};
    m.u_ab_avg = Vec2::Zero();
    St x{m.psi.x(), m.psi.y(), m.th, m.w, 0, 0, 0, 0, 0};

    if (outputs_enabled && m.floating) {
        m.floating = false;
        m.i = m.model->current(m.psi);
    }
    if (outputs_enabled) m.latched[0] = m.latched[1] = m.latched[2] = false;
    if (outputs_enabled) m.seed[0] = m.seed[1] = m.seed[2] = 0;
    if (m.open >= 0) m.latched[m.open] = true;  // disabled periods: that phase is open anyway

    m.cs_end_valid = false;
    if (!outputs_enabled) {
        m.g_valid = false;
        m.disabled_period(x, Ts);
    } else {
        m.enabled_period(x, t0, Ts, duty);
    }

    m.t = t0 + Ts;
    if (m.mech.speed_imposed()) m.w = m.mech.omega_end();
    x.ein += m.project_open();
    const double inv_ts = 1.0 / Ts;
    m.u_dq_avg = Vec2(x.ud, x.uq) * inv_ts;
    m.u_ab_avg *= inv_ts;
    for (double& v : m.v_avg) v *= inv_ts;
    m.ledger.electrical_in += x.ein;
    m.ledger.copper_loss += x.cu;
    m.ledger.mech_out += x.mech;
    if (m.cfg.energy_ledger || !outputs_enabled || m.cfg.integrator == PlantConfig::Integrator::Rk4 || m.open >= 0)
        m.ledger.magnetic = 1.5 * (m.model->energy(m.psi) - m.w_init);
}

double Plant::time() const { return impl_->t; }
Vec2 Plant::psi_dq() const { return impl_->psi; }
Vec2 Plant::i_dq() const { return impl_->i; }
std::array<double, 3> Plant::i_abc() const {
    const Impl& m = *impl_;
    double c, s;
    if (m.cs_end_valid) {  // cos, sin of p theta_m carried by the integrator to the period end
        c = m.c_end;
        s = m.s_end;
    } else {
        c = std::cos(m.p * m.th);
        s = std::sin(m.p * m.th);
    }
    return inverse_clarke(Vec2(c * m.i.x() - s * m.i.y(), s * m.i.x() + c * m.i.y()));
}
double Plant::theta_e() const {
    const double a = impl_->p * impl_->th;
    if (a >= -kPi && a < kPi) return a;
    // Number of turns by truncation (no libm): exact enough for |a| < 1e12 rad.
    double x = (a + kPi) * (0.5 / kPi);
    if (!(std::fabs(x) < 9.0e18)) {
        // A diverged state (NaN, inf, or beyond long long turns): the integer conversion below would
        // be UB. NaN stays NaN (the metrics show null); a huge finite angle has no digits left.
        if (!std::isfinite(a)) return std::numeric_limits<double>::quiet_NaN();
        double r = std::fmod(a + kPi, 2.0 * kPi);
        if (r < 0) r += 2.0 * kPi;
        return r - kPi;
    }
    double turns = static_cast<double>(static_cast<long long>(x));
    if (turns > x) turns -= 1.0;
    double r = a - turns * (2.0 * kPi);
    if (r >= kPi) r -= 2.0 * kPi;
    if (r < -kPi) r += 2.0 * kPi;
    return r;
}
double Plant::theta_m() const { return impl_->th; }
double Plant::omega_m() const { return impl_->w; }
double Plant::omega_e() const { return impl_->p * impl_->w; }
double Plant::torque() const {
    const Impl& m = *impl_;
    return 1.5 * m.p * (m.psi.x() * m.i.y() - m.psi.y() * m.i.x());
}
Vec2 Plant::u_dq_avg_last() const { return impl_->u_dq_avg; }
Vec2 Plant::u_ab_avg_last() const { return impl_->u_ab_avg; }
std::array<double, 3> Plant::v_phase_avg_last() const { return impl_->v_avg; }
Vec2 Plant::psi_no_current() const { return impl_->psi0; }
bool Plant::floating() const { return impl_->floating; }
const EnergyLedger& Plant::energy() const { return impl_->ledger; }
const PlantConfig& Plant::config() const { return impl_->cfg; }
const FluxModel& Plant::model() const { return *impl_->model; }
void Plant::set_vdc(double vdc) { impl_->cfg.inverter.vdc = vdc; }

void Plant::set_open_phase(int phase) {
    Impl& m = *impl_;
    if (phase < -1 || phase > 2) throw std::invalid_argument("Plant::set_open_phase: phase must be -1..2");
    m.open = phase;
    if (phase < 0) return;
    const double a = phase * (2.0 * kPi / 3.0);
    m.e_open = Vec2(std::cos(a), std::sin(a));
    m.cs_end_valid = false;
    const double dw = m.project_open();  // the snap: the released energy goes into the break
    m.ledger.electrical_in += dw;
    m.ledger.magnetic = 1.5 * (m.model->energy(m.psi) - m.w_init);
}

int Plant::open_phase() const { return impl_->open; }

std::array<double, 3> Plant::i_abc_ahead(double delta, double Ts, const std::array<double, 3>& duty,
                                         bool outputs_enabled) const {
    const Impl& m = *impl_;
    if (!(delta > 0.0) || !outputs_enabled || m.floating) return i_abc();
    const InverterConfig& inv = m.cfg.inverter;
    const double c = std::cos(m.p * m.th), s = std::sin(m.p * m.th);
    auto rot = [c, s](const Vec2& v) { return Vec2(c * v.x() - s * v.y(), s * v.x() + c * v.y()); };
    const Vec2 i_ab = rot(m.i), psi_ab = rot(m.psi);
    const std::array<double, 3> i0 = inverse_clarke(i_ab);
    // Voltage-time integral of each phase over [0, delta]: low, high from the (dead-time delayed)
    // rise to the (delayed) fall, as the sequencer decides with the current at the boundary.
    const double half = 0.5 * inv.vdc, td = inv.t_dead > 0.0 ? inv.t_dead : 0.0;
    std::array<double, 3> vt{};
    for (int k = 0; k < 3; ++k) {
        const double d = std::max(0.0, std::min(1.0, duty[k]));
        double high = 0.0;
        if (d >= 1.0) {
            high = delta;
        } else if (d > 0.0) {
            double rise = 0.5 * (1.0 - d) * Ts, fall = 0.5 * (1.0 + d) * Ts;
            if (i0[k] > inv.i_zero_band) rise += td;
            if (i0[k] < -inv.i_zero_band) fall = std::min(fall + td, Ts);
            if (rise < fall) high = std::max(0.0, std::min(delta, fall) - rise);
        }
        vt[k] = -half * delta + 2.0 * half * high - device_drop(i0[k], inv) * delta;
    }
    const Mat2 g = m.model->di_dpsi(m.psi);
    Mat2 r;
    r << c, -s, s, c;
    const Mat2 a = r * g * r.transpose();
    const double we = m.p * m.w;
    const Vec2 j_i(-i_ab.y(), i_ab.x()), j_psi(-psi_ab.y(), psi_ab.x());
    Vec2 di = a * (clarke_phase_voltages(vt) - delta * m.rs * i_ab) + delta * we * (j_i - a * j_psi);
    if (m.open >= 0) {  // the open phase's terminal voltage keeps its current at 0
        const double den = m.e_open.dot(a * m.e_open);
        if (den > 0.0) di -= (a * m.e_open) * (m.e_open.dot(di) / den);
    }
    std::array<double, 3> out = inverse_clarke(i_ab + di);
    if (m.open >= 0) out[m.open] = 0.0;
    return out;
}

}  // namespace mcsim
