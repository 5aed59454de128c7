// fluxmap-invert: invert a flux map psi(i) into a current map i(psi) (thesis Fig. 4.3).
//   fluxmap-invert IN_psi_of_i.csv OUT_i_of_psi.csv [--grid Nd Nq]
//   fluxmap-invert --from-preset NAME OUT.csv [--grid Nd Nq] [--imax A] [--n N] [--save-forward F.csv]
// Exit status: 0 success, 1 some nodes did not converge (the table is still written, the nodes
// are listed), 2 bad input or usage.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "mcsim/fluxmap.hpp"
#include "mcsim/machine.hpp"

namespace {

constexpr const char* kUsage =
    "usage: fluxmap-invert IN_psi_of_i.csv OUT_i_of_psi.csv [--grid Nd Nq]\n"
    "       fluxmap-invert --from-preset NAME OUT_i_of_psi.csv [--grid Nd Nq] [--imax A] [--n N]\n"
    "                      [--save-forward OUT_psi_of_i.csv]\n"
    "  --grid Nd Nq   points of the output psi_d x psi_q grid (default: those of the input grid);\n"
    "                 the psi range is the extent of the input psi values\n"
    "  --from-preset  tabulate the preset's analytic model on i_d, i_q in [-imax, imax] with N\n"
    "                 points per axis (default imax = 1.5 * i_rated_peak, N = 81), then invert\n"
    "CSV formats: see docs/machine-models.md (header i_d_A,i_q_A,psi_d_Wb,psi_q_Wb for psi(i)).\n";

struct BadInput : std::runtime_error {
    using std::runtime_error::runtime_error;
};

int parse_int(const std::string& opt, const char* s, int lo) {
    char* end = nullptr;
    const long v = std::strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < lo || v > 100000)
        throw BadInput(opt + ": '" + s + "' is not an integer >= " + std::to_string(lo));
    return int(v);
}

double parse_pos(const std::string& opt, const char* s) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (*s == '\0' || *end != '\0' || !(v > 0)) throw BadInput(opt + ": '" + s + "' is not a number > 0");
    return v;
}

}  // namespace

int main(int argc, char** argv) {
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
                nd = parse_int(a, argv[++k], 2);
                nq = parse_int(a, argv[++k], 2);
            } else if (a == "--from-preset") {
                need(1);
                preset = argv[++k];
            } else if (a == "--imax") {
                need(1);
                imax = parse_pos(a, argv[++k]);
            } else if (a == "--n") {
                need(1);
                n_i = parse_int(a, argv[++k], 2);
            } else if (a == "--save-forward") {
                need(1);
                save_forward = argv[++k];
            } else if (a.size() > 1 && a[0] == '-') {
                throw BadInput("unknown option " + a);
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
            fwd = read_table_csv(pos[0]);
            if (fwd.kind != TableKind::FluxOfCurrent)
                throw std::runtime_error(pos[0] + ": is a current map i(psi); the input must be a flux map psi(i)");
        } else {
            const MachineParams mp = load_machine_preset(preset);
            if (imax <= 0) imax = 1.5 * mp.i_rated_peak;
            const auto model = make_preset_model(mp);
            const GridAxis ax{-imax, imax, n_i};
            fwd = tabulate_flux_map(*model, ax, ax);
            if (!save_forward.empty()) write_table_csv(save_forward, fwd);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fluxmap-invert: %s\n", e.what());
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
    for (const auto& p : inv.failed)
        std::fprintf(stderr, "  not converged: node (%d, %d) psi = (%.6g, %.6g) Wb, best i = (%.6g, %.6g) A, "
                     "residual %.3g Wb\n", p.ix, p.iy, p.psi.x(), p.psi.y(), p.i.x(), p.i.y(), p.residual);
    return inv.failed.empty() ? 0 : 1;
}
