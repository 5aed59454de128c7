// Flux-map tables, LUT inversion (thesis Fig. 4.3) and the table-based current-map model.
#include "mcsim/fluxmap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mcsim {
namespace {

// Edge-clamped cell index and the (unclamped) local co-ordinate in it; see Table2D doc.
struct CellPos {
    int k;
    double t;
};
CellPos locate(const GridAxis& a, double v) {
    const double u = (v - a.lo) / a.step();
    int k = static_cast<int>(std::floor(u));
    k = std::clamp(k, 0, a.n - 2);
    return {k, u - k};
}

void check_axis(const GridAxis& a, const char* what) {
    if (!a.valid() || !std::isfinite(a.lo) || !std::isfinite(a.hi))
        throw std::invalid_argument(std::string("grid axis ") + what + ": need n >= 2 and lo < hi (got n = " +
                                    std::to_string(a.n) + ", lo = " + std::to_string(a.lo) +
                                    ", hi = " + std::to_string(a.hi) + ")");
}

}  // namespace

Table2D::Table2D(TableKind k, const GridAxis& ax, const GridAxis& ay)
    : kind(k), x(ax), y(ay), out_d(Eigen::MatrixXd::Zero(ax.n, ay.n)), out_q(Eigen::MatrixXd::Zero(ax.n, ay.n)) {
    check_axis(ax, "x");
    check_axis(ay, "y");
}

Vec2 Table2D::eval(const Vec2& p) const {
    const CellPos cx = locate(x, p.x()), cy = locate(y, p.y());
    const double tx = cx.t, ty = cy.t;
    const int i = cx.k, j = cy.k;
    auto bil = [&](const Eigen::MatrixXd& f) {
        return (1 - tx) * (1 - ty) * f(i, j) + tx * (1 - ty) * f(i + 1, j) + (1 - tx) * ty * f(i, j + 1) +
               tx * ty * f(i + 1, j + 1);
    };
    return {bil(out_d), bil(out_q)};
}

Mat2 Table2D::jacobian(const Vec2& p) const {
    const CellPos cx = locate(x, p.x()), cy = locate(y, p.y());
    const double tx = cx.t, ty = cy.t, hx = x.step(), hy = y.step();
    const int i = cx.k, j = cy.k;
    auto ddx = [&](const Eigen::MatrixXd& f) {
        return ((1 - ty) * (f(i + 1, j) - f(i, j)) + ty * (f(i + 1, j + 1) - f(i, j + 1))) / hx;
    };
    auto ddy = [&](const Eigen::MatrixXd& f) {
        return ((1 - tx) * (f(i, j + 1) - f(i, j)) + tx * (f(i + 1, j + 1) - f(i + 1, j))) / hy;
    };
    Mat2 jac;
    jac << ddx(out_d), ddy(out_d), ddx(out_q), ddy(out_q);
    return jac;
}

bool Table2D::inside(const Vec2& p) const {
    return p.x() >= x.lo && p.x() <= x.hi && p.y() >= y.lo && p.y() <= y.hi;
}

FluxMapTable tabulate_flux_map(const FluxModel& m, const GridAxis& id, const GridAxis& iq) {
    FluxMapTable t(TableKind::FluxOfCurrent, id, iq);
    for (int a = 0; a < id.n; ++a) {
        Vec2 warm = m.flux(Vec2(id.at(a), iq.at(0)));
        for (int b = 0; b < iq.n; ++b) {
            const Vec2 i(id.at(a), iq.at(b));
            FluxSolveStats st;
            Vec2 psi = solve_flux(m, i, warm, &st);
            if (!st.converged) psi = m.flux(i);  // throws if even the continuation fails
            t.set_node(a, b, psi);
            warm = psi;
        }
    }
    return t;
}

std::pair<GridAxis, GridAxis> flux_extent_axes(const FluxMapTable& f, int n_d, int n_q) {
    return {GridAxis{f.out_d.minCoeff(), f.out_d.maxCoeff(), n_d}, GridAxis{f.out_q.minCoeff(), f.out_q.maxCoeff(), n_q}};
}

namespace {

struct LmOutcome {
    Vec2 i;
    double residual;
    int iterations;
    bool converged;
};

// Levenberg-Marquardt on r(i) = F(i) - psi* with F the bilinear forward table. With two
// unknowns and two equations the undamped step is Newton's; the Marquardt diagonal scaling
// keeps steps short where the interpolated map is nearly singular or we are far from the root.
LmOutcome solve_point(const FluxMapTable& f, const Vec2& target, const Vec2& start, double tol, int max_iter) {
    Vec2 i = start;
    Vec2 r = f.eval(i) - target;
    double rn = r.norm();
    double mu = 1e-3;
    int k = 0;
    for (; k < max_iter && rn > tol; ++k) {
        const Mat2 jac = f.jacobian(i);
        const Mat2 jtj = jac.transpose() * jac;
        const Vec2 g = jac.transpose() * r;
        bool accepted = false;
        for (int tries = 0; tries < 30 && !accepted; ++tries) {
            Mat2 a = jtj;
            a.diagonal() += mu * jtj.diagonal().cwiseMax(1e-300);
            const Vec2 step = a.ldlt().solve(-g);
            const Vec2 i_new = i + step;
            const Vec2 r_new = f.eval(i_new) - target;
            if (step.allFinite() && r_new.norm() < rn) {
                i = i_new;
                r = r_new;
                rn = r.norm();
                mu = std::max(mu / 10, 1e-12);
                accepted = true;
            } else {
                mu *= 10;
            }
        }
        if (!accepted) break;
    }
    return {i, rn, k, rn <= tol};
}

Vec2 nearest_node_argument(const Table2D& t, const Vec2& value) {
    double best = std::numeric_limits<double>::infinity();
    Vec2 arg(t.x.lo, t.y.lo);
    for (int a = 0; a < t.x.n; ++a)
        for (int b = 0; b < t.y.n; ++b) {
            const double d = (t.node(a, b) - value).squaredNorm();
            if (d < best) {
                best = d;
                arg = Vec2(t.x.at(a), t.y.at(b));
            }
        }
    return arg;
}

}  // namespace

InversionResult invert_flux_map(const FluxMapTable& psi_of_i, const GridAxis& psi_d, const GridAxis& psi_q,
                                const InversionOptions& opt) {
    if (psi_of_i.kind != TableKind::FluxOfCurrent)
        throw std::invalid_argument("invert_flux_map: input must be a psi(i) table (kind FluxOfCurrent)");
    InversionResult res;
    res.table = CurrentMapTable(TableKind::CurrentOfFlux, psi_d, psi_q);
    const double psi_scale = std::max(psi_of_i.out_d.cwiseAbs().maxCoeff(), psi_of_i.out_q.cwiseAbs().maxCoeff());
    const double tol = opt.tol_rel * std::max(psi_scale, 1e-300);
    // Column by column in psi_q, along psi_d inside a column: each node starts from its
    // neighbour's solution (the map is smooth, so that is close); the first node of a column
    // starts from the first node of the previous column.
    Vec2 column_start = nearest_node_argument(psi_of_i, Vec2(psi_d.at(0), psi_q.at(0)));
    for (int b = 0; b < psi_q.n; ++b) {
        Vec2 warm = column_start;
        for (int a = 0; a < psi_d.n; ++a) {
            const Vec2 target(psi_d.at(a), psi_q.at(b));
            LmOutcome o = solve_point(psi_of_i, target, warm, tol, opt.max_iter);
            if (!o.converged) {
                const LmOutcome o2 =
                    solve_point(psi_of_i, target, nearest_node_argument(psi_of_i, target), tol, opt.max_iter);
                if (o2.residual < o.residual) o = o2;
            }
            res.table.set_node(a, b, o.i);
            res.max_iterations = std::max(res.max_iterations, o.iterations);
            if (o.converged) {
                res.max_residual = std::max(res.max_residual, o.residual);
                if (!psi_of_i.inside(o.i)) ++res.n_extrapolated;
                warm = o.i;
            } else {
                res.failed.push_back({a, b, target, o.i, o.residual});
            }
            if (a == 0) column_start = o.converged ? o.i : column_start;
        }
    }
    return res;
}

TableModel::TableModel(CurrentMapTable i_of_psi) : t_(std::move(i_of_psi)) {
    if (t_.kind != TableKind::CurrentOfFlux)
        throw std::invalid_argument("TableModel: needs a current map i(psi) (kind CurrentOfFlux)");
    psi0_ = flux(Vec2::Zero());
}

Vec2 TableModel::flux_initial_guess(const Vec2& i) const { return nearest_node_argument(t_, i); }

double TableModel::energy(const Vec2& psi) const {
    // Breakpoints where the straight path psi0 -> psi crosses interior grid lines; between two
    // of them i(psi(s)) is bilinear in a line, i.e. quadratic in s, and i . dpsi/ds is quadratic,
    // so 2-point Gauss-Legendre per piece is exact.
    const Vec2 dpsi = psi - psi0_;
    std::vector<double> s{0.0, 1.0};
    auto add_crossings = [&](const GridAxis& a, double p0, double dp) {
        if (dp == 0) return;
        for (int k = 1; k < a.n - 1; ++k) {
            const double sk = (a.at(k) - p0) / dp;
            if (sk > 0 && sk < 1) s.push_back(sk);
        }
    };
    add_crossings(t_.x, psi0_.x(), dpsi.x());
    add_crossings(t_.y, psi0_.y(), dpsi.y());
    std::sort(s.begin(), s.end());
    const double g = 0.5 / std::sqrt(3.0);
    double w = 0;
    for (size_t k = 0; k + 1 < s.size(); ++k) {
        const double mid = 0.5 * (s[k] + s[k + 1]), half = s[k + 1] - s[k];
        for (double node : {mid - g * half, mid + g * half})
            w += 0.5 * half * t_.eval(psi0_ + node * dpsi).dot(dpsi);
    }
    return w;
}

FluxMapGridSpec default_flux_map_grid(double i_max, int n, double span_factor) {
    FluxMapGridSpec g;
    const double span = span_factor * i_max;
    g.i_d = GridAxis{-span, span, n};
    g.i_q = GridAxis{-span, span, n};
    return g;
}

std::unique_ptr<TableModel> make_table_model_from(const FluxModel& m, const FluxMapGridSpec& grid,
                                                  InversionResult* diagnostics) {
    const FluxMapTable fwd = tabulate_flux_map_cached(m, grid.i_d, grid.i_q);
    const int nd = grid.psi_d.n > 0 ? grid.psi_d.n : grid.i_d.n;
    const int nq = grid.psi_q.n > 0 ? grid.psi_q.n : grid.i_q.n;
    auto [ad, aq] = flux_extent_axes(fwd, nd, nq);
    if (grid.psi_d.hi > grid.psi_d.lo) ad = GridAxis{grid.psi_d.lo, grid.psi_d.hi, nd};
    if (grid.psi_q.hi > grid.psi_q.lo) aq = GridAxis{grid.psi_q.lo, grid.psi_q.hi, nq};
    InversionResult inv = invert_flux_map(fwd, ad, aq);
    if (!inv.failed.empty()) {
        const auto& p = inv.failed.front();
        throw std::runtime_error("make_table_model_from: flux-map inversion failed at " +
                                 std::to_string(inv.failed.size()) + " node(s), first at psi = (" +
                                 std::to_string(p.psi.x()) + ", " + std::to_string(p.psi.y()) +
                                 ") Wb, residual " + std::to_string(p.residual) + " Wb");
    }
    auto model = std::make_unique<TableModel>(inv.table);
    if (diagnostics) *diagnostics = std::move(inv);
    return model;
}

// ---------------------------------------------------------------- CSV

namespace {

const char* header_of(TableKind k) {
    return k == TableKind::FluxOfCurrent ? "i_d_A,i_q_A,psi_d_Wb,psi_q_Wb" : "psi_d_Wb,psi_q_Wb,i_d_A,i_q_A";
}

std::string strip(const std::string& s) {
    std::string out;
    for (char c : s)
        if (c != ' ' && c != '\t' && c != '\r') out += c;
    return out;
}

// Distinct values of a co-ordinate column, merged when closer than a tiny fraction of the span
// (text round-off), checked to be equally spaced.
GridAxis axis_from_values(std::vector<double> v, const std::string& where, const char* col) {
    std::sort(v.begin(), v.end());
    const double span = v.back() - v.front();
    std::vector<double> u;
    for (double x : v)
        if (u.empty() || x - u.back() > 1e-9 * span) u.push_back(x);
    if (u.size() < 2) throw std::runtime_error(where + ": column " + col + " needs at least 2 distinct values");
    const GridAxis a{u.front(), u.back(), int(u.size())};
    for (size_t k = 0; k < u.size(); ++k)
        if (std::abs(u[k] - a.at(int(k))) > 1e-6 * a.step())
            throw std::runtime_error(where + ": column " + col + " is not a regular grid (value " +
                                     std::to_string(u[k]) + " where " + std::to_string(a.at(int(k))) +
                                     " was expected)");
    return a;
}

}  // namespace

void write_table_csv(const std::string& path, const Table2D& t) {
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot open for writing");
    f << header_of(t.kind) << '\n';
    char buf[128];
    for (int a = 0; a < t.x.n; ++a)
        for (int b = 0; b < t.y.n; ++b) {
            std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g\n", t.x.at(a), t.y.at(b), t.out_d(a, b),
                          t.out_q(a, b));
            f << buf;
        }
    if (!f) throw std::runtime_error(path + ": write error");
}

Table2D read_table_csv(const std::string& path) {
    std::ifstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot open");
    std::string line;
    int lineno = 0;
    TableKind kind{};
    bool have_header = false;
    struct Row {
        double c[4];
        int line;
    };
    std::vector<Row> rows;
    while (std::getline(f, line)) {
        ++lineno;
        const std::string s = strip(line);
        if (s.empty() || s[0] == '#') continue;
        const std::string where = path + ":" + std::to_string(lineno);
        if (!have_header) {
            if (s == header_of(TableKind::FluxOfCurrent)) kind = TableKind::FluxOfCurrent;
            else if (s == header_of(TableKind::CurrentOfFlux)) kind = TableKind::CurrentOfFlux;
            else
                throw std::runtime_error(where + ": header '" + s + "' is neither '" +
                                         header_of(TableKind::FluxOfCurrent) + "' nor '" +
                                         header_of(TableKind::CurrentOfFlux) + "'");
            have_header = true;
            continue;
        }
        Row r{{0, 0, 0, 0}, lineno};
        std::stringstream ss(s);
        std::string cell;
        int n = 0;
        while (std::getline(ss, cell, ',')) {
            if (n >= 4) throw std::runtime_error(where + ": more than 4 columns");
            char* end = nullptr;
            r.c[n] = std::strtod(cell.c_str(), &end);
            if (cell.empty() || *end != '\0' || !std::isfinite(r.c[n]))
                throw std::runtime_error(where + ": column " + std::to_string(n + 1) + " value '" + cell +
                                         "' is not a finite number");
            ++n;
        }
        if (n != 4) throw std::runtime_error(where + ": expected 4 columns, got " + std::to_string(n));
        rows.push_back(r);
    }
    if (!have_header) throw std::runtime_error(path + ": empty file (no header line)");
    std::vector<double> xs, ys;
    for (const Row& r : rows) {
        xs.push_back(r.c[0]);
        ys.push_back(r.c[1]);
    }
    if (rows.size() < 4) throw std::runtime_error(path + ": need at least a 2 x 2 grid of rows");
    const GridAxis ax = axis_from_values(xs, path, "1"), ay = axis_from_values(ys, path, "2");
    if (size_t(ax.n) * size_t(ay.n) != rows.size())
        throw std::runtime_error(path + ": " + std::to_string(rows.size()) + " rows do not fill the " +
                                 std::to_string(ax.n) + " x " + std::to_string(ay.n) + " grid");
    Table2D t(kind, ax, ay);
    Eigen::MatrixXi seen = Eigen::MatrixXi::Zero(ax.n, ay.n);
    for (const Row& r : rows) {
        const int a = int(std::lround((r.c[0] - ax.lo) / ax.step()));
        const int b = int(std::lround((r.c[1] - ay.lo) / ay.step()));
        if (seen(a, b)++)
            throw std::runtime_error(path + ":" + std::to_string(r.line) + ": duplicate grid node (" +
                                     std::to_string(r.c[0]) + ", " + std::to_string(r.c[1]) + ")");
        t.set_node(a, b, Vec2(r.c[2], r.c[3]));
    }
    return t;
}

}  // namespace mcsim
