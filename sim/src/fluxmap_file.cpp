// Measured flux maps (sim/include/mcsim/fluxmap_file.hpp): the checked reader and the map model.
// The same checks, in the same order and with the same messages, are in tools/mctools/fluxmap.py.
#include "mcsim/fluxmap_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mcsim {
namespace {

constexpr std::uintmax_t kMaxMapBytes = std::uintmax_t(16) << 20;  // a 401 x 401 map is ~13 MB
const char* const kColumn[4] = {"i_d_A", "i_q_A", "psi_d_Vs", "psi_q_Vs"};

std::string num(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.10g", v);
    return b;
}

std::string strip(const std::string& s) {
    std::string out;
    for (char c : s)
        if (c != ' ' && c != '\t' && c != '\r') out += c;
    return out;
}

// A decimal number: [+-]digits[.digits][e[+-]digits] (no nan/inf spellings, no hex, no '_').
bool decimal(const std::string& s) {
    size_t k = 0, n = s.size();
    if (k < n && (s[k] == '+' || s[k] == '-')) ++k;
    size_t digits = 0;
    while (k < n && std::isdigit(static_cast<unsigned char>(s[k]))) ++k, ++digits;
    if (k < n && s[k] == '.') {
        ++k;
        while (k < n && std::isdigit(static_cast<unsigned char>(s[k]))) ++k, ++digits;
    }
    if (digits == 0) return false;
    if (k < n && (s[k] == 'e' || s[k] == 'E')) {
        ++k;
        if (k < n && (s[k] == '+' || s[k] == '-')) ++k;
        size_t e = 0;
        while (k < n && std::isdigit(static_cast<unsigned char>(s[k]))) ++k, ++e;
        if (e == 0) return false;
    }
    return k == n;
}

struct Row {
    double c[4];
    int line;
};

// The distinct values of one co-ordinate (merged within 1e-9 of the span: text round-off), checked
// to be equally spaced; `first_line` gives the line that introduced each value, for the message.
GridAxis axis_of(const std::vector<Row>& rows, int col, const std::string& file) {
    std::map<double, int> first_line;
    for (const Row& r : rows)
        if (!first_line.count(r.c[col])) first_line[r.c[col]] = r.line;
    const double span = first_line.rbegin()->first - first_line.begin()->first;
    std::vector<std::pair<double, int>> u;
    for (const auto& [v, line] : first_line)
        if (u.empty() || v - u.back().first > 1e-9 * span) u.emplace_back(v, line);
    if (u.size() < 3)
        throw std::runtime_error(file + ": column " + kColumn[col] + " has " + std::to_string(u.size()) +
                                 " distinct value(s); a map needs at least 3 grid points per axis");
    const GridAxis a{u.front().first, u.back().first, int(u.size())};
    for (size_t k = 0; k < u.size(); ++k)
        if (std::abs(u[k].first - a.at(int(k))) > 1e-6 * a.step())
            throw std::runtime_error(file + ":" + std::to_string(u[k].second) + ": " + kColumn[col] + " = " +
                                     num(u[k].first) + " is off the equally spaced grid (" + num(a.at(int(k))) +
                                     " expected: " + std::to_string(a.n) + " points from " + num(a.lo) + " to " +
                                     num(a.hi) + "); the grid must be rectangular and equally spaced");
    return a;
}

}  // namespace

FluxMapData read_flux_map_file(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw std::runtime_error(path + ": no such flux-map file (or not a regular file)");
    const auto size = fs::file_size(path, ec);
    if (!ec && size > kMaxMapBytes)
        throw std::runtime_error(path + ": file of " + std::to_string(size) + " bytes is larger than the 16 MiB limit for a flux map");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error(path + ": cannot open flux-map file");

    std::vector<Row> rows;
    std::string line;
    int lineno = 0;
    bool have_header = false;
    while (std::getline(f, line)) {
        ++lineno;
        const std::string s = strip(line);
        if (s.empty() || s[0] == '#') continue;
        const std::string where = path + ":" + std::to_string(lineno) + ": ";
        if (!have_header) {
            if (s != kFluxMapFileHeader)
                throw std::runtime_error(where + "header '" + line.substr(0, 80) + "' is not '" + kFluxMapFileHeader + "'");
            have_header = true;
            continue;
        }
        Row r{{0, 0, 0, 0}, lineno};
        std::vector<std::string> cells;
        std::stringstream ss(s);
        std::string cell;
        while (std::getline(ss, cell, ',')) cells.push_back(cell);
        if (!s.empty() && s.back() == ',') cells.push_back("");
        if (cells.size() != 4)
            throw std::runtime_error(where + "expected 4 columns (" + kFluxMapFileHeader + "), got " +
                                     std::to_string(cells.size()));
        for (int k = 0; k < 4; ++k) {
            const double v = decimal(cells[size_t(k)]) ? std::strtod(cells[size_t(k)].c_str(), nullptr) : NAN;
            if (!std::isfinite(v))
                throw std::runtime_error(where + "column " + kColumn[k] + ": '" + cells[size_t(k)].substr(0, 40) +
                                         "' is not a finite number");
            r.c[k] = v;
        }
        rows.push_back(r);
    }
    if (!have_header) throw std::runtime_error(path + ": empty file (no header line '" + kFluxMapFileHeader + "')");
    if (rows.empty()) throw std::runtime_error(path + ": no data rows after the header");

    const GridAxis ax = axis_of(rows, 0, path), ay = axis_of(rows, 1, path);
    FluxMapData d;
    d.file = path;
    d.table = FluxMapTable(TableKind::FluxOfCurrent, ax, ay);
    Eigen::MatrixXi line_of = Eigen::MatrixXi::Zero(ax.n, ay.n);
    for (const Row& r : rows) {
        const int a = int(std::lround((r.c[0] - ax.lo) / ax.step()));
        const int b = int(std::lround((r.c[1] - ay.lo) / ay.step()));
        if (line_of(a, b))
            throw std::runtime_error(path + ":" + std::to_string(r.line) + ": duplicate grid point (i_d, i_q) = (" +
                                     num(ax.at(a)) + ", " + num(ay.at(b)) + ") A, first given on line " +
                                     std::to_string(line_of(a, b)));
        line_of(a, b) = r.line;
        d.table.set_node(a, b, Vec2(r.c[2], r.c[3]));
    }
    for (int a = 0; a < ax.n; ++a)
        for (int b = 0; b < ay.n; ++b)
            if (!line_of(a, b))
                throw std::runtime_error(path + ": no row for grid point (i_d, i_q) = (" + num(ax.at(a)) + ", " +
                                         num(ay.at(b)) + ") A: the " + std::to_string(ax.n) + " x " +
                                         std::to_string(ay.n) + " grid needs " + std::to_string(ax.n * ay.n) +
                                         " rows, the file has " + std::to_string(rows.size()));
    // psi_d rises with i_d at every i_q, psi_q with i_q at every i_d (positive differential
    // self-inductance: the map can be inverted along each axis)
    for (int b = 0; b < ay.n; ++b)
        for (int a = 1; a < ax.n; ++a)
            if (!(d.table.out_d(a, b) > d.table.out_d(a - 1, b)))
                throw std::runtime_error(path + ":" + std::to_string(line_of(a, b)) + ": psi_d_Vs = " +
                                         num(d.table.out_d(a, b)) + " does not rise with i_d (" +
                                         num(d.table.out_d(a - 1, b)) + " at i_d = " + num(ax.at(a - 1)) +
                                         " A, line " + std::to_string(line_of(a - 1, b)) + "; i_q = " +
                                         num(ay.at(b)) + " A): psi_d must increase strictly along i_d");
    for (int a = 0; a < ax.n; ++a)
        for (int b = 1; b < ay.n; ++b)
            if (!(d.table.out_q(a, b) > d.table.out_q(a, b - 1)))
                throw std::runtime_error(path + ":" + std::to_string(line_of(a, b)) + ": psi_q_Vs = " +
                                         num(d.table.out_q(a, b)) + " does not rise with i_q (" +
                                         num(d.table.out_q(a, b - 1)) + " at i_q = " + num(ay.at(b - 1)) +
                                         " A, line " + std::to_string(line_of(a, b - 1)) + "; i_d = " +
                                         num(ax.at(a)) + " A): psi_q must increase strictly along i_q");
    if (!(ax.lo <= 0 && ax.hi >= 0 && ay.lo <= 0 && ay.hi >= 0))
        throw std::runtime_error(path + ": the grid (i_d " + num(ax.lo) + " .. " + num(ax.hi) + " A, i_q " +
                                 num(ay.lo) + " .. " + num(ay.hi) +
                                 " A) does not contain i = 0: the PM flux cannot be read from it");
    const FluxMapTable& t = d.table;
    const Vec2 psi0 = t.eval(Vec2::Zero());
    if (!(psi0.x() > 0))
        throw std::runtime_error(path + ": psi_d(0, 0) = " + num(psi0.x()) +
                                 " Vs: no PM flux on +d (the convention: magnet flux along +d; rotate a map "
                                 "with the magnets on -q by i_d' = -i_q, i_q' = i_d, psi_d' = -psi_q, psi_q' = psi_d)");
    d.psi_pm = psi0.x();
    d.psi_q0 = psi0.y();
    const double hd = ax.step(), hq = ay.step();
    d.ld = (t.eval(Vec2(hd, 0)).x() - t.eval(Vec2(-hd, 0)).x()) / (2 * hd);
    d.lq = (t.eval(Vec2(0, hq)).y() - t.eval(Vec2(0, -hq)).y()) / (2 * hq);
    d.ldq = (t.eval(Vec2(0, hq)).x() - t.eval(Vec2(0, -hq)).x()) / (2 * hq);
    double sum2 = 0;
    int cells = 0;
    for (int a = 0; a + 1 < ax.n; ++a)
        for (int b = 0; b + 1 < ay.n; ++b) {
            const auto& pd = t.out_d;
            const auto& pq = t.out_q;
            const double l_dd = (pd(a + 1, b) - pd(a, b) + pd(a + 1, b + 1) - pd(a, b + 1)) / (2 * hd);
            const double l_qq = (pq(a, b + 1) - pq(a, b) + pq(a + 1, b + 1) - pq(a + 1, b)) / (2 * hq);
            const double l_dq = (pd(a, b + 1) - pd(a, b) + pd(a + 1, b + 1) - pd(a + 1, b)) / (2 * hq);
            const double l_qd = (pq(a + 1, b) - pq(a, b) + pq(a + 1, b + 1) - pq(a, b + 1)) / (2 * hd);
            const double rel = std::abs(l_dq - l_qd) / std::sqrt(l_dd * l_qq);
            sum2 += rel * rel;
            ++cells;
            if (cells == 1 || rel > d.recip_max) {
                d.recip_max = rel;
                d.recip_max_id = ax.at(a) + hd / 2;
                d.recip_max_iq = ay.at(b) + hq / 2;
            }
        }
    d.recip_rms = std::sqrt(sum2 / cells);
    if (d.recip_max > kFluxMapReciprocityWarn)
        d.warnings.push_back(path + ": reciprocity: d psi_d/d i_q and d psi_q/d i_d differ by up to " +
                             num(100 * d.recip_max) + " % of sqrt(l_dd l_qq) (rms " + num(100 * d.recip_rms) +
                             " %, worst in the cell around (" + num(d.recip_max_id) + ", " + num(d.recip_max_iq) +
                             ") A); above " + num(100 * kFluxMapReciprocityWarn) +
                             " % the map is not energy-consistent: the plant creates or loses energy on closed current paths");
    if (std::abs(d.psi_q0) > 0.05 * d.psi_pm)
        d.warnings.push_back(path + ": psi_q(0, 0) = " + num(d.psi_q0) + " Vs is more than 5 % of psi_d(0, 0) = " +
                             num(d.psi_pm) + " Vs: is the PM on +d (rotor angle offset)?");
    return d;
}

MeasuredMapModel::MeasuredMapModel(std::shared_ptr<const FluxMapData> map) : map_(std::move(map)) {
    const FluxMapTable& fwd = map_->table;
    const int nd = std::min(4 * (fwd.x.n - 1) + 1, 161), nq = std::min(4 * (fwd.y.n - 1) + 1, 161);
    const auto [ad, aq] = flux_extent_axes(fwd, nd, nq);
    InversionResult inv = invert_flux_map(fwd, ad, aq);
    if (!inv.failed.empty()) {
        const auto& p = inv.failed.front();
        throw std::runtime_error(map_->file + ": the map cannot be inverted to i(psi): " + std::to_string(inv.failed.size()) +
                                 " node(s) of the psi grid not reached, first psi = (" + num(p.psi.x()) + ", " +
                                 num(p.psi.y()) + ") Vs, residual " + num(p.residual) + " Vs");
    }
    inv_ = std::make_unique<TableModel>(std::move(inv.table));
}

}  // namespace mcsim
