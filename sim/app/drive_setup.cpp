#include "drive_setup.hpp"

#include <cmath>
#include <deque>
#include <cstdio>
#include <sstream>

#include "metrics.hpp"

namespace mcsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

bool is_drive_key(const mc_param_info_t& e)
{
    const std::string n = e.name;
    return n.rfind("motor.", 0) != 0 && n.rfind("hw.", 0) != 0;
}

std::string number(double v)
{
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

double nice_up(double x)
{
    static const double steps[] = {1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8, 10};
    if (!(x > 0) || !std::isfinite(x)) return x;
    const double dec = std::pow(10.0, std::floor(std::log10(x)));
    for (double s : steps)
        if (s * dec >= x * (1 - 1e-12)) return s * dec;
    return 10 * dec;
}

// hw.* and motor.* entries stand for these scenario keys.
struct Alias {
    int param;
    const char* key;
};
const Alias kAliases[] = {
    {MC_PARAM_hw_i_span_a, "sensors.i_full_scale_a"},    {MC_PARAM_hw_vdc_span_v, "sensors.vdc_full_scale_v"},
    {MC_PARAM_hw_adc_bits, "sensors.adc_bits"},        {MC_PARAM_hw_vdc_nominal_v, "inverter.vdc_v"},
    {MC_PARAM_hw_dead_time_s, "inverter.dead_time_s"},   {MC_PARAM_hw_encoder_lines, "sensors.encoder_lines"},
    {MC_PARAM_hw_device_drop_v, "inverter.device_drop_v"},
    {MC_PARAM_hw_encoder_offset_rad, "sensors.encoder_offset_deg"}, {MC_PARAM_motor_inertia_kgm2, "mechanics.inertia_kgm2"},
};

}  // namespace

const std::vector<KeySpec>& drive_key_specs()
{
    static std::deque<std::string> text;  // storage for the generated strings
    static const std::vector<KeySpec> specs = [] {
        std::vector<KeySpec> out;
        for (int k = 0; k < static_cast<int>(MC_PARAM_COUNT); ++k) {
            const mc_param_info_t& e = mc_param_table[k];
            if (!is_drive_key(e)) continue;
            KeySpec s{};
            s.key = e.name;
            s.unit = e.unit;
            s.min = e.min;
            s.max = e.max;
            s.def_ideal = nullptr;
            s.def = "";  // the firmware applies its own default: only given keys are passed on
            std::string doc = e.doc;
            switch (static_cast<mc_param_type_t>(e.type)) {
            case MC_PT_F32: s.type = KeyType::Float; break;
            case MC_PT_I32: s.type = KeyType::Int; break;
            case MC_PT_BOOL: s.type = KeyType::Bool; break;
            case MC_PT_ENUM: {
                s.type = KeyType::Enum;
                std::string c = e.choices;
                if (!c.empty() && c.back() == '|') c.pop_back();
                text.push_back(c);
                s.choices = text.back().c_str();
                break;
            }
            }
            std::string shown;
            if (e.rule != MC_RULE_NONE) {
                shown = "(derived)";
            } else if (e.type == MC_PT_ENUM) {
                mc_params_t p;
                mc_params_default(&p);
                char buf[64];
                mc_param_choice_text(&p, k, buf, sizeof buf);
                shown = std::string("\"") + buf + "\"";
            } else if (e.type == MC_PT_BOOL) {
                shown = e.def != 0 ? "true" : "false";
            } else {
                shown = number(e.def);
            }
            text.push_back(shown);
            s.shown_default = text.back().c_str();
            text.push_back(doc + " [firmware parameter " + std::to_string(k) + ", group " +
                           mc_param_group_name(static_cast<mc_param_group_t>(e.group)) + "]");
            s.doc = text.back().c_str();
            out.push_back(s);
        }
        return out;
    }();
    return specs;
}

double default_i_full_scale(const MachineParams& mp) { return nice_up(1.875 * mp.i_rated_peak); }
double default_vdc_full_scale(double vdc_nominal) { return nice_up(1.6 * vdc_nominal); }

std::string scenario_key_of(int param)
{
    for (const Alias& a : kAliases)
        if (a.param == param) return a.key;
    if (param < 0 || param >= static_cast<int>(MC_PARAM_COUNT)) return "?";
    const std::string n = mc_param_table[param].name;
    if (n.rfind("motor.", 0) == 0) return "machine.preset (" + n.substr(6) + ")";
    return n;
}

static void set_or_throw(const Scenario& sc, mc_params_t* p, int id, double v, const std::string& key)
{
    mc_param_err_t err{};
    if (!mc_param_set(p, id, static_cast<float>(v), &err))
        throw ScenarioError(sc.origin() + ": key '" + key + "' = " + json_number(v) + ": " + err.text);
}

void set_drive_params(const Scenario& sc, const MachineParams& mp, double vdc, double i_span, double vdc_span,
                      mc_params_t* p)
{
    const std::string preset = "machine.preset";
    // the motor: the model the controller gets is the preset's (the estimator's may be scaled)
    set_or_throw(sc, p, MC_PARAM_motor_pole_pairs, mp.pole_pairs, preset);
    set_or_throw(sc, p, MC_PARAM_motor_rs_ohm, mp.rs, preset);
    set_or_throw(sc, p, MC_PARAM_motor_ld_h, mp.ld, preset);
    set_or_throw(sc, p, MC_PARAM_motor_lq_h, mp.lq, preset);
    set_or_throw(sc, p, MC_PARAM_motor_psi_pm_wb, mp.psi_pm, preset);
    set_or_throw(sc, p, MC_PARAM_motor_i_rated_a, mp.i_rated_peak, preset);
    set_or_throw(sc, p, MC_PARAM_motor_torque_rated_nm, mp.torque_rated, preset);
    set_or_throw(sc, p, MC_PARAM_motor_inertia_kgm2, sc.has("mechanics.inertia_kgm2") ? sc.f("mechanics.inertia_kgm2") : mp.inertia,
                 "mechanics.inertia_kgm2");
    // the power stage and sensing, from the simulator's keys
    set_or_throw(sc, p, MC_PARAM_hw_vdc_nominal_v, vdc, "inverter.vdc_v");
    set_or_throw(sc, p, MC_PARAM_hw_adc_bits, static_cast<double>(sc.i("sensors.adc_bits")), "sensors.adc_bits");
    set_or_throw(sc, p, MC_PARAM_hw_i_span_a, i_span, "sensors.i_full_scale_a");
    set_or_throw(sc, p, MC_PARAM_hw_vdc_span_v, vdc_span, "sensors.vdc_full_scale_v");
    set_or_throw(sc, p, MC_PARAM_hw_dead_time_s, sc.f("inverter.dead_time_s"), "inverter.dead_time_s");
    set_or_throw(sc, p, MC_PARAM_hw_device_drop_v, sc.f("inverter.device_drop_v"), "inverter.device_drop_v");
    set_or_throw(sc, p, MC_PARAM_hw_encoder_lines, static_cast<double>(sc.i("sensors.encoder_lines")), "sensors.encoder_lines");
    set_or_throw(sc, p, MC_PARAM_hw_encoder_offset_rad, mp.pole_pairs * sc.f("sensors.encoder_offset_deg") * kPi / 180.0,
                 "sensors.encoder_offset_deg");
    set_or_throw(sc, p, MC_PARAM_control_ts_s, sc.has("control.ts_s") ? sc.f("control.ts_s") : 1.0 / mp.f_sample, "control.ts_s");
    // every drive key the scenario gives
    for (const KeySpec& s : drive_key_specs()) {
        if (!sc.has(s.key)) continue;
        const int id = mc_param_find(s.key);
        if (s.type == KeyType::Enum) {
            mc_param_err_t err{};
            if (!mc_param_set_choice(p, id, sc.s(s.key).c_str(), &err))
                throw ScenarioError(sc.origin() + ": key '" + s.key + "' = \"" + sc.s(s.key) + "\": " + err.text);
        } else {
            set_or_throw(sc, p, id, sc.f(s.key), s.key);
        }
    }
}

// A parameter's value as the scenario writes it (an ENUM by its choice).
static std::string shown(int param, float v)
{
    if (param >= 0 && param < static_cast<int>(MC_PARAM_COUNT) && mc_param_table[param].type == MC_PT_ENUM &&
        std::isfinite(v)) {
        mc_params_t p;
        mc_params_default(&p);
        mc_param_err_t err{};
        char buf[64];
        if (mc_param_set(&p, param, v, &err)) {
            mc_param_choice_text(&p, param, buf, sizeof buf);
            if (buf[0] != '\0') return std::string("\"") + buf + "\"";
        }
    }
    return number(v);
}

std::string explain_config_error(const Scenario& sc, const mc_param_err_t& e)
{
    std::ostringstream os;
    os << sc.origin() << ": ";
    if (e.param < 0) return os.str() + "the firmware refused the drive configuration: " + (e.text ? e.text : "");
    const std::string key = scenario_key_of(e.param);
    const bool derived = e.param < static_cast<int>(MC_PARAM_COUNT) && mc_param_table[e.param].rule != MC_RULE_NONE &&
                         !sc.has(mc_param_table[e.param].name);
    const bool is_enum = mc_param_table[e.param].type == MC_PT_ENUM;
    os << "key '" << key << "' = " << shown(e.param, e.value);
    if (derived) os << " (derived from the motor data)";
    os << ": " << (e.text ? e.text : "refused");
    if (e.kind == MC_PERR_CROSS && e.param2 >= 0) {
        os << "; key '" << scenario_key_of(e.param2) << "' = " << shown(e.param2, e.value2);
        if (!is_enum) os << "; allowed range [" << number(e.min) << ", " << number(e.max) << "]";
    } else if (e.kind == MC_PERR_RANGE || e.kind == MC_PERR_NOT_FINITE || (e.kind == MC_PERR_MODEL && !is_enum)) {
        os << "; allowed range [" << number(e.min) << ", " << number(e.max) << "]";
    }
    return os.str();
}

std::string params_markdown()
{
    static const char* access[] = {"init", "standstill", "runtime"};
    static const char* types[] = {"f32", "i32", "bool", "enum"};
    std::ostringstream os;
    char hash[16];
    std::snprintf(hash, sizeof hash, "0x%08x", static_cast<unsigned>(mc_params_table_hash()));
    os << "Generated by `mcsim params` from `firmware/app/include/mc/params_table.h` (" << MC_PARAM_COUNT
       << " entries, table hash " << hash << ").\n\n";
    os << "| id | object | name | type | unit | range / choices | default | group | access | meaning |\n";
    os << "|---|---|---|---|---|---|---|---|---|---|\n";
    mc_params_t defaults;
    mc_params_default(&defaults);
    for (int k = 0; k < static_cast<int>(MC_PARAM_COUNT); ++k) {
        const mc_param_info_t& e = mc_param_table[k];
        std::string range, def;
        if (e.type == MC_PT_ENUM) {
            range = e.choices;
            if (!range.empty() && range.back() == '|') range.pop_back();
            for (size_t p = 0; (p = range.find('|', p)) != std::string::npos; p += 2) range.replace(p, 1, "\\|");
            char buf[64];
            mc_param_choice_text(&defaults, k, buf, sizeof buf);
            def = std::string("`") + buf + "`";
        } else if (e.type == MC_PT_BOOL) {
            range = "false, true";
            def = e.def != 0 ? "`true`" : "`false`";
        } else {
            range = number(e.min) + " .. " + number(e.max);
            def = "`" + number(e.def) + "`";
        }
        if (e.rule != MC_RULE_NONE) def = "rule (" + def + " on the thesis motor)";
        char obj[16];
        std::snprintf(obj, sizeof obj, "0x%04X", 0x2000 + k);
        os << "| " << k << " | " << obj << " | `" << e.name << "` | " << types[e.type] << " | " << e.unit << " | "
           << range << " | " << def << " | " << mc_param_group_name(static_cast<mc_param_group_t>(e.group)) << " | "
           << access[e.access] << " | " << e.doc << " |\n";
    }
    return os.str();
}

}  // namespace mcsim
