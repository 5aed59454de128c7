#include "runner.hpp"

#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "drive_setup.hpp"
#include "can_link.hpp"
#include "drive_target.hpp"
#include "metrics.hpp"
#include "mcsim/fluxmap.hpp"
#include "mcsim/fluxmap_file.hpp"
#include "mcsim/plant.hpp"
#include "mcsim/sensors.hpp"

extern "C" {
#include "hal_host/host.h"
#include "mc/drive.h"
}

namespace mcsim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRpm = 60.0 / (2.0 * kPi);  // rad/s -> rpm

double wrap_pi(double x)
{
    x = std::fmod(x + kPi, 2.0 * kPi);
    if (x < 0) x += 2.0 * kPi;
    return x - kPi;
}

const char* state_name(mc_state_t s)
{
    switch (s) {
    case MC_STATE_IDLE: return "IDLE";
    case MC_STATE_OFFSET_CAL: return "OFFSET_CAL";
    case MC_STATE_RUN: return "RUN";
    case MC_STATE_FAULT: return "FAULT";
    case MC_STATE_INIT_POS: return "INIT_POS";
    case MC_STATE_FAULT_REACTION: return "FAULT_REACTION";
    }
    return "?";
}

// Step II's verdict (mc/polarity.h), "" when Step II did not run
const char* step2_verdict_name(unsigned v)
{
    switch (v) {
    case MC_POL_DECIDED: return "decided";
    case MC_POL_UNDECIDED: return "undecided";
    case MC_POL_NO_DATA: return "no_data";
    case MC_POL_ABORTED: return "aborted";
    default: return "";
    }
}

std::vector<std::string> fault_names(uint32_t f);

std::vector<std::string> fault_names(uint32_t f)
{
    // the fault table's names (mc/faults.h), in bit order; a bit without a row has no name
    std::vector<std::string> out;
#define MC_FAULT_NAME_(NAME, bit, name, emcy, reg, reaction, rec, doc) \
    if (f & MC_FAULT_##NAME) out.push_back(name);
    MC_FAULTS(MC_FAULT_NAME_)
#undef MC_FAULT_NAME_
    return out;
}

std::unique_ptr<FluxModel> make_plant_model(const Scenario& sc, const MachineParams& mp)
{
    const std::string& kind = sc.s("machine.model");
    if (kind == "linear") return make_linear_model(mp.ld, mp.lq, mp.psi_pm);
    // a measured map is the plant itself for "analytic" and "table" (there is no closed form)
    if (mp.flux_map) return make_preset_model(mp);
    auto analytic = make_analytic_model(mp.sat);
    if (kind == "analytic") return analytic;
    const int n = static_cast<int>(sc.i("machine.table_points"));
    FluxMapGridSpec grid = default_flux_map_grid(std::max(mp.i_rated_peak, 1.0), n);
    return make_table_model_from(*analytic, grid);
}

// The plant-side defaults that follow the preset; the drive's own come from the firmware.
struct Resolved {
    MachineParams mp;
    double vdc, ts, inertia, friction, i_span, vdc_span;
    Profile vdc_profile;               // inverter.vdc_v (constant: the preset's nominal)
    double vdc_ripple, vdc_ripple_hz;  // inverter.vdc_ripple_v (harsh: derived), _hz
    // the DC link at time t: the profile plus the ripple, >= 0
    double vdc_at(double t) const
    {
        double v = vdc_profile.at(t);
        if (vdc_ripple != 0.0) v += vdc_ripple * std::sin(2.0 * kPi * vdc_ripple_hz * t);
        return v > 0.0 ? v : 0.0;
    }
    bool vdc_varies() const { return !vdc_profile.constant() || vdc_ripple != 0.0; }
};

Resolved resolve(const Scenario& sc)
{
    Resolved r;
    try {
        r.mp = load_machine_preset(sc.s("machine.preset"));
    } catch (const std::exception& e) {
        throw ScenarioError(sc.origin() + ": key 'machine.preset' = \"" + message_text(sc.s("machine.preset")) + "\": " + message_text(e.what(), 400, false));
    }
    auto opt = [&](const char* k, double def) { return sc.has(k) ? sc.f(k) : def; };
    // the DC link: a profile; the firmware's nominal (and the sensor span's default) is its t = 0 value
    if (sc.has("inverter.vdc_v")) r.vdc_profile = sc.profile("inverter.vdc_v");
    else r.vdc_profile.pts.push_back({0.0, r.mp.vdc_nominal});
    r.vdc = r.vdc_profile.at(0.0);
    if (!(r.vdc >= 1.0))
        throw ScenarioError(sc.origin() + ": key 'inverter.vdc_v' = " + json_number(r.vdc) +
                            " at t = 0: the DC link must start at 1 V or more (the firmware's nominal DC link is that value)");
    r.vdc_ripple = opt("inverter.vdc_ripple_v", 0.02 * r.vdc);  // not given: harsh (2 % of nominal)
    r.vdc_ripple_hz = sc.f("inverter.vdc_ripple_hz");
    // the preset's sampling frequency (the drive gets the same value through control.ts_s)
    r.ts = opt("control.ts_s", 1.0 / r.mp.f_sample);
    r.inertia = opt("mechanics.inertia_kgm2", r.mp.inertia);
    r.friction = opt("mechanics.friction_nms", r.mp.friction);
    r.i_span = opt("sensors.i_full_scale_a", default_i_full_scale(r.mp));
    r.vdc_span = opt("sensors.vdc_full_scale_v", default_vdc_full_scale(r.vdc));
    return r;
}

// The estimator's flux map: the plant's magnetics tabulated on a regular grid, as an offline
// identification would deliver it (the KIT identifier will replace this later).
//
// Mismatch (estimator.cross_scale = c, applied first): each flux splits into its self part, the
// cut along its own axis, and its cross-saturation part, what the other axis' current adds,
//   psi_d(i_d, i_q) = psi_d(i_d, 0) + c [psi_d(i_d, i_q) - psi_d(i_d, 0)]
//   psi_q(i_d, i_q) = psi_q(0, i_q) + c [psi_q(i_d, i_q) - psi_q(0, i_q)]
// (the cuts are the plant's flux at the node's i_d, resp. i_q; c = 0: no cross-saturation at all,
// and d psi_d / d i_q, d psi_q / d i_d both scale with c, so the map stays reciprocal). Then
// (estimator.psi_scale, l_scale) the magnet part psi_d(0, 0) scales with psi_scale and the
// current-dependent rest psi - psi(0, 0) with l_scale. c = 1 takes the nodes as tabulated.
std::unique_ptr<mc_flux_map_t> make_estimator_map(const FluxModel& m, int n, double span, double l_scale,
                                                  double psi_scale, double cross_scale)
{
    const GridAxis axis{-span, span, n};
    // A measured map is resampled from the map itself (bilinear, with its edge extrapolation), not
    // from the plant's inversion of it: the estimator's model is the map, as with the analytic model.
    const auto* measured = dynamic_cast<const MeasuredMapModel*>(&m);
    auto fwd = [&](const Vec2& i) { return measured ? measured->measured().table.eval(i) : m.flux(i); };
    FluxMapTable t(TableKind::FluxOfCurrent, axis, axis);
    if (measured) {
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) t.set_node(a, b, fwd(Vec2(axis.at(a), axis.at(b))));
    } else {
        t = tabulate_flux_map_cached(m, axis, axis);
    }
    auto map = std::make_unique<mc_flux_map_t>();
    map->n_d = n;
    map->n_q = n;
    map->id0 = map->iq0 = static_cast<float>(-span);
    map->did = map->diq = static_cast<float>(axis.step());
    const Vec2 psi0 = fwd(Vec2::Zero());
    std::vector<Vec2> cut_d, cut_q;  // psi(i_d, 0), psi(0, i_q) at the grid's currents
    if (cross_scale != 1.0) {
        for (int k = 0; k < n; ++k) {
            cut_d.push_back(fwd(Vec2(axis.at(k), 0.0)));
            cut_q.push_back(fwd(Vec2(0.0, axis.at(k))));
        }
    }
    for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
            Vec2 psi = t.node(a, b);
            if (cross_scale != 1.0) {
                psi.x() = cut_d[a].x() + cross_scale * (psi.x() - cut_d[a].x());
                psi.y() = cut_q[b].y() + cross_scale * (psi.y() - cut_q[b].y());
            }
            // mismatch: the magnet part scales with psi_scale, the current-dependent part with l_scale
            map->psi_d[a * n + b] = static_cast<float>(psi_scale * psi0.x() + l_scale * (psi.x() - psi0.x()));
            map->psi_q[a * n + b] = static_cast<float>(l_scale * (psi.y() - psi0.y()));
        }
    }
    return map;
}

class Progress {
public:
    explicit Progress(bool on, double total) : on_(on && isatty(STDERR_FILENO)), total_(total) {}
    void update(double t, double wall)
    {
        if (!on_ || wall - last_ < 0.25) return;
        last_ = wall;
        std::fprintf(stderr, "\r  t = %7.3f / %.3f s  [%3.0f%%]  %6.0fx real time ", t, total_, 100.0 * t / total_,
                     wall > 0 ? t / wall : 0.0);
        std::fflush(stderr);
    }
    void done()
    {
        if (on_) std::fprintf(stderr, "\r%70s\r", "");
    }

private:
    bool on_;
    double total_, last_ = -1;
};

// ---- the steps of a run

PlantConfig plant_config(const Scenario& sc, const Resolved& r)
{
    const MachineParams& mp = r.mp;
    PlantConfig pc;
    pc.machine = mp;
    pc.inverter.mode = sc.s("inverter.mode") == "averaged" ? InverterConfig::Mode::Averaged : InverterConfig::Mode::Switching;
    pc.inverter.vdc = r.vdc;
    if (r.vdc_varies()) pc.vdc_profile = [r](double t) { return r.vdc_at(t); };
    pc.inverter.t_dead = sc.f("inverter.dead_time_s");
    pc.inverter.v_device = sc.f("inverter.device_drop_v");
    const std::string& mech = sc.s("mechanics.mode");
    pc.mech.mode = mech == "dyno" ? MechanicsConfig::Mode::Dyno : MechanicsConfig::Mode::Inertia;
    pc.mech.locked = mech == "locked";
    pc.mech.inertia = r.inertia;
    pc.mech.friction = r.friction;
    const Profile load = sc.profile("mechanics.load_torque_nm");
    const Profile dyno = sc.profile("mechanics.dyno_speed_rpm");
    pc.mech.load_torque = [load](double t) { return load.at(t); };
    pc.mech.reactive_load = sc.s("mechanics.load_kind") == "reactive";
    pc.mech.dyno_speed = [dyno](double t) { return dyno.at(t) / kRpm; };
    pc.theta_m0 = sc.f("mechanics.theta0_deg") * kPi / 180.0 / mp.pole_pairs;
    pc.energy_ledger = false;  // no metric or trace column reads the energy ledger
    const std::string& integ = sc.s("inverter.integrator");
    pc.integrator = integ == "taylor" ? PlantConfig::Integrator::Taylor
                    : integ == "rk4"  ? PlantConfig::Integrator::Rk4
                                      : PlantConfig::Integrator::Hermite;
    pc.omega_m0 = mech == "dyno" ? dyno.at(0.0) / kRpm : (mech == "locked" ? 0.0 : sc.f("mechanics.speed0_rpm") / kRpm);
    return pc;
}

Sensors make_sensors(const Scenario& sc, const Resolved& r)
{
    AdcConfig ac;
    ac.bits = static_cast<int>(sc.i("sensors.adc_bits"));
    ac.i_full_scale = r.i_span;
    ac.i_noise_rms = sc.f("sensors.i_noise_rms_a");
    const auto ge = sc.f3("sensors.i_gain_err"), oe = sc.f3("sensors.i_offset_err_a");
    for (int k = 0; k < 3; ++k) {
        ac.gain_err[k] = ge[k];
        ac.offset_err[k] = oe[k];
    }
    ac.vdc_full_scale = r.vdc_span;
    ac.vdc_noise_rel = sc.f("sensors.vdc_noise_rel");
    ac.delay_s = sc.f("sensors.adc_delay_s");
    EncoderConfig ec;
    ec.lines = static_cast<int>(sc.i("sensors.encoder_lines"));
    ec.offset_rad = sc.f("sensors.encoder_offset_deg") * kPi / 180.0;
    Sensors sensors(ac, ec, static_cast<uint64_t>(sc.i("scenario.seed")));
    SensorFaults sf;
    sf.i_stuck_phase = static_cast<int>(sc.i("faults.i_stuck_phase"));
    sf.i_stuck_from_s = sc.f("faults.i_stuck_from_s");
    sf.i_stuck_a = sc.f("faults.i_stuck_a");
    const auto drift = sc.f3("faults.i_offset_drift_a_per_s");
    for (int k = 0; k < 3; ++k) sf.i_offset_drift_a_per_s[k] = drift[k];
    sf.i_offset_drift_from_s = sc.f("faults.i_offset_drift_from_s");
    sf.encoder_loss_from_s = sc.f("faults.encoder_loss_from_s");
    sensors.set_faults(sf);
    return sensors;
}

// The drive's configuration: the firmware's parameter table, filled from the preset, the
// simulator's sensor keys and the scenario's drive keys (the firmware derives the rest), and the
// estimator's model: the plant's, scaled by the mismatch keys, with its flux map tabulated from
// the plant's magnetics (the map also serves the polarity detection's l_dd profile). Validated
// here, as the firmware will: a refusal is a ScenarioError naming the keys.
DriveSetup drive_setup(const Scenario& sc, const Resolved& r, const FluxModel& magnetics)
{
    const MachineParams& mp = r.mp;
    DriveSetup ds;
    mc_drive_cfg_default(&ds.cfg);
    set_drive_params(sc, mp, r.vdc, r.i_span, r.vdc_span, &ds.cfg.p);
    ds.cfg.est.rs = static_cast<float>(mp.rs * sc.f("estimator.rs_scale"));
    ds.cfg.est.ld = static_cast<float>(mp.ld * sc.f("estimator.l_scale"));
    ds.cfg.est.lq = static_cast<float>(mp.lq * sc.f("estimator.l_scale"));
    ds.cfg.est.psi_pm = static_cast<float>(mp.psi_pm * sc.f("estimator.psi_scale"));
    const mc_angle_src_desc_t* src = mc_angle_src_get(ds.cfg.p.control_angle_source);
    // The machine's flux map is the drive's model of the motor, not only the estimator's: an
    // encoder drive uses it too (the current loop's decoupling, the field-weakening entry law).
    if (src != nullptr) {
        const double span = sc.has("estimator.map_span_a") ? sc.f("estimator.map_span_a") : 1.5 * mp.i_rated_peak;
        try {
            ds.est_map = make_estimator_map(magnetics, static_cast<int>(sc.i("estimator.map_points")), span,
                                            sc.f("estimator.l_scale"), sc.f("estimator.psi_scale"),
                                            sc.f("estimator.cross_scale"));
        } catch (const std::exception& e) {
            throw ScenarioError(sc.origin() + ": key 'estimator.map_span_a' = " + json_number(span) +
                                ": the plant's magnetics cannot be tabulated over this span (" + e.what() + ")");
        }
        ds.cfg.est.map = ds.est_map.get();
    }
    auto built = std::make_unique<mc_drive_built_t>();
    mc_param_err_t err{};
    if (!mc_drive_build(&ds.cfg, built.get(), &err)) throw ScenarioError(explain_config_error(sc, err));
    ds.resolved = built->p;
    ds.estimator = src != nullptr && src->cls == MC_ANGLE_ESTIMATOR;
    if (built->blk.if_on) {
        // what the drive chose at configuration (mc/if_start.h): said once, as a drive would log it
        std::fprintf(stderr,
                     "mcsim: note: the drive runs I/f below %g rpm (startup.if_handover_rpm; %g A, %g rpm/s)%s\n",
                     static_cast<double>(built->p.startup_if_handover_rpm), static_cast<double>(built->p.startup_if_i_a),
                     static_cast<double>(built->p.startup_if_accel_rpm_s),
                     built->blk.if_from_zero ? ", started by I/f: the motor model's saliency is not usable for the "
                                               "injection (or startup.init_pos = if_start)"
                                             : ": the motor model's saliency is not usable for the injection");
        if (sc.s("control.mode") == "torque") {
            // I/f has no speed to ramp to in torque mode: said, not left for the user to find out
            std::fprintf(stderr,
                         "mcsim: note: torque mode below %g rpm on this motor: I/f holds its frame still and the "
                         "torque is NOT controlled there; the estimator takes over once the load turns the rotor above it. "
                         "Use speed mode, an encoder, or run above that speed\n",
                         static_cast<double>(built->p.startup_if_handover_rpm));
        }
    }
    const mc_catch_cfg_t& fc = built->blk.flying;
    if ((built->blk.seq.catch_first || built->blk.prot.recover) && fc.w_limit > 0.0f) {
        // the flying-start catch's shortest pulse at this f_s (drive_config.c, build_catch): said once
        const mc_param_info_t& ts = mc_param_table[MC_PARAM_control_ts_s];
        const double rpm = 60.0 / (2.0 * M_PI * built->p.motor_pole_pairs);
        std::fprintf(stderr,
                     "mcsim: note: the flying-start catch keeps the current within 1.1 x control.i_max_a (%g A) "
                     "only below %.0f rpm: its shortest pulse, one zero-vector period of control.ts_s = %g s "
                     "(range %g..%g s), drives more above it, up to the generation speed; control.ts_s <= %.3g s "
                     "covers every speed%s\n",
                     1.1 * built->p.control_i_max_a, fc.w_limit * rpm, static_cast<double>(built->p.control_ts_s),
                     static_cast<double>(ts.min), static_cast<double>(ts.max), static_cast<double>(fc.ts_cover),
                     fc.ts_cover < ts.min ? " (below the range: startup.catch = off, or a drive with phase-voltage "
                                            "sensing, for rotors turning faster)"
                                          : " (or startup.catch = off)");
    }
    return ds;
}

// Commands from the scenario's profiles, as the background side (CANopen on a target) would send them.
struct Commander {
    mc_mode_t mode;
    Profile speed_ref, torque_ref, id_ref, iq_ref;
    double enable_at, theta_init_err;

    explicit Commander(const Scenario& sc)
        : speed_ref(sc.profile("control.speed_ref_rpm")), torque_ref(sc.profile("control.torque_ref_nm")),
          id_ref(sc.profile("control.id_ref_a")), iq_ref(sc.profile("control.iq_ref_a")),
          enable_at(sc.f("control.enable_at_s")), theta_init_err(sc.f("estimator.theta0_err_deg") * kPi / 180.0)
    {
        const std::string& m = sc.s("control.mode");
        mode = m == "current" ? MC_MODE_CURRENT : (m == "torque" ? MC_MODE_TORQUE : MC_MODE_SPEED);
    }
    // The angle handed over with the enable (startup.init_pos = given): the true one plus the
    // scenario's error; the drive reads it only at the enable edge.
    mc_drive_cmd_t at(double t, double theta_true) const
    {
        mc_drive_cmd_t cmd{};
        cmd.enable = t >= enable_at;
        cmd.mode = mode;
        cmd.speed_ref = static_cast<float>(speed_ref.at(t) / kRpm);
        cmd.torque_ref = static_cast<float>(torque_ref.at(t));
        cmd.i_ref = mc_dq_t{static_cast<float>(id_ref.at(t)), static_cast<float>(iq_ref.at(t))};
        cmd.theta_init = static_cast<float>(wrap_pi(theta_true + theta_init_err));
        return cmd;
    }
    // the intended direction of rotation, for reverse_angle_max_deg: the last reference's sign
    double direction(double end) const
    {
        const double ref = mode == MC_MODE_SPEED    ? speed_ref.at(end)
                           : mode == MC_MODE_TORQUE ? torque_ref.at(end)
                                                    : iq_ref.at(end);
        return ref < 0 ? -1.0 : 1.0;
    }
};

// trace.csv, one row every output.decimation periods.
class Trace {
public:
    Trace(const Scenario& sc, const std::string& dir) : decim_(sc.i("output.decimation"))
    {
        if (dir.empty() || !sc.b("output.trace")) return;
        const std::string tp = dir + "/trace.csv";
        f_ = std::fopen(tp.c_str(), "w");
        if (!f_) throw std::runtime_error("cannot write " + tp);
        std::fputs("t_s,theta_deg,theta_hat_deg,angle_err_deg,speed_rpm,speed_hat_rpm,speed_ref_rpm,"
                   "id_a,iq_a,id_ref_a,iq_ref_a,ud_v,uq_v,torque_nm,torque_ref_nm,load_nm,"
                   "ia_a,ib_a,ic_a,vdc_v,state,theta_raw_deg,speed_raw_rpm,newton_iter,cost,u_inj_v\n", f_);
    }
    ~Trace()
    {
        flush();
        if (f_) std::fclose(f_);
    }
    Trace(const Trace&) = delete;
    Trace& operator=(const Trace&) = delete;
    bool wants(long k) const { return f_ && k % decim_ == 0; }
    // One row. std::to_chars with a precision formats exactly as printf's "%.Nf" / "%.Ng" (both
    // round the exact binary value), at a fraction of fprintf's cost: on a long run fprintf was a
    // third of the loop. Rows are collected and written in blocks.
    void row(double t, const Plant& plant, const mc_drive_telem_t& tm, const Sample& s, double load, int p, bool est)
    {
        const double deg = 180.0 / kPi;
        const bool run = s.running;
        const auto iabc = plant.i_abc();
        const double fixed[] = {t, s.theta_true_deg, run ? tm.theta * deg : NAN, s.angle_err_deg, s.speed_rpm,
                                run ? tm.omega / p * kRpm : NAN, s.speed_ref_rpm, s.id, s.iq, run ? tm.i_ref.d : NAN,
                                run ? tm.i_ref.q : NAN, run ? tm.u_dq.d : NAN, run ? tm.u_dq.q : NAN, s.torque,
                                run ? tm.torque_ref : NAN, load, iabc[0], iabc[1], iabc[2], tm.vdc};
        static const int prec[] = {6, 4, 4, 4, 4, 4, 4, 5, 5, 5, 5, 4, 4, 5, 5, 5, 5, 5, 5, 3};
        for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; ++k) num(fixed[k], std::chars_format::fixed, prec[k]);
        integer(static_cast<int>(tm.state));
        num(run ? tm.theta_raw * deg : NAN, std::chars_format::fixed, 4);
        num(run ? tm.omega_raw / p * kRpm : NAN, std::chars_format::fixed, 4);
        integer(run && est ? tm.est_iters : 0);
        num(run && est ? tm.est_cost : NAN, std::chars_format::general, 4);
        num(run ? tm.u_inj : NAN, std::chars_format::fixed, 3);
        buf_.back() = '\n';   // the last separator ends the row
        if (buf_.size() > (1u << 16)) flush();
    }

private:
    void num(double v, std::chars_format fmt, int precision)
    {
        if (std::isnan(v)) {   // printf's spelling, sign included
            buf_.append(std::signbit(v) ? "-nan," : "nan,");
            return;
        }
        char tmp[400];   // %.6f of the largest double needs ~317 characters
        const auto r = std::to_chars(tmp, tmp + sizeof tmp, v, fmt, precision);
        buf_.append(tmp, r.ptr);
        buf_.push_back(',');
    }
    void integer(int v)
    {
        char tmp[16];
        const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
        buf_.append(tmp, r.ptr);
        buf_.push_back(',');
    }
    void flush()
    {
        if (f_ && !buf_.empty()) std::fwrite(buf_.data(), 1, buf_.size(), f_);
        buf_.clear();
    }

private:
    std::FILE* f_ = nullptr;
    long decim_;
    std::string buf_;
};

}  // namespace

DriveSetup drive_setup_for(const Scenario& sc)
{
    const Resolved r = resolve(sc);
    const std::unique_ptr<FluxModel> magnetics = make_plant_model(sc, r.mp);
    return drive_setup(sc, r, *magnetics);
}

void check_scenario(const Scenario& sc)
{
    const Resolved r = resolve(sc);
    const std::unique_ptr<FluxModel> magnetics = make_plant_model(sc, r.mp);
    drive_setup(sc, r, *magnetics);
}

RunSummary run_scenario(const Scenario& sc, const RunOptions& opt)
{
    const Resolved r = resolve(sc);
    const int p = r.mp.pole_pairs;
    Plant plant(plant_config(sc, r), make_plant_model(sc, r.mp));
    Sensors sensors = make_sensors(sc, r);
    const DriveSetup ds = drive_setup(sc, r, plant.model());

    // ---- the firmware: built for the host, or a cross-built image under PIL
    std::unique_ptr<DriveTarget> drive =
        opt.pil_elf.empty() ? make_host_drive(sc, ds, r.ts, opt.nvm_file) : make_pil_drive(opt.pil_elf, ds, r.ts);
    if (!opt.nvm_file.empty() && !opt.pil_elf.empty())
        throw ScenarioError("--nvm: the PIL image keeps its configuration in its configuration area (mcsim image-config), not in an NVM file");
    const mc_params_t& dp = ds.resolved;
    const bool estimator = ds.estimator;
    std::unique_ptr<CanLink> can;
    const bool can_commands = !opt.can.empty() && sc.s("can.commands") == "canopen";
    if (!opt.can.empty()) {
        if (drive->can() == nullptr)
            throw ScenarioError("--can: this target has no CAN controller the simulator models (the generic Cortex-M4F port has none: use the host build or the am263x image)");
        can = make_can_link(opt.can);
        if (!drive->attach_canopen(static_cast<uint8_t>(sc.i("can.node_id")), static_cast<uint16_t>(sc.i("can.heartbeat_ms")),
                                   can_commands))
            throw ScenarioError("--can: the drive's CANopen device refused its configuration");
        if (opt.progress) std::fprintf(stderr, "mcsim: the drive is on CAN: %s\n", can->describe().c_str());
    }

    // ---- commands and outputs
    const Commander commander(sc);
    if (!opt.out_dir.empty()) std::filesystem::create_directories(opt.out_dir);
    Trace trace(sc, opt.out_dir);
    Metrics metrics(sc);
    const double duration = sc.f("scenario.duration_s");
    const double direction = commander.direction(duration);
    const long periods = static_cast<long>(std::llround(duration / r.ts));
    Progress progress(opt.progress, duration);
    const double deg = 180.0 / kPi;
    const std::string& mech = sc.s("mechanics.mode");
    const bool is_dyno = mech == "dyno", is_inertia = mech == "inertia", is_locked = mech == "locked";
    const Profile load = sc.profile("mechanics.load_torque_nm");
    const Profile dyno = sc.profile("mechanics.dyno_speed_rpm");
    // plant-side and timing faults (the sensor faults live in `sensors`)
    const int open_phase = static_cast<int>(sc.i("faults.open_phase"));
    const double open_from = sc.f("faults.open_phase_from_s");
    const double overrun_from = sc.f("faults.isr_overrun_from_s");
    const long overrun_every = sc.i("faults.isr_overrun_every");
    const long overrun_k0 = overrun_from >= 0.0 ? static_cast<long>(std::ceil(overrun_from / r.ts - 1e-9)) : -1;

    // A measured map: its load warnings, and the time the current spends outside its grid (the
    // plant extrapolates there, docs/machine-models.md "Measured flux maps"); warned at the first exit.
    const FluxMapData* fmap = r.mp.flux_map.get();
    if (fmap)
        for (const std::string& w : fmap->warnings) std::fprintf(stderr, "mcsim: warning: %s\n", w.c_str());
    double map_outside_s = 0, map_first_out_s = NAN;

    double isr_ns = 0, plant_ns = 0;
    mc_drive_telem_t last_tm{};
    long timed = 0;
    const auto wall0 = std::chrono::steady_clock::now();
    for (long k = 0; k < periods; ++k) {
        const double t = k * r.ts;
        // Period boundary: the duties of the last ISR take effect; the ADC and QEP sample.
        const PwmOut coming = drive->pending();
        const AdcSample as = sensors.sample_adc(plant, r.vdc_at(t), r.ts, coming.duty, coming.enabled);
        const QepSample qs = sensors.sample_qep(plant);
        DriveInputs in;
        for (int j = 0; j < 3; ++j) in.adc_i[j] = as.i[j];
        in.adc_vdc = as.vdc;
        in.overrun = overrun_k0 >= 0 && k >= overrun_k0 &&
                     (k == overrun_k0 || (overrun_every > 0 && (k - overrun_k0) % overrun_every == 0));
        in.qep_count = qs.count;
        in.qep_index_seen = qs.index_seen;
        in.qep_index_count = qs.index_count;
        in.t = t;
        drive->boundary(in);

        const double theta = plant.theta_e();
        if (!can_commands) drive->command(commander.at(t, theta));   // else CiA 402 commands

        // The ISR / plant split is timed on every 17th period: a clock read costs about a tenth
        // of a simulated period, so timing all of them would slow down what it measures; 17 is
        // prime to the firmware's slow-loop dividers, so the sample sees their share.
        const bool time_it = k % 17 == 0;
        timed += time_it;
        std::chrono::steady_clock::time_point i0;
        if (time_it) i0 = std::chrono::steady_clock::now();
        drive->isr(k);
        if (time_it) isr_ns += std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - i0).count();

        // Record the state at the sample instant, before the plant moves on, as the background
        // would read it.
        const mc_drive_telem_t tm = drive->telemetry();
        last_tm = tm;
        const bool running = tm.state == MC_STATE_RUN;
        const auto iabc = plant.i_abc();
        const double ipk = std::max({std::fabs(iabc[0]), std::fabs(iabc[1]), std::fabs(iabc[2])});
        const Vec2 idq = plant.i_dq();
        if (fmap && !fmap->in_grid(idq)) {
            if (std::isnan(map_first_out_s)) {
                map_first_out_s = t;
                const FluxMapTable& g = fmap->table;
                std::fprintf(stderr,
                             "mcsim: warning: t = %.6f s: the current (i_d, i_q) = (%.3f, %.3f) A leaves the flux map's grid "
                             "(i_d %g .. %g A, i_q %g .. %g A, %s); the plant extrapolates linearly from the edge "
                             "(metric fluxmap_outside_s)\n",
                             t, idq.x(), idq.y(), g.x.lo, g.x.hi, g.y.lo, g.y.hi, fmap->file.c_str());
            }
            map_outside_s += r.ts;
        }
        double sref = NAN;
        if (is_dyno) sref = dyno.at(t);
        else if (!can_commands && commander.mode == MC_MODE_SPEED && !is_locked) sref = commander.speed_ref.at(t);
        Sample smp{t, running, running ? wrap_pi(tm.theta - theta) * deg : NAN, plant.omega_m() * kRpm, sref,
                   idq.x(), idq.y(), tm.i_ref.d, tm.i_ref.q, plant.torque(), ipk,
                   running && estimator ? tm.est_iters : -1};
        smp.state = static_cast<int>(tm.state);
        smp.init_step = static_cast<int>(tm.init_step);
        const bool pipeline = running || (tm.state == MC_STATE_INIT_POS && tm.init_step == MC_INIT_STEP3);
        smp.angle_err_any = pipeline ? wrap_pi(tm.theta - theta) * deg : NAN;
        smp.theta_true_deg = theta * deg;
        smp.theta_e_unwrapped = plant.theta_m() * p;
        smp.theta1_deg = tm.theta1 * deg;
        smp.theta2_deg = tm.theta2 * deg;
        smp.direction = direction;
        smp.ts = r.ts;
        smp.if_on = tm.if_on;
        smp.if_open = running && tm.if_mode != 0u;
        metrics.add(smp);
        if (trace.wants(k)) trace.row(t, plant, tm, smp, is_inertia ? load.at(t) : NAN, p, estimator);

        // An open-phase fault takes effect here (the sample at t still saw the current).
        if (open_phase >= 0 && plant.open_phase() < 0 && t >= open_from) plant.set_open_phase(open_phase);
        // The inverter applies the latched duties over (t, t + Ts).
        std::chrono::steady_clock::time_point p0;
        if (time_it) p0 = std::chrono::steady_clock::now();
        const PwmOut now = drive->outputs();
        plant.step_period(r.ts, now.duty, now.enabled);
        if (time_it) plant_ns += std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - p0).count();

        if (can) can->pump(drive->can(), t + r.ts);
        if (opt.realtime > 0 && (k % 10) == 0) {
            // simulated time paced to the wall clock (a bus peer sees the drive in real time)
            const auto due = wall0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                         std::chrono::duration<double>((t + r.ts) / opt.realtime));
            std::this_thread::sleep_until(due);
        }
        if ((k & 1023) == 0)
            progress.update(t, std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count());
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    progress.done();

    RunSummary out;
    out.sim_time_s = periods * r.ts;
    out.wall_time_s = wall;
    out.realtime_factor = wall > 0 ? out.sim_time_s / wall : 0;
    out.isr_ns_mean = timed > 0 ? isr_ns / timed : 0;
    out.plant_ns_mean = timed > 0 ? plant_ns / timed : 0;
    out.periods = periods;
    const mc_drive_telem_t& tm = last_tm;
    std::vector<std::pair<std::string, std::string>> extra = {{"scenario", json_string(sc.s("scenario.name"))},
                                     {"current_limit_a", json_number(dp.control_i_max_a)},
                                     {"current_trip_a", json_number(dp.control_i_trip_a)},
                                     {"speed_final_rpm", json_number(plant.omega_m() * kRpm)},
                                     {"sim_time_s", json_number(out.sim_time_s)},
                                     {"wall_time_s", json_number(wall)},
                                     {"realtime_factor", json_number(out.realtime_factor)},
                                     {"fault_count", std::to_string(fault_names(tm.faults).size())},
                                     {"recoveries", std::to_string(tm.recoveries)},
                                     {"recovered_from", json_string_array(fault_names(tm.recovered_from))},
                                     {"polarity_checks", std::to_string(tm.polarity_checks)},
                                     {"polarity_flips", std::to_string(tm.polarity_flips)},
                                     {"step2_confidence", json_number(tm.pol_z)},
                                     {"step2_verdict", json_string(step2_verdict_name(tm.pol_verdict))}};
    if (fmap) {
        extra.push_back({"fluxmap_outside_s", json_number(map_outside_s)});
        extra.push_back({"fluxmap_first_outside_s", json_number(map_first_out_s)});
    }
    for (auto& kv : drive->metrics()) extra.push_back(std::move(kv));
    out.metrics_json = metrics.json(fault_names(tm.faults), state_name(tm.state), extra);
    if (!opt.out_dir.empty()) {
        std::ofstream m(opt.out_dir + "/metrics.json");
        m << out.metrics_json;
    }
    return out;
}

std::string faults_markdown()
{
    // the names through fault_names(), the metrics' own: docs/protection.md says what metrics say
    std::string os = "Generated by `mcsim faults` from `firmware/control/include/mc/faults.h`; the EMCY codes in "
                     "docs/can.md.\n\n"
                     "| bit | fault (metrics name) | reaction | recoverable | detects |\n"
                     "|---:|---|---|---|---|\n";
#define MC_FAULT_ROW_(NAME, bit, name, emcy, reg, reaction, rec, doc)                                  \
    {                                                                                                 \
        const std::vector<std::string> n = fault_names(MC_FAULT_##NAME);                              \
        os += "| " + std::to_string(bit) + " | `" + (n.empty() ? std::string("?") : n[0]) + "` | " +    \
              (MC_FAULT_REACT_##reaction == MC_FAULT_REACT_HOLD_FW                                     \
                   ? "outputs off; above the generation speed with `protection.overspeed_action = "   \
                     "hold_fw` first FAULT_REACTION (zero torque, field weakening)"                   \
                   : "outputs off") +                                                                 \
              " | " + ((rec) ? "yes (`protection.lock_action = recover`)" : "no") + " | " + doc + " |\n"; \
    }
    MC_FAULTS(MC_FAULT_ROW_)
#undef MC_FAULT_ROW_
    return os;
}

}  // namespace mcsim
