// model-dump: evaluate a machine preset's magnetic model on a grid and print it as CSV, so that a
// second implementation (tools/mctools/machine.py) can be checked against the simulator's.
//   model-dump PRESET [--i ID IQ]... [--psi PD PQ]... [--i-grid] [--psi-grid PD_LO PD_HI PQ_LO PQ_HI]
//              [--imax A] [--n N]
// PRESET is a name (presets/NAME.toml) or a path. Without any --i/--psi/--i-grid/--psi-grid the
// current grid over [-imax, imax]^2 is printed (imax = 1.5 * i_rated_peak, N = 21 points per axis).
// Exit status: 0 success, 1 model evaluation failed (e.g. flux() did not converge), 2 bad usage or
// preset.
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "mcsim/machine.hpp"

namespace {

constexpr const char* kUsage =
    "usage: model-dump PRESET [--i ID IQ]... [--psi PD PQ]... [--i-grid]\n"
    "                  [--psi-grid PD_LO PD_HI PQ_LO PQ_HI] [--imax A] [--n N]\n"
    "  PRESET          preset name (presets/NAME.toml) or path to a .toml file\n"
    "  --i ID IQ       a current point [A] (repeatable): psi = flux(i)\n"
    "  --psi PD PQ     a flux-linkage point [Wb] (repeatable): i = current(psi)\n"
    "  --i-grid        N x N current grid over i_d, i_q in [-imax, imax] (the default when no point\n"
    "                  or grid is given)\n"
    "  --psi-grid ...  N x N flux grid over [PD_LO, PD_HI] x [PQ_LO, PQ_HI] [Wb]\n"
    "  --imax A        half-width of the current grid (default 1.5 * i_rated_peak of the preset)\n"
    "  --n N           points per grid axis, >= 2 (default 21)\n"
    "Output: CSV on stdout, one row per point, all numbers with 17 significant digits:\n"
    "  input           'i' (row from a current point: psi_d, psi_q = flux(i)) or\n"
    "                  'psi' (row from a flux point: i_d, i_q = current(psi))\n"
    "  i_d_A,i_q_A,psi_d_Wb,psi_q_Wb      the consistent pair (one of them is the input)\n"
    "  cur_d_A,cur_q_A                    current(psi) at the printed psi (the plant's evaluation)\n"
    "  g_dd,g_dq,g_qq [1/H]               Jacobian di/dpsi at psi (symmetric)\n"
    "  l_dd_H,l_dq_H,l_qq_H               differential inductances L = (di/dpsi)^-1 at psi\n"
    "  torque_Nm                          1.5 p (psi_d i_q - psi_q i_d)\n"
    "  energy_J                           W(psi) - W(flux(0)), without the 1.5 three-phase factor\n";

struct BadInput : std::runtime_error {
    using std::runtime_error::runtime_error;
};

double parse_num(const std::string& opt, const char* s) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (*s == '\0' || *end != '\0' || !std::isfinite(v))
        throw BadInput(opt + ": '" + s + "' is not a finite number");
    return v;
}

int parse_int(const std::string& opt, const char* s, int lo, int hi) {
    char* end = nullptr;
    const long v = std::strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < lo || v > hi)
        throw BadInput(opt + ": '" + s + "' is not an integer in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]");
    return int(v);
}

struct Point {
    bool is_current;  // true: (x, y) = (i_d, i_q); false: (psi_d, psi_q)
    double x, y;
};

double lin(double lo, double hi, int k, int n) {
    // Exact end points, symmetric grids through 0 when n is odd.
    if (k == n - 1) return hi;
    return lo + (hi - lo) * double(k) / double(n - 1);
}

}  // namespace

int main(int argc, char** argv) {
    using namespace mcsim;
    std::string preset;
    std::vector<Point> points;
    bool i_grid = false, psi_grid = false;
    double pd_lo = 0, pd_hi = 0, pq_lo = 0, pq_hi = 0, imax = 0;
    int n = 21;
    try {
        for (int k = 1; k < argc; ++k) {
            const std::string a = argv[k];
            auto need = [&](int count) {
                if (k + count >= argc) throw BadInput(a + ": needs " + std::to_string(count) + " value(s)");
            };
            if (a == "-h" || a == "--help") {
                std::fputs(kUsage, stdout);
                return 0;
            } else if (a == "--i" || a == "--psi") {
                need(2);
                const double x = parse_num(a, argv[++k]);
                const double y = parse_num(a, argv[++k]);
                points.push_back({a == "--i", x, y});
            } else if (a == "--i-grid") {
                i_grid = true;
            } else if (a == "--psi-grid") {
                need(4);
                pd_lo = parse_num(a, argv[++k]);
                pd_hi = parse_num(a, argv[++k]);
                pq_lo = parse_num(a, argv[++k]);
                pq_hi = parse_num(a, argv[++k]);
                if (!(pd_lo < pd_hi) || !(pq_lo < pq_hi))
                    throw BadInput("--psi-grid: need PD_LO < PD_HI and PQ_LO < PQ_HI");
                psi_grid = true;
            } else if (a == "--imax") {
                need(1);
                imax = parse_num(a, argv[++k]);
                if (!(imax > 0)) throw BadInput("--imax: must be > 0");
            } else if (a == "--n") {
                need(1);
                n = parse_int(a, argv[++k], 2, 10000);
            } else if (a.size() > 1 && a[0] == '-' && !(std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.')) {
                throw BadInput("unknown option " + a);
            } else if (preset.empty()) {
                preset = a;
            } else {
                throw BadInput("unexpected argument '" + a + "' (the preset is '" + preset + "')");
            }
        }
        if (preset.empty()) throw BadInput("no preset given");
    } catch (const BadInput& e) {
        std::fprintf(stderr, "model-dump: %s\n%s", e.what(), kUsage);
        return 2;
    }

    MachineParams mp;
    std::unique_ptr<FluxModel> model;
    try {
        mp = load_machine_preset(preset);
        model = make_preset_model(mp);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "model-dump: %s\n", e.what());
        return 2;
    }

    if (points.empty() && !psi_grid) i_grid = true;
    if (imax <= 0) imax = 1.5 * mp.i_rated_peak;
    if (i_grid)
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) points.push_back({true, lin(-imax, imax, a, n), lin(-imax, imax, b, n)});
    if (psi_grid)
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) points.push_back({false, lin(pd_lo, pd_hi, a, n), lin(pq_lo, pq_hi, b, n)});

    std::printf("input,i_d_A,i_q_A,psi_d_Wb,psi_q_Wb,cur_d_A,cur_q_A,g_dd_per_H,g_dq_per_H,g_qq_per_H,"
                "l_dd_H,l_dq_H,l_qq_H,torque_Nm,energy_J\n");
    for (const Point& p : points) {
        try {
            Vec2 i, psi, cur;
            Mat2 g;
            if (p.is_current) {
                i = Vec2(p.x, p.y);
                psi = model->flux(i);
                model->current_jacobian(psi, &cur, &g);
            } else {
                psi = Vec2(p.x, p.y);
                model->current_jacobian(psi, &cur, &g);
                i = cur;
            }
            const Mat2 l = g.inverse();
            // From a current point through the library's torque() (it solves flux(i) itself).
            const double t = p.is_current ? torque(*model, mp.pole_pairs, i)
                                          : 1.5 * mp.pole_pairs * (psi.x() * i.y() - psi.y() * i.x());
            std::printf("%s,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                        p.is_current ? "i" : "psi", i.x(), i.y(), psi.x(), psi.y(), cur.x(), cur.y(), g(0, 0),
                        g(0, 1), g(1, 1), l(0, 0), l(0, 1), l(1, 1), t, model->energy(psi));
        } catch (const std::exception& e) {
            std::fflush(stdout);
            std::fprintf(stderr, "model-dump: at %s = (%.17g, %.17g): %s\n", p.is_current ? "i" : "psi", p.x, p.y,
                         e.what());
            return 1;
        }
    }
    return 0;
}
