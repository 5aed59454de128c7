// fluxmap-invert: invert a flux map psi(i) into a current map i(psi) (thesis Fig. 4.3).
//   fluxmap-invert IN_psi_of_i.csv OUT_i_of_psi.csv [--grid Nd Nq]
//   fluxmap-invert --from-preset NAME OUT.csv [--grid Nd Nq] [--imax A] [--n N] [--save-forward F.csv]
// Exit status: 0 success, 1 some nodes did not converge (the table is still written, the nodes
// are listed), 2 bad input or usage (also: a grid beyond kMaxGrid points per axis, an input file
// that is not a regular file or beyond kMaxInputBytes, a constant or degenerate flux map).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <new>
#include <string>
#include <vector>

#include "mcsim/fluxmap.hpp"
#include "mcsim/text.hpp"
#include "mcsim/machine.hpp"

namespace {

// Largest grid per axis (output --grid, --n, and an input grid used as the output's default):
// 1001 x 1001 nodes invert in well under a minute; beyond that only memory and time grow.
constexpr int kMaxGrid = 1001;
constexpr double kMaxImax = 1e6;                               // [A]
constexpr std::uintmax_t kMaxInputBytes = std::uintmax_t(256) << 20;  // a 1001^2 CSV is ~80 MB

constexpr const char* kUsage =
    "usage: fluxmap-invert IN_psi_of_i.csv OUT_i_of_psi.csv [--grid Nd Nq]\n"
    "       fluxmap-invert --from-preset NAME OUT_i_of_psi.csv [--grid Nd Nq] [--imax A] [--n N]\n"
    "                      [--save-forward OUT_psi_of_i.csv]\n"
    "  --grid Nd Nq   points of the output psi_d x psi_q grid, 2..1001 each (default: those of the\n"
    "                 input grid); the psi range is the extent of the input psi values\n"
    "  --from-preset  tabulate the preset's analytic model on i_d, i_q in [-imax, imax] with N\n"
    "                 points per axis (default imax = 1.5 * i_rated_peak, N = 81; N in 2..1001,\n"
    "                 imax <= 1e6 A), then invert\n"
    "The input must be a regular file of at most 256 MiB with a flux map that is not constant and\n"
    "not degenerate (psi_d and psi_q must both vary, and not only together).\n"
    "CSV formats: see docs/machine-models.md (header i_d_A,i_q_A,psi_d_Wb,psi_q_Wb for psi(i)).\n";

struct BadInput : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// An argument as shown in a message: printable ASCII, the rest as \xNN, at most 80 characters.
std::string shown(const std::string& s) { return mcsim::shown_text(s, false); }

int parse_int(const std::string& opt, const char* s, int lo, int hi) {
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || errno == ERANGE || v < lo || v > hi)
        throw BadInput(opt + ": '" + shown(s) + "' is not an integer in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]");
    return int(v);
}

double parse_pos(const std::string& opt, const char* s, double hi) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (*s == '\0' || *end != '\0' || !(v > 0) || !(v <= hi)) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", hi);
        throw BadInput(opt + ": '" + shown(s) + "' is not a number in (0, " + buf + "]");
    }
    return v;
}

// An input file: a regular file (not a device such as /dev/zero, a FIFO or a directory) of at most
// kMaxInputBytes.
void check_input_file(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw BadInput(shown(path) + ": cannot open (no such file)");
    if (!fs::is_regular_file(st)) throw BadInput(shown(path) + ": not a regular file");
    const auto size = fs::file_size(path, ec);
    if (!ec && size > kMaxInputBytes)
        throw BadInput(shown(path) + ": " + std::to_string(size) + " bytes, more than the limit of " +
                       std::to_string(kMaxInputBytes) + " bytes");
}

// A flux map the inversion can work on: finite values, psi_d and psi_q both varying over the grid
// (else the psi grid has zero extent), and a bilinear Jacobian that is not singular in every cell
// (else no psi point has a unique current: e.g. psi_d and psi_q functions of i_d + i_q only).
void check_flux_map(const mcsim::FluxMapTable& f, const std::string& what) {
    if (!f.out_d.allFinite() || !f.out_q.allFinite())
        throw BadInput(what + ": the flux map has non-finite values (NaN or inf)");
    const double d_lo = f.out_d.minCoeff(), d_hi = f.out_d.maxCoeff();
    const double q_lo = f.out_q.minCoeff(), q_hi = f.out_q.maxCoeff();
    const double scale = std::max({std::fabs(d_lo), std::fabs(d_hi), std::fabs(q_lo), std::fabs(q_hi)});
    auto flat = [&](double lo, double hi) { return !(hi - lo > 1e-12 * scale) || !(hi > lo); };
    if (flat(d_lo, d_hi) || flat(q_lo, q_hi)) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "psi_d spans [%.6g, %.6g] Wb, psi_q [%.6g, %.6g] Wb", d_lo, d_hi, q_lo, q_hi);
        throw BadInput(what + ": the flux map is constant along psi_d or psi_q (" + buf +
                       "); a psi grid needs both to vary");
    }
    if (!(std::isfinite(d_hi - d_lo) && std::isfinite(q_hi - q_lo)))
        throw BadInput(what + ": the flux values span more than a double can hold");
    // |det J| at every cell centre against the map's typical gradient scale
    const double hx = f.x.step(), hy = f.y.step();
    const double ref = (d_hi - d_lo) / (f.x.hi - f.x.lo) * (q_hi - q_lo) / (f.y.hi - f.y.lo);
    if (!(std::isfinite(ref) && ref > 0 && std::isfinite(1.0 / hx) && std::isfinite(1.0 / hy)))
    {
        char buf[256];
        std::snprintf(buf, sizeof buf, "current spacing %.6g x %.6g A, flux spans %.6g and %.6g Wb", hx, hy,
                      d_hi - d_lo, q_hi - q_lo);
        throw BadInput(what + ": the flux map is degenerate: " + buf + " give no usable gradient (under- or overflow)");
    }
    double det_max = 0;
    for (int i = 0; i + 1 < f.x.n; ++i)
        for (int j = 0; j + 1 < f.y.n; ++j) {
            auto ddx = [&](const Eigen::MatrixXd& m) { return 0.5 * (m(i + 1, j) - m(i, j) + m(i + 1, j + 1) - m(i, j + 1)) / hx; };
            auto ddy = [&](const Eigen::MatrixXd& m) { return 0.5 * (m(i, j + 1) - m(i, j) + m(i + 1, j + 1) - m(i + 1, j)) / hy; };
            det_max = std::max(det_max, std::fabs(ddx(f.out_d) * ddy(f.out_q) - ddy(f.out_d) * ddx(f.out_q)));
        }
    if (!(det_max > 1e-9 * ref))
        throw BadInput(what + ": the flux map is degenerate: its Jacobian d psi / d i is singular in every cell "
                       "(psi_d and psi_q do not vary independently), so it has no inverse");
}

int run(int argc, char** argv) {
    using namespace mcsim;
    std::vector<std::string> pos;
    std::string preset, save_forward;
    int nd = 0, nq = 0, n_i = 81;
    double imax = 0;
    try {
        for (int k = 1; k < argc; ++k) {
            const std::string a = argv[k];
            auto need = [&](int count) {
                if (k + count >= argc) throw BadInput(a + ": needs " + std::to_string(count) + " value(s)");
            };
            if (a == "-h" || a == "--help") {
                std::fputs(kUsage, stdout);
                return 0;
            } else if (a == "--grid") {
                need(2);
                nd = parse_int(a, argv[++k], 2, kMaxGrid);
                nq = parse_int(a, argv[++k], 2, kMaxGrid);
            } else if (a == "--from-preset") {
                need(1);
                preset = argv[++k];
            } else if (a == "--imax") {
                need(1);
                imax = parse_pos(a, argv[++k], kMaxImax);
            } else if (a == "--n") {
                need(1);
                n_i = parse_int(a, argv[++k], 2, kMaxGrid);
            } else if (a == "--save-forward") {
                need(1);
                save_forward = argv[++k];
            } else if (a.size() > 1 && a[0] == '-') {
                throw BadInput("unknown option " + shown(a));
            } else {
                pos.push_back(a);
            }
        }
        const size_t want = preset.empty() ? 2 : 1;
        if (pos.size() != want)
            throw BadInput("expected " + std::string(preset.empty() ? "IN.csv OUT.csv" : "OUT.csv") + ", got " +
                           std::to_string(pos.size()) + " file argument(s)");
        if (preset.empty() && (imax > 0 || !save_forward.empty()))
            throw BadInput("--imax/--save-forward only apply with --from-preset");
    } catch (const BadInput& e) {
        std::fprintf(stderr, "fluxmap-invert: %s\n%s", e.what(), kUsage);
        return 2;
    }

    FluxMapTable fwd;
    try {
        if (preset.empty()) {
            check_input_file(pos[0]);
            fwd = read_table_csv(pos[0]);
            if (fwd.kind != TableKind::FluxOfCurrent)
                throw std::runtime_error(pos[0] + ": is a current map i(psi); the input must be a flux map psi(i)");
            check_flux_map(fwd, shown(pos[0]));
        } else {
            const MachineParams mp = load_machine_preset(preset);
            if (imax <= 0) imax = 1.5 * mp.i_rated_peak;
            const auto model = make_preset_model(mp);
            const GridAxis ax{-imax, imax, n_i};
            fwd = tabulate_flux_map(*model, ax, ax);
            check_flux_map(fwd, "preset " + shown(preset));
            if (!save_forward.empty()) write_table_csv(save_forward, fwd);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fluxmap-invert: %s\n", e.what());
        return 2;
    }
    if ((nd == 0 && fwd.x.n > kMaxGrid) || (nq == 0 && fwd.y.n > kMaxGrid)) {
        std::fprintf(stderr, "fluxmap-invert: the input grid is %d x %d; the output grid (by default the input's) is "
                     "limited to %d points per axis: pass --grid Nd Nq\n", fwd.x.n, fwd.y.n, kMaxGrid);
        return 2;
    }
    const auto [ad, aq] = flux_extent_axes(fwd, nd > 0 ? nd : fwd.x.n, nq > 0 ? nq : fwd.y.n);
    const InversionResult inv = invert_flux_map(fwd, ad, aq);
    try {
        write_table_csv(pos.back(), inv.table);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fluxmap-invert: %s\n", e.what());
        return 2;
    }
    std::printf("fluxmap-invert: %d x %d nodes, psi_d [%.6g, %.6g] Wb, psi_q [%.6g, %.6g] Wb\n", ad.n, aq.n, ad.lo,
                ad.hi, aq.lo, aq.hi);
    std::printf("  converged %d, not converged %zu, extrapolated beyond the input current grid %d\n",
                ad.n * aq.n - int(inv.failed.size()), inv.failed.size(), inv.n_extrapolated);
    std::printf("  max residual %.3g Wb, max iterations %d\n", inv.max_residual, inv.max_iterations);
    constexpr size_t kListMax = 50;  // a degenerate map would otherwise list every node
    for (size_t k = 0; k < inv.failed.size() && k < kListMax; ++k) {
        const auto& p = inv.failed[k];
        std::fprintf(stderr, "  not converged: node (%d, %d) psi = (%.6g, %.6g) Wb, best i = (%.6g, %.6g) A, "
                     "residual %.3g Wb\n", p.ix, p.iy, p.psi.x(), p.psi.y(), p.i.x(), p.i.y(), p.residual);
    }
    if (inv.failed.size() > kListMax)
        std::fprintf(stderr, "  ... and %zu more nodes not converged\n", inv.failed.size() - kListMax);
    return inv.failed.empty() ? 0 : 1;
}

}  // namespace

// Every exception ends here with a message and exit status 2 (bad input: a grid the inversion
// rejects, out of memory for a grid within the limits, ...), never as an uncaught abort.
int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "fluxmap-invert: out of memory (grid too large for this machine)\n");
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fluxmap-invert: %s\n", e.what());
        return 2;
    } catch (...) {
        std::fprintf(stderr, "fluxmap-invert: unexpected error\n");
        return 2;
    }
}
