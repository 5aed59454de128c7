#include "scenario.hpp"

#include "drive_setup.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

namespace mcsim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

// clang-format off
const std::vector<KeySpec>& scenario_schema()
{
    static const std::vector<KeySpec> k = {
    {"scenario.name", KeyType::String, "\"\"", nullptr, 0, 0, "", "", "Short name, used in plot titles."},
    {"scenario.description", KeyType::String, "\"\"", nullptr, 0, 0, "", "", "What the scenario reproduces."},
    {"scenario.duration_s", KeyType::Float, "1.0", nullptr, 1e-3, 86400, "s", "", "Simulated time (a drive on CAN may run for hours: nothing is kept per period but the trace, output.trace)."},
    {"scenario.seed", KeyType::Int, "1", nullptr, 0, 2147483647, "", "", "Seed of the sensor noise."},
    {"scenario.profile", KeyType::Enum, "\"realistic\"", nullptr, 0, 0, "", "realistic|ideal|harsh",
     "Realism profile: sets the defaults of the inverter and sensor keys (the table's profile column): ideal for debugging, harsh for robustness (long dead time, device drop, gain errors, more noise, ADC delay, DC-link ripple)."},

    {"machine.preset", KeyType::String, "\"sun2016-ipm-5kw\"", nullptr, 0, 0, "", "", "Preset name (presets/NAME.toml) or path."},
    {"machine.model", KeyType::Enum, "\"analytic\"", nullptr, 0, 0, "", "analytic|linear|table",
     "Plant magnetics: analytic saturation model, constant Ld/Lq/psi_pm, or the analytic model tabulated, inverted (Fig. 4.3) and interpolated."},
    {"machine.table_points", KeyType::Int, "41", nullptr, 5, 401, "", "", "Grid points per axis of the table model."},

    {"inverter.mode", KeyType::Enum, "\"switching\"", "\"averaged\"", 0, 0, "", "switching|averaged", "Switching instants with dead time, or period averages."},
    {"inverter.vdc_v", KeyType::Profile, "", nullptr, 0, 2000, "V", "", "DC-link voltage (default: the preset's nominal); a profile: sag, surge, loss (to ~0). The plant holds its value at each period's middle over the period; the firmware's nominal DC link and the Vdc sensor span follow its value at t = 0 (at least 1 V)."},
    {"inverter.vdc_ripple_v", KeyType::Float, "0.0", nullptr, 0, 1000, "V", "", "DC-link ripple amplitude, added to inverter.vdc_v as a sine (harsh default: 2 % of inverter.vdc_v at t = 0).", nullptr, ""},
    {"inverter.vdc_ripple_hz", KeyType::Float, "300.0", nullptr, 0, 100000, "Hz", "", "DC-link ripple frequency (300 Hz: a six-pulse rectifier on 50 Hz mains)."},
    {"inverter.dead_time_s", KeyType::Float, "0.5e-6", "0.0", 0, 10e-6, "s", "", "Dead time per commutation.", nullptr, "2e-6"},
    {"inverter.device_drop_v", KeyType::Float, "0.0", nullptr, 0, 10, "V", "", "Device on-state drop.", nullptr, "1.0"},
    {"can.node_id", KeyType::Int, "1", nullptr, 1, 127, "", "", "CANopen node id of the drive (mcsim run --can)."},
    {"can.heartbeat_ms", KeyType::Int, "1000", nullptr, 0, 65535, "ms", "", "CANopen producer heartbeat time 0x1017 at start (0: off)."},
    {"can.bitrate", KeyType::Int, "500000", nullptr, 10000, 1000000, "bit/s", "", "Classic CAN bit rate (a real bus's; the TCP and virtual links do not pace to it)."},
    {"can.commands", KeyType::Enum, "\"canopen\"", nullptr, 0, 0, "", "canopen|scenario", "With --can: the drive takes its commands from CANopen (CiA 402: enable, mode, targets) like a real one and the scenario's control.* profiles are not sent; or from the scenario (CANopen then only reads, tunes and scopes)."},
    {"can.scope_values", KeyType::Int, "16384", nullptr, 64, 1048576, "values", "", "The scope's buffer (0x2308): samples x channels it holds."},
    {"inverter.pwm_counts", KeyType::Int, "0", nullptr, 0, 65535, "counts", "", "Compare resolution of the host build's modulator: 0 ideal (the firmware's duties as computed); N: each duty becomes a whole number of counts of a half period of N counts, as a timer compare does (a --pil run: the image's own timer does it; check_pil.py sets this to the port's, e.g. 5000 generic, 10000 AM263x at 10 kHz)."},
    {"inverter.pwm_compare", KeyType::Enum, "\"on_time\"", nullptr, 0, 0, "", "on_time|off_time", "With inverter.pwm_counts: the compare value counts the high side's on-time (round(d N), the generic port) or its off-time (N - round((1 - d) N), the AM263x ePWM)."},
    {"inverter.integrator", KeyType::Enum, "\"taylor\"", nullptr, 0, 0, "", "taylor|hermite|rk4",
     "Plant integration (docs/plant.md): taylor: the period in one pass with the current map expanded to second order about mid-period, exact at the period end (tables go edge by edge with Hermite); hermite: one model evaluation per switching interval (the most exact); classical RK4 (reference)."},

    {"sensors.adc_bits", KeyType::Int, "12", "16", 8, 16, "bit", "", "Current/voltage ADC resolution."},
    {"sensors.i_full_scale_a", KeyType::Float, "", nullptr, 0.1, 10000, "A", "", "Current ADC span is -fs..+fs (default: a sensor sized for the motor, 1.875 x rated peak rounded up to 1-1.2-1.5-2-2.5-3-4-5-6-8: 25 A on sun2016-ipm-5kw, 300 A on brodatzki-35kw)."},
    {"sensors.i_noise_rms_a", KeyType::Float, "0.02", "0.0", 0, 10, "A", "", "White noise on each current sample.", nullptr, "0.05"},
    {"sensors.i_gain_err", KeyType::Float3, "[0.0, 0.0, 0.0]", nullptr, -0.5, 0.5, "1", "", "Relative gain error per phase.", nullptr, "[0.01, -0.01, 0.005]"},
    {"sensors.i_offset_err_a", KeyType::Float3, "[0.0, 0.0, 0.0]", nullptr, -10, 10, "A", "", "Offset error per phase (removed by the firmware's calibration)."},
    {"sensors.vdc_full_scale_v", KeyType::Float, "", nullptr, 1, 5000, "V", "", "Vdc ADC span 0..fs (default: 1.6 x inverter.vdc_v rounded up alike: 500 V at 300 V, 400 V at 250 V)."},
    {"sensors.vdc_noise_rel", KeyType::Float, "0.005", "0.0", 0, 0.2, "1", "", "Vdc noise, rms relative to the value."},
    {"sensors.adc_delay_s", KeyType::Float, "0.0", nullptr, 0, 20e-6, "s", "", "Conversion delay: the currents are sampled this long after the PWM centre (first-order extrapolation along the voltage the latched duties apply, docs/plant.md).", nullptr, "2e-6"},
    {"sensors.encoder_lines", KeyType::Int, "20000", nullptr, 1, 1000000, "lines/rev", "", "Quadrature encoder lines (4 counts each); 20000 = the thesis' 80000 counts."},
    {"sensors.encoder_offset_deg", KeyType::Float, "0.0", nullptr, -360, 360, "deg (mech)", "", "Mechanical angle where the counter reads 0 and the index sits."},

    {"mechanics.mode", KeyType::Enum, "\"inertia\"", nullptr, 0, 0, "", "inertia|dyno|locked",
     "inertia: J dw/dt = Te - B w - T_load; dyno: speed held to mechanics.dyno_speed_rpm; locked: rotor held."},
    {"mechanics.inertia_kgm2", KeyType::Float, "", nullptr, 1e-6, 1e3, "kg m^2", "", "Inertia (default: preset)."},
    {"mechanics.friction_nms", KeyType::Float, "", nullptr, 0, 1e2, "N m s", "", "Viscous friction (default: preset)."},
    {"mechanics.theta0_deg", KeyType::Float, "0.0", nullptr, -360, 360, "deg (elec)", "", "Initial electrical rotor angle."},
    {"mechanics.speed0_rpm", KeyType::Float, "0.0", nullptr, -30000, 30000, "rpm", "", "Initial speed."},
    {"mechanics.load_torque_nm", KeyType::Profile, "0.0", nullptr, -1e4, 1e4, "N m", "", "Load torque opposing positive speed (inertia mode)."},
    {"mechanics.load_kind", KeyType::Enum, "\"active\"", nullptr, 0, 0, "", "active|reactive", "active: the load torque acts whatever the speed (gravity-like); reactive: it opposes the motion and holds the rotor at rest up to its magnitude (friction-like)."},
    {"mechanics.dyno_speed_rpm", KeyType::Profile, "0.0", nullptr, -30000, 30000, "rpm", "", "Dyno speed profile (dyno mode)."},

    {"control.mode", KeyType::Enum, "\"speed\"", nullptr, 0, 0, "", "speed|torque|current", "What the references command."},
    {"control.enable_at_s", KeyType::Float, "0.0", nullptr, 0, 600, "s", "", "Enable command time (offset calibration follows)."},
    {"control.speed_ref_rpm", KeyType::Profile, "0.0", nullptr, -30000, 30000, "rpm", "", "Speed reference (speed mode)."},
    {"control.torque_ref_nm", KeyType::Profile, "0.0", nullptr, -1e5, 1e5, "N m", "", "Torque reference (torque mode)."},
    {"control.id_ref_a", KeyType::Profile, "0.0", nullptr, -5000, 5000, "A", "", "d current reference (current mode)."},
    {"control.iq_ref_a", KeyType::Profile, "0.0", nullptr, -5000, 5000, "A", "", "q current reference (current mode)."},

    {"estimator.theta0_err_deg", KeyType::Float, "0.0", nullptr, -180, 180, "deg (elec)", "", "Error of the initial angle handed to the estimator at enable (the initial position is otherwise taken as known)."},
    {"estimator.rs_scale", KeyType::Float, "1.0", nullptr, 0.1, 10, "1", "", "Estimator's Rs / true (parameter-mismatch tests)."},
    {"estimator.psi_scale", KeyType::Float, "1.0", nullptr, 0.1, 10, "1", "", "Estimator's psi_pm / true."},
    {"estimator.l_scale", KeyType::Float, "1.0", nullptr, 0.1, 10, "1", "", "Estimator's Ld, Lq (and flux-map inductances) / true."},
    {"estimator.cross_scale", KeyType::Float, "1.0", nullptr, 0.1, 10, "1", "", "Estimator's flux-map cross-saturation / true: scales the part of psi_d that depends on i_q and of psi_q that depends on i_d (flux-map model only)."},
    {"estimator.map_points", KeyType::Int, "41", nullptr, 5, 41, "", "", "Flux-map grid points per axis."},
    {"estimator.map_span_a", KeyType::Float, "", nullptr, 0.1, 5000, "A", "", "Flux map covers +-span on both axes (default: 1.5 x rated peak)."},

    {"faults.i_stuck_phase", KeyType::Int, "-1", nullptr, -1, 2, "", "", "Current channel (0 a, 1 b, 2 c) that sticks from faults.i_stuck_from_s on; -1 none."},
    {"faults.i_stuck_from_s", KeyType::Float, "0.0", nullptr, 0, 600, "s", "", "Time the current channel sticks."},
    {"faults.i_stuck_a", KeyType::Float, "0.0", nullptr, -10000, 10000, "A", "", "What the stuck channel reads from then on (nominal scaling, no gain, offset or noise; clamped to the ADC span)."},
    {"faults.i_offset_drift_a_per_s", KeyType::Float3, "[0.0, 0.0, 0.0]", nullptr, -1000, 1000, "A/s", "", "Per phase: the current channel's offset drifts linearly at this rate from faults.i_offset_drift_from_s on (added to sensors.i_offset_err_a)."},
    {"faults.i_offset_drift_from_s", KeyType::Float, "0.0", nullptr, 0, 600, "s", "", "Time the offset drift starts."},
    {"faults.open_phase", KeyType::Int, "-1", nullptr, -1, 2, "", "", "Phase (0 a, 1 b, 2 c) disconnected between inverter and machine from faults.open_phase_from_s on: its terminal floats, its current is 0, the other two carry i and -i (docs/plant.md); -1 none."},
    {"faults.open_phase_from_s", KeyType::Float, "0.0", nullptr, 0, 600, "s", "", "Time the phase opens (a current it carries then is cut at once)."},
    {"faults.encoder_loss_from_s", KeyType::Float, "-1.0", nullptr, -1, 600, "s", "", "From this time the encoder counter freezes at its last count (no counts, no index); < 0: never."},
    {"faults.isr_overrun_from_s", KeyType::Float, "-1.0", nullptr, -1, 600, "s", "", "The ADC sample's overrun flag (the previous ISR overran its period) is set in the first period starting at or after this time; < 0: never."},
    {"faults.isr_overrun_every", KeyType::Int, "0", nullptr, 0, 1000000, "periods", "", "After that first one, set the overrun flag again every N periods (0: only once)."},

    {"output.decimation", KeyType::Int, "10", nullptr, 1, 1000000, "periods", "", "Write one trace row every N periods."},
    {"output.trace", KeyType::Bool, "true", nullptr, 0, 0, "", "", "Write trace.csv."},

    {"metrics.start_s", KeyType::Float, "0.0", nullptr, 0, 600, "s", "", "angle_err_max_deg and current figures from here on."},
    {"metrics.settle_from_s", KeyType::Float, "0.0", nullptr, 0, 600, "s", "", "settling_time_s is measured from here."},
    {"metrics.settle_signal", KeyType::Enum, "\"speed\"", nullptr, 0, 0, "", "speed|angle|iq", "Error settling_time_s looks at: speed - ref [rpm], angle error [deg], iq - iq_ref [A]."},
    {"metrics.settle_band", KeyType::Float, "6.0", nullptr, 0, 1e5, "rpm|deg|A", "", "Error band for settling_time_s."},
    {"metrics.window", KeyType::String, "", nullptr, 0, 0, "", "",
     "Array of tables [[metrics.window]] with name (string), from_s, to_s: the steady windows."},
    };
    // the drive's keys come from the firmware's parameter table (drive_setup.cpp)
    static const std::vector<KeySpec> all = [] {
        std::vector<KeySpec> v = k;
        for (const KeySpec& d : drive_key_specs()) v.push_back(d);
        return v;
    }();
    return all;
}
// clang-format on

double Profile::at(double t) const
{
    if (pts.empty()) return 0.0;
    if (t <= pts.front().first) return pts.front().second;
    if (t >= pts.back().first) return pts.back().second;
    for (size_t k = 1; k < pts.size(); ++k) {
        if (t < pts[k].first) {
            const auto& a = pts[k - 1];
            const auto& b = pts[k];
            if (b.first <= a.first) return b.second;  // a step: two points at the same time
            return a.second + (b.second - a.second) * (t - a.first) / (b.first - a.first);
        }
    }
    return pts.back().second;
}

// Length of the well-formed UTF-8 sequence at s[k] (1 for printable ASCII), 0 if the byte there
// must be escaped (control character, DEL, or not valid UTF-8).
static size_t utf8_printable_len(const std::string& s, size_t k)
{
    const unsigned char c = static_cast<unsigned char>(s[k]);
    if (c < 0x80) return (c >= 0x20 && c != 0x7f) ? 1 : 0;
    return utf8_sequence_len(s, k);
}

size_t utf8_sequence_len(const std::string& s, size_t k)
{
    const unsigned char c = static_cast<unsigned char>(s[k]);
    if (c < 0x80) return 1;
    size_t len = 0;
    unsigned lo = 0x80, hi = 0xBF;
    if (c >= 0xC2 && c <= 0xDF) len = 2;
    else if (c >= 0xE0 && c <= 0xEF) {
        len = 3;
        if (c == 0xE0) lo = 0xA0;
        if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
        len = 4;
        if (c == 0xF0) lo = 0x90;
        if (c == 0xF4) hi = 0x8F;
    }
    if (len == 0 || k + len > s.size()) return 0;
    for (size_t j = 1; j < len; ++j) {
        const unsigned char d = static_cast<unsigned char>(s[k + j]);
        if (d < (j == 1 ? lo : 0x80u) || d > (j == 1 ? hi : 0xBFu)) return 0;
    }
    return len;
}

std::string message_text(const std::string& s, size_t max_chars, bool escape_quotes)
{
    std::string o;
    size_t k = 0, chars = 0;
    for (; k < s.size() && chars < max_chars; ++chars) {
        const char c = s[k];
        if (escape_quotes && (c == '"' || c == '\\')) {
            o += '\\';
            o += c;
            ++k;
        } else if (const size_t len = utf8_printable_len(s, k)) {
            o.append(s, k, len);
            k += len;
        } else {
            static const char* const kHex = "0123456789abcdef";
            const unsigned char u = static_cast<unsigned char>(c);
            switch (c) {
            case '\n': o += "\\n"; break;
            case '\t': o += "\\t"; break;
            case '\r': o += "\\r"; break;
            default:
                o += "\\x";
                o += kHex[u >> 4];
                o += kHex[u & 15];
            }
            ++k;
        }
    }
    if (k < s.size()) o += "\u2026(" + std::to_string(s.size()) + " bytes)";
    return o;
}

namespace {

const KeySpec* find_spec(const std::string& key)
{
    for (const auto& s : scenario_schema())
        if (key == s.key) return &s;
    return nullptr;
}

// One-line rendering of a value for error messages: strings quoted with message_text (escaped,
// shortened), arrays cut after ~kMessageChars characters.
std::string node_text(const toml::node& n)
{
    std::ostringstream os;
    if (auto s = n.as_string()) {
        os << '"' << message_text(s->get()) << '"';
    } else if (auto f = n.as_floating_point()) {
        os << f->get();
    } else if (auto i = n.as_integer()) {
        os << i->get();
    } else if (auto b = n.as_boolean()) {
        os << (b->get() ? "true" : "false");
    } else if (auto a = n.as_array()) {
        os << '[';
        for (size_t k = 0; k < a->size(); ++k) {
            if (k > 0 && os.tellp() > std::streamoff(kMessageChars)) {
                os << ", \u2026(" << a->size() << " elements)";
                break;
            }
            os << (k ? ", " : "") << node_text(*a->get(k));
        }
        os << ']';
    } else if (n.is_table()) {
        os << "(table)";
    } else {
        os << "(value)";
    }
    return os.str();
}

const char* type_name(KeyType t)
{
    switch (t) {
    case KeyType::Float: return "a number";
    case KeyType::Int: return "an integer";
    case KeyType::Bool: return "true or false";
    case KeyType::String: return "a string";
    case KeyType::Enum: return "one of the strings";
    case KeyType::Float3: return "an array of 3 numbers";
    case KeyType::Profile: return "a number or an array of [t_s, value] pairs with non-decreasing t";
    }
    return "?";
}

std::string range_text(const KeySpec& s)
{
    std::ostringstream os;
    if (s.type == KeyType::Enum) {
        os << "allowed: " << s.choices;
    } else if (s.type == KeyType::Bool || s.type == KeyType::String) {
        os << "expected " << type_name(s.type);
    } else {
        os << "allowed range [" << s.min << ", " << s.max << "]" << (s.unit[0] ? " " : "") << s.unit;
    }
    return os.str();
}

// key: raw (escaped and shortened here); value: already rendered (node_text), only capped.
[[noreturn]] void fail(const std::string& origin, const std::string& key, const std::string& value,
                       const std::string& what)
{
    const size_t cap = 3 * kMessageChars;  // nested arrays render each level's first element
    std::string v = value;
    if (v.size() > cap) {
        size_t cut = cap;
        while (cut > 0 && (static_cast<unsigned char>(v[cut]) & 0xC0) == 0x80) --cut;  // not inside UTF-8
        v = v.substr(0, cut) + "\u2026(" + std::to_string(value.size()) + " bytes)";
    }
    throw ScenarioError(origin + ": key '" + message_text(key) + "' = " + v + ": " + what);
}

std::optional<double> as_number(const toml::node& n)
{
    if (auto v = n.as_floating_point()) return v->get();
    if (auto v = n.as_integer()) return static_cast<double>(v->get());
    return std::nullopt;
}

}  // namespace

// Convert one validated node into the typed stores.
static void store(const std::string& origin, const KeySpec& s, const toml::node& n,
                  std::map<std::string, double>& num, std::map<std::string, std::string>& str,
                  std::map<std::string, Profile>& prof, std::map<std::string, std::vector<double>>& f3)
{
    const std::string key = s.key;
    const std::string shown = node_text(n);
    auto check_range = [&](double v) {
        if (!std::isfinite(v) || v < s.min || v > s.max) fail(origin, key, shown, "out of range; " + range_text(s));
    };
    switch (s.type) {
    case KeyType::Float: {
        auto v = as_number(n);
        if (!v) fail(origin, key, shown, std::string("wrong type: expected ") + type_name(s.type) + "; " + range_text(s));
        check_range(*v);
        num[key] = *v;
        break;
    }
    case KeyType::Int: {
        auto v = n.as_integer();
        if (!v) fail(origin, key, shown, std::string("wrong type: expected ") + type_name(s.type) + "; " + range_text(s));
        check_range(static_cast<double>(v->get()));
        num[key] = static_cast<double>(v->get());
        break;
    }
    case KeyType::Bool: {
        auto v = n.as_boolean();
        if (!v) fail(origin, key, shown, "wrong type: expected true or false");
        num[key] = v->get() ? 1.0 : 0.0;
        break;
    }
    case KeyType::String: {
        auto v = n.as_string();
        if (!v) fail(origin, key, shown, "wrong type: expected a string");
        str[key] = v->get();
        break;
    }
    case KeyType::Enum: {
        auto v = n.as_string();
        if (!v) fail(origin, key, shown, std::string("wrong type: expected a string; ") + range_text(s));
        std::string val = v->get();
        // Choices that were removed: a scenario written for them keeps running, with one line.
        struct Deprecated {
            const char *key, *old_choice, *now, *why;
        };
        static const Deprecated kDeprecated[] = {
            {"inverter.integrator", "ripple", "taylor", "the ripple-moment integrator was removed, superseded by taylor"},
        };
        for (const Deprecated& d : kDeprecated) {
            if (key == d.key && val == d.old_choice) {
                std::fprintf(stderr, "mcsim: %s: key '%s' = \"%s\" is deprecated (%s): using \"%s\"\n",
                             message_text(origin).c_str(), key.c_str(), d.old_choice, d.why, d.now);
                val = d.now;
            }
        }
        const std::string choices = std::string("|") + s.choices + "|";
        if (val.empty() || choices.find("|" + val + "|") == std::string::npos)
            fail(origin, key, shown, "not a valid choice; " + range_text(s));
        str[key] = val;
        break;
    }
    case KeyType::Float3: {
        auto a = n.as_array();
        if (!a || a->size() != 3) fail(origin, key, shown, "wrong type: expected an array of 3 numbers; " + range_text(s));
        std::vector<double> out;
        for (auto& e : *a) {
            auto v = as_number(e);
            if (!v) fail(origin, key, shown, "wrong type: expected an array of 3 numbers");
            check_range(*v);
            out.push_back(*v);
        }
        f3[key] = out;
        break;
    }
    case KeyType::Profile: {
        Profile p;
        if (auto v = as_number(n)) {
            check_range(*v);
            p.pts.push_back({0.0, *v});
        } else if (auto a = n.as_array()) {
            if (a->empty()) fail(origin, key, shown, std::string("wrong type: expected ") + type_name(s.type));
            for (auto& e : *a) {
                auto pair = e.as_array();
                std::optional<double> t, v;
                if (pair && pair->size() == 2) {
                    t = as_number(*pair->get(0));
                    v = as_number(*pair->get(1));
                }
                if (!t || !v) fail(origin, key, shown, std::string("wrong type: expected ") + type_name(s.type));
                if (*t < 0 || !std::isfinite(*t)) fail(origin, key, shown, "profile time must be >= 0 s");
                if (!p.pts.empty() && *t < p.pts.back().first)
                    fail(origin, key, shown, "profile times must be non-decreasing");
                check_range(*v);
                p.pts.push_back({*t, *v});
            }
        } else {
            fail(origin, key, shown, std::string("wrong type: expected ") + type_name(s.type) + "; " + range_text(s));
        }
        prof[key] = p;
        break;
    }
    }
}

static void parse_windows(const std::string& origin, const toml::node& n, std::vector<Window>& out)
{
    const std::string key = "metrics.window";
    auto arr = n.as_array();
    if (!arr) fail(origin, key, node_text(n), "wrong type: expected an array of tables [[metrics.window]]");
    out.clear();
    for (auto& e : *arr) {
        auto t = e.as_table();
        if (!t) fail(origin, key, node_text(e), "wrong type: expected a table with name, from_s, to_s");
        Window w;
        bool has_from = false, has_to = false;
        for (auto&& [k, v] : *t) {
            const std::string kk = std::string(k.str());
            const std::string full = key + "." + kk;
            if (kk == "name") {
                auto s = v.as_string();
                if (!s) fail(origin, full, node_text(v), "wrong type: expected a string");
                w.name = s->get();
            } else if (kk == "from_s" || kk == "to_s") {
                auto x = as_number(v);
                if (!x || *x < 0 || *x > 600) fail(origin, full, node_text(v), "expected a number; allowed range [0, 600] s");
                (kk == "from_s" ? w.from_s : w.to_s) = *x;
                (kk == "from_s" ? has_from : has_to) = true;
            } else {
                fail(origin, full, node_text(v), "unknown key; a window has name, from_s, to_s");
            }
        }
        if (w.name.empty()) fail(origin, key + ".name", "(missing)", "every window needs a name");
        if (!has_from || !has_to) fail(origin, key + "." + w.name, "(missing)", "every window needs from_s and to_s");
        if (w.to_s <= w.from_s) fail(origin, key + "." + w.name, std::to_string(w.to_s), "to_s must be after from_s");
        out.push_back(w);
    }
}

// Flatten the two-level document; reject unknown sections/keys before anything is used.
static void walk(const std::string& origin, const toml::table& root, std::map<std::string, const toml::node*>& leaves)
{
    for (auto&& [sec, node] : root) {
        const std::string sname = std::string(sec.str());
        auto t = node.as_table();
        if (!t) fail(origin, sname, node_text(node), "unknown top-level key; keys live in sections [scenario], [machine], [inverter], [sensors], [mechanics], [control], [faults], [output], [metrics]");
        for (auto&& [k, v] : *t) {
            const std::string full = sname + "." + std::string(k.str());
            if (!find_spec(full)) fail(origin, full, node_text(v), "unknown key (see `mcsim keys` for the list)");
            leaves[full] = &v;
        }
    }
}

// Insert "a.b = value" into a table; the value is parsed as TOML, or taken as a bare string.
static void apply_set(toml::table& root, const std::string& set)
{
    const auto eq = set.find('=');
    if (eq == std::string::npos || eq == 0) throw ScenarioError("--set '" + message_text(set) + "': expected key=value");
    const std::string key = set.substr(0, eq);
    const std::string val = set.substr(eq + 1);
    const auto dot = key.find('.');
    if (dot == std::string::npos) throw ScenarioError("--set: key '" + message_text(key) + "': expected section.key");
    if (!find_spec(key))
        throw ScenarioError("--set: key '" + message_text(key) + "' = " + message_text(val) +
                            ": unknown key (see `mcsim keys` for the list)");
    const std::string sec = key.substr(0, dot), name = key.substr(dot + 1);
    toml::table parsed;
    try {
        parsed = toml::parse("v = " + val);
    } catch (const toml::parse_error&) {
        parsed = toml::table{};
        parsed.insert("v", val);
    }
    if (!root.contains(sec)) root.insert(sec, toml::table{});
    auto* t = root[sec].as_table();
    if (!t) throw ScenarioError("--set: section '" + message_text(sec) + "' is not a table (the file sets it to a value)");
    t->insert_or_assign(name, *parsed.get("v"));
}

Scenario Scenario::from_string(const std::string& text, const std::string& origin, const std::vector<std::string>& sets)
{
    toml::table root;
    try {
        root = toml::parse(text, origin);
    } catch (const toml::parse_error& e) {
        std::ostringstream os;
        os << origin << ":" << e.source().begin.line << ":" << e.source().begin.column
           << ": TOML syntax error: " << message_text(std::string(e.description()), 2 * kMessageChars, false);
        throw ScenarioError(os.str());
    }
    for (const auto& s : sets) apply_set(root, s);

    Scenario sc;
    sc.origin_ = origin;
    std::map<std::string, const toml::node*> leaves;
    walk(origin, root, leaves);

    // profile first: it selects the defaults of the other keys
    bool ideal = false, harsh = false;
    if (auto it = leaves.find("scenario.profile"); it != leaves.end()) {
        store(origin, *find_spec("scenario.profile"), *it->second, sc.num_, sc.str_, sc.prof_, sc.f3_);
        ideal = sc.str_["scenario.profile"] == "ideal";
        harsh = sc.str_["scenario.profile"] == "harsh";
    }
    for (const auto& spec : scenario_schema()) {
        const std::string key = spec.key;
        if (key == "metrics.window") {
            if (auto it = leaves.find(key); it != leaves.end()) parse_windows(origin, *it->second, sc.windows_);
            continue;
        }
        if (auto it = leaves.find(key); it != leaves.end()) {
            store(origin, spec, *it->second, sc.num_, sc.str_, sc.prof_, sc.f3_);
            continue;
        }
        const char* def = (ideal && spec.def_ideal) ? spec.def_ideal : (harsh && spec.def_harsh) ? spec.def_harsh : spec.def;
        if (!def || !def[0]) continue;  // derived from the preset by the runner
        toml::table d = toml::parse(std::string("v = ") + def);
        store("(default)", spec, *d.get("v"), sc.num_, sc.str_, sc.prof_, sc.f3_);
    }
    // cross-key checks
    for (const auto& w : sc.windows_)
        if (w.to_s > sc.f("scenario.duration_s") + 1e-12)
            fail(origin, "metrics.window." + w.name + ".to_s", std::to_string(w.to_s), "window ends after scenario.duration_s");
    return sc;
}

// Only regular files up to kMaxScenarioBytes: a device (/dev/zero), FIFO or directory is refused
// before it is read, and the read itself is bounded (a file that grows, /proc files of size 0).
Scenario Scenario::load(const std::string& path, const std::vector<std::string>& sets)
{
    namespace fs = std::filesystem;
    const std::string shown = message_text(path, 2 * kMessageChars);
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw ScenarioError(shown + ": cannot open scenario file (no such file)");
    if (fs::is_directory(st)) throw ScenarioError(shown + ": is a directory, not a scenario file");
    if (!fs::is_regular_file(st))
        throw ScenarioError(shown + ": not a regular file (device, FIFO or socket); a scenario must be a TOML file");
    const auto size = fs::file_size(path, ec);
    if (!ec && size > kMaxScenarioBytes)
        throw ScenarioError(shown + ": file of " + std::to_string(size) + " bytes is larger than the limit of " +
                            std::to_string(kMaxScenarioBytes) + " bytes (1 MiB) for a scenario");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ScenarioError(shown + ": cannot open scenario file");
    // read what is there, at most a chunk past the limit (no 1 MiB buffer zeroed per run)
    std::string text;
    char chunk[16384];
    while (text.size() <= kMaxScenarioBytes && (in.read(chunk, sizeof chunk) || in.gcount() > 0))
        text.append(chunk, size_t(in.gcount()));
    if (text.size() > kMaxScenarioBytes)
        throw ScenarioError(shown + ": larger than the limit of " + std::to_string(kMaxScenarioBytes) +
                            " bytes (1 MiB) for a scenario");
    if (in.bad()) throw ScenarioError(shown + ": read error");
    return from_string(text, path, sets);
}

double Scenario::f(const std::string& key) const
{
    auto it = num_.find(key);
    if (it == num_.end()) throw ScenarioError("internal: key '" + key + "' has no value");
    return it->second;
}
long Scenario::i(const std::string& key) const { return static_cast<long>(std::llround(f(key))); }
bool Scenario::b(const std::string& key) const { return f(key) != 0.0; }
const std::string& Scenario::s(const std::string& key) const
{
    auto it = str_.find(key);
    if (it == str_.end()) throw ScenarioError("internal: key '" + key + "' has no value");
    return it->second;
}
bool Scenario::has(const std::string& key) const
{
    return num_.count(key) || str_.count(key) || prof_.count(key) || f3_.count(key);
}
const Profile& Scenario::profile(const std::string& key) const
{
    auto it = prof_.find(key);
    if (it == prof_.end()) throw ScenarioError("internal: key '" + key + "' has no value");
    return it->second;
}
std::vector<double> Scenario::f3(const std::string& key) const
{
    auto it = f3_.find(key);
    if (it == f3_.end()) throw ScenarioError("internal: key '" + key + "' has no value");
    return it->second;
}

std::string schema_markdown()
{
    std::ostringstream os;
    os << "| key | type | default | profiles ideal; harsh | range / choices | unit | meaning |\n";
    os << "|---|---|---|---|---|---|---|\n";
    for (const auto& s : scenario_schema()) {
        std::string range;
        if (s.type == KeyType::Enum) {
            range = s.choices;
        } else if (s.type == KeyType::Float || s.type == KeyType::Int || s.type == KeyType::Float3 || s.type == KeyType::Profile) {
            std::ostringstream r;
            r.precision(10);
            r << s.min << " .. " << s.max;
            range = r.str();
        }
        const char* tn = "";
        switch (s.type) {
        case KeyType::Float: tn = "float"; break;
        case KeyType::Int: tn = "int"; break;
        case KeyType::Bool: tn = "bool"; break;
        case KeyType::String: tn = std::string(s.key) == "metrics.window" ? "array of tables" : "string"; break;
        case KeyType::Enum: tn = "string"; break;
        case KeyType::Float3: tn = "float[3]"; break;
        case KeyType::Profile: tn = "profile"; break;
        }
        std::string def = s.def && s.def[0] ? s.def : (s.shown_default ? s.shown_default : "(preset)");
        if (std::string(s.key) == "metrics.window") def = "none";
        std::string range_esc = range;
        for (size_t p = 0; (p = range_esc.find('|', p)) != std::string::npos; p += 2) range_esc.replace(p, 1, "\\|");
        std::string unit = s.unit;
        for (size_t p = 0; (p = unit.find('|', p)) != std::string::npos; p += 2) unit.replace(p, 1, "\\|");
        std::string prof;
        if (s.def_ideal) prof = std::string("ideal `") + s.def_ideal + "`";
        if (s.def_harsh) prof += std::string(prof.empty() ? "" : "; ") + "harsh `" + (s.def_harsh[0] ? s.def_harsh : "(derived)") + "`";
        os << "| `" << s.key << "` | " << tn << " | `" << def << "` | " << prof << " | "
           << range_esc << " | " << unit << " | " << s.doc << " |\n";
    }
    return os.str();
}

}  // namespace mcsim
