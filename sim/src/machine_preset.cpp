// Machine preset loader (presets/*.toml, read by the Python tools with tomllib as well).
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "mcsim/fluxmap_file.hpp"
#include "mcsim/machine.hpp"
#include "mcsim/text.hpp"

#ifndef MCSIM_PRESET_DIR
#define MCSIM_PRESET_DIR "presets"
#endif

namespace mcsim {
namespace {

bool file_exists(const std::string& p) { return std::ifstream(p).good(); }

// Largest preset file read (a preset is ~2 kB; this refuses /dev/zero and the like unread).
constexpr std::uintmax_t kMaxPresetBytes = std::uintmax_t(1) << 20;

std::string shown(const std::string& s) { return shown_text(s, true); }

// A bare name is looked up in the preset directory; anything that looks like a path (has a
// directory separator or the .toml suffix) is taken as given.
std::string resolve_preset(const std::string& name_or_path) {
    if (name_or_path.empty()) throw std::runtime_error("machine preset: empty name");
    for (const char c : name_or_path)
        if (static_cast<unsigned char>(c) < 0x20)
            throw std::runtime_error("machine preset '" + shown(name_or_path) +
                                     "': the name contains a control character or NUL byte");
    const bool looks_like_path = name_or_path.find('/') != std::string::npos ||
                                 (name_or_path.size() > 5 && name_or_path.rfind(".toml") == name_or_path.size() - 5);
    if (looks_like_path) return name_or_path;
    const std::string in_dir = std::string(MCSIM_PRESET_DIR) + "/" + name_or_path + ".toml";
    if (file_exists(in_dir)) return in_dir;
    throw std::runtime_error("machine preset '" + shown(name_or_path) + "' not found: no file " + shown(in_dir));
}

std::string node_text(const toml::node& n) {
    if (auto s = n.as_string()) return '"' + shown(s->get()) + '"';
    if (n.is_table()) return "(table)";
    std::ostringstream os;
    if (auto f = n.as_floating_point()) {
        os.precision(12);
        os << f->get();
        return os.str();
    }
    n.visit([&os](auto&& v) { os << v; });
    return shown(os.str());
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

// Plausible range of a preset number: lo < v (lo_open) or lo <= v, and v <= hi. The bounds are
// generous (from a few-watt servo to a traction machine); they exist to refuse typos and fuzz
// values such as 1e300 that would make the plant diverge.
struct Range {
    double lo;
    bool lo_open;
    double hi;
    const char* unit;
};
std::string num_text(double v) {
    std::ostringstream os;
    os.precision(10);
    os << v;
    return os.str();
}
std::string range_text(const Range& r) {
    return std::string(r.lo_open ? "> " : ">= ") + num_text(r.lo) + " and <= " + num_text(r.hi) +
           (r.unit[0] ? std::string(" ") + r.unit : std::string());
}

class Reader {
public:
    Reader(std::string file, const toml::table& root) : file_(std::move(file)), root_(root) {}

    [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
        throw std::runtime_error(file_ + ": key '" + shown(key) + "': " + msg);
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
        const bool ok = std::isfinite(v) && (r.lo_open ? v > r.lo : v >= r.lo) && v <= r.hi;
        if (!ok)
            fail(prefix + key, "value " + node_text(n) + " out of range, expected a finite number " + range_text(r) +
                                   " (allowed range of this preset key)");
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

    std::string string(const toml::table& t, const std::string& key, const std::string& prefix = "") const {
        const toml::node& n = need(t, prefix, key);
        auto s = n.as_string();
        if (!s) fail(prefix + key, "value " + node_text(n) + " is a " + type_name(n) + ", expected a string");
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
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::status(file, ec);
    if (ec || !fs::exists(st)) throw std::runtime_error(shown(file) + ": cannot open machine preset (no such file)");
    if (!fs::is_regular_file(st))
        throw std::runtime_error(shown(file) + ": not a regular file; a machine preset must be a TOML file");
    const auto size = fs::file_size(file, ec);
    if (!ec && size > kMaxPresetBytes)
        throw std::runtime_error(shown(file) + ": file of " + std::to_string(size) +
                                 " bytes is larger than the 1 MiB limit for a machine preset");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::runtime_error(shown(file) + ": cannot open machine preset");
    // read what is there, at most one byte past the limit (a 1 MiB buffer zeroed per run was a
    // tenth of a short simulation)
    std::string text;
    char chunk[16384];
    while (text.size() <= kMaxPresetBytes && (in.read(chunk, sizeof chunk) || in.gcount() > 0))
        text.append(chunk, size_t(in.gcount()));
    if (text.size() > kMaxPresetBytes)
        throw std::runtime_error(shown(file) + ": larger than the 1 MiB limit for a machine preset");
    toml::table root;
    try {
        root = toml::parse(text, file);
    } catch (const toml::parse_error& e) {
        std::ostringstream os;
        os << file << ":" << e.source().begin.line << ":" << e.source().begin.column << ": TOML syntax error: "
           << shown(std::string(e.description()));
        throw std::runtime_error(os.str());
    }
    const Reader rd(file, root);
    const toml::table& t = rd.root();
    MachineParams m;
    m.name = rd.string(t, "name");
    m.pole_pairs = rd.integer(t, "pole_pairs", 1, 100);
    // Plausible ranges; the scenario keys these defaults feed have their own (docs/simulator.md).
    m.rs = rd.number(t, "", "rs_ohm", {0, false, 100, "ohm"});
    // With a measured [flux_map], psi_pm_wb, ld_h, lq_h may be omitted: the map's values at i = 0.
    const bool has_map = t.contains("flux_map"), has_sat = t.contains("saturation");
    const Range r_psi{0, false, 10, "Wb"}, r_l{1e-7, false, 10, "H"};
    const bool map_psi = has_map && !t.contains("psi_pm_wb"), map_ld = has_map && !t.contains("ld_h"),
               map_lq = has_map && !t.contains("lq_h");
    if (!map_psi) m.psi_pm = rd.number(t, "", "psi_pm_wb", r_psi);
    if (!map_ld) m.ld = rd.number(t, "", "ld_h", r_l);
    if (!map_lq) m.lq = rd.number(t, "", "lq_h", r_l);
    m.inertia = rd.number(t, "", "inertia_kgm2", {1e-6, false, 1e3, "kg m^2"});
    m.friction = rd.number(t, "", "friction_nms", {0, false, 1e2, "N m s"});
    m.i_rated_peak = rd.number(t, "", "i_rated_peak_a", {0.01, false, 5000, "A"});
    m.torque_rated = rd.number(t, "", "torque_rated_nm", {1e-3, false, 1e5, "N m"});
    m.vdc_nominal = rd.number(t, "", "vdc_nominal_v", {1, false, 2000, "V"});
    m.f_sample = rd.number(t, "", "f_sample_hz", {100, false, 1e6, "Hz"});

    // The magnetics: an analytic [saturation] model or a measured [flux_map], exactly one.
    if (has_map && has_sat)
        rd.fail("flux_map", "a preset gives either [saturation] or [flux_map], not both");
    if (has_map) {
        const toml::table& fm = rd.table("flux_map");
        const std::string rel = rd.string(fm, "file", "flux_map.");
        if (rel.empty()) rd.fail("flux_map.file", "empty file name");
        namespace fs = std::filesystem;
        const fs::path p(rel);
        const std::string map_file = p.is_absolute() ? rel : (fs::path(file).parent_path() / p).string();
        std::shared_ptr<FluxMapData> map;
        try {
            map = std::make_shared<FluxMapData>(read_flux_map_file(map_file));
        } catch (const std::exception& e) {
            rd.fail("flux_map.file", e.what());
        }
        // psi_pm_wb, ld_h, lq_h: the map's values at i = 0 unless given
        if (map_psi) m.psi_pm = map->psi_pm;
        if (map_ld) m.ld = map->ld;
        if (map_lq) m.lq = map->lq;
        auto in_range = [](double v, const Range& r) { return std::isfinite(v) && v > r.lo && v <= r.hi; };
        if (!in_range(m.psi_pm, r_psi) || !in_range(m.ld, r_l) || !in_range(m.lq, r_l))
            rd.fail("flux_map.file", "the map's psi_pm = " + num_text(m.psi_pm) + " Wb, Ld = " + num_text(m.ld) +
                                         " H, Lq = " + num_text(m.lq) + " H at i = 0 are outside the preset ranges (" +
                                         range_text(r_psi) + ", " + range_text(r_l) + ")");
        m.flux_map = std::move(map);
        return m;
    }
    if (!has_sat) rd.fail("saturation", "missing (give an analytic [saturation] table or a measured [flux_map])");
    const toml::table& s = rd.table("saturation");
    const std::string sp = "saturation.";
    const Range exponent{0, false, 8, ""};
    m.sat.S = rd.number(s, sp, "S", exponent);
    m.sat.T = rd.number(s, sp, "T", exponent);
    m.sat.U = rd.number(s, sp, "U", exponent);
    m.sat.V = rd.number(s, sp, "V", exponent);
    m.sat.a_d0 = rd.number(s, sp, "a_d0", {0.1, false, 1e7, "1/H"});  // as ld_h: 0.1 uH .. 10 H
    m.sat.a_dd = rd.number(s, sp, "a_dd", {0, false, 1e12, "1/(H Wb^S)"});
    m.sat.a_q0 = rd.number(s, sp, "a_q0", {0.1, false, 1e7, "1/H"});
    m.sat.a_qq = rd.number(s, sp, "a_qq", {0, false, 1e12, "1/(H Wb^T)"});
    m.sat.a_dq = rd.number(s, sp, "a_dq", {0, false, 1e12, "1/(H Wb^(U+V+2))"});
    m.sat.i_f = rd.number(s, sp, "i_f", {-1e5, false, 1e5, "A"});
    return m;
}

}  // namespace mcsim
