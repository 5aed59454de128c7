// Machine preset loader (presets/*.toml, read by the Python tools with tomllib as well).
#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "mcsim/machine.hpp"

#ifndef MCSIM_PRESET_DIR
#define MCSIM_PRESET_DIR "presets"
#endif

namespace mcsim {
namespace {

bool file_exists(const std::string& p) { return std::ifstream(p).good(); }

// A bare name is looked up in the preset directory; anything that looks like a path (has a
// directory separator or the .toml suffix) is taken as given.
std::string resolve_preset(const std::string& name_or_path) {
    const bool looks_like_path = name_or_path.find('/') != std::string::npos ||
                                 (name_or_path.size() > 5 && name_or_path.rfind(".toml") == name_or_path.size() - 5);
    if (looks_like_path) return name_or_path;
    const std::string in_dir = std::string(MCSIM_PRESET_DIR) + "/" + name_or_path + ".toml";
    if (file_exists(in_dir)) return in_dir;
    throw std::runtime_error("machine preset '" + name_or_path + "' not found: no file " + in_dir);
}

std::string node_text(const toml::node& n) {
    std::ostringstream os;
    n.visit([&os](auto&& v) { os << v; });
    return os.str();
}

std::string type_name(const toml::node& n) {
    switch (n.type()) {
        case toml::node_type::string: return "string";
        case toml::node_type::integer: return "integer";
        case toml::node_type::floating_point: return "float";
        case toml::node_type::boolean: return "boolean";
        case toml::node_type::table: return "table";
        case toml::node_type::array: return "array";
        default: return "date/time";
    }
}

enum class Range { Positive, NonNegative, Finite };

class Reader {
public:
    Reader(std::string file, const toml::table& root) : file_(std::move(file)), root_(root) {}

    [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
        throw std::runtime_error(file_ + ": key '" + key + "': " + msg);
    }

    const toml::node& need(const toml::table& t, const std::string& prefix, const std::string& key) const {
        const toml::node* n = t.get(key);
        if (!n) fail(prefix + key, "missing");
        return *n;
    }

    double number(const toml::table& t, const std::string& prefix, const std::string& key, Range r) const {
        const toml::node& n = need(t, prefix, key);
        double v = 0;
        if (auto f = n.as_floating_point()) v = f->get();
        else if (auto i = n.as_integer()) v = double(i->get());
        else fail(prefix + key, "value " + node_text(n) + " is a " + type_name(n) + ", expected a number");
        const char* expected = nullptr;
        if (!std::isfinite(v)) expected = "a finite number";
        else if (r == Range::Positive && !(v > 0)) expected = "a number > 0";
        else if (r == Range::NonNegative && !(v >= 0)) expected = "a number >= 0";
        if (expected) fail(prefix + key, "value " + node_text(n) + " out of range, expected " + expected);
        return v;
    }

    int integer(const toml::table& t, const std::string& key, long lo, long hi) const {
        const toml::node& n = need(t, "", key);
        auto i = n.as_integer();
        if (!i) fail(key, "value " + node_text(n) + " is a " + type_name(n) + ", expected an integer");
        if (i->get() < lo || i->get() > hi)
            fail(key, "value " + node_text(n) + " out of range, expected an integer in [" + std::to_string(lo) +
                          ", " + std::to_string(hi) + "]");
        return int(i->get());
    }

    std::string string(const toml::table& t, const std::string& key) const {
        const toml::node& n = need(t, "", key);
        auto s = n.as_string();
        if (!s) fail(key, "value " + node_text(n) + " is a " + type_name(n) + ", expected a string");
        return s->get();
    }

    const toml::table& table(const std::string& key) const {
        const toml::node& n = need(root_, "", key);
        auto t = n.as_table();
        if (!t) fail(key, "value " + node_text(n) + " is a " + type_name(n) + ", expected a table [" + key + "]");
        return *t;
    }

    const toml::table& root() const { return root_; }

private:
    std::string file_;
    const toml::table& root_;
};

}  // namespace

MachineParams load_machine_preset(const std::string& name_or_path) {
    const std::string file = resolve_preset(name_or_path);
    if (!file_exists(file)) throw std::runtime_error(file + ": cannot open machine preset");
    toml::table root;
    try {
        root = toml::parse_file(file);
    } catch (const toml::parse_error& e) {
        std::ostringstream os;
        os << file << ":" << e.source().begin.line << ":" << e.source().begin.column << ": TOML syntax error: "
           << e.description();
        throw std::runtime_error(os.str());
    }
    const Reader rd(file, root);
    const toml::table& t = rd.root();
    MachineParams m;
    m.name = rd.string(t, "name");
    m.pole_pairs = rd.integer(t, "pole_pairs", 1, 100);
    m.rs = rd.number(t, "", "rs_ohm", Range::NonNegative);
    m.psi_pm = rd.number(t, "", "psi_pm_wb", Range::NonNegative);
    m.ld = rd.number(t, "", "ld_h", Range::Positive);
    m.lq = rd.number(t, "", "lq_h", Range::Positive);
    m.inertia = rd.number(t, "", "inertia_kgm2", Range::Positive);
    m.friction = rd.number(t, "", "friction_nms", Range::NonNegative);
    m.i_rated_peak = rd.number(t, "", "i_rated_peak_a", Range::Positive);
    m.torque_rated = rd.number(t, "", "torque_rated_nm", Range::Positive);
    m.vdc_nominal = rd.number(t, "", "vdc_nominal_v", Range::Positive);
    m.f_sample = rd.number(t, "", "f_sample_hz", Range::Positive);

    const toml::table& s = rd.table("saturation");
    const std::string sp = "saturation.";
    m.sat.S = rd.number(s, sp, "S", Range::NonNegative);
    m.sat.T = rd.number(s, sp, "T", Range::NonNegative);
    m.sat.U = rd.number(s, sp, "U", Range::NonNegative);
    m.sat.V = rd.number(s, sp, "V", Range::NonNegative);
    m.sat.a_d0 = rd.number(s, sp, "a_d0", Range::Positive);
    m.sat.a_dd = rd.number(s, sp, "a_dd", Range::NonNegative);
    m.sat.a_q0 = rd.number(s, sp, "a_q0", Range::Positive);
    m.sat.a_qq = rd.number(s, sp, "a_qq", Range::NonNegative);
    m.sat.a_dq = rd.number(s, sp, "a_dq", Range::NonNegative);
    m.sat.i_f = rd.number(s, sp, "i_f", Range::Finite);
    return m;
}

}  // namespace mcsim
