// Flux-map tables: psi_dq(i_dq) as measured/FEM data, its inversion to a current map
// i_dq(psi_dq) (thesis section 4.2.3, Figure 4.3) and the table-based FluxModel built on it.
// Everything in the rotor d-q frame, peak-value space vectors, SI units (A, Wb).
#pragma once
#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "mcsim/machine.hpp"

namespace mcsim {

// Regular grid axis: n >= 2 points lo, lo + h, ..., hi with h = (hi - lo)/(n - 1).
struct GridAxis {
    double lo = 0, hi = 0;
    int n = 0;
    double step() const { return (hi - lo) / (n - 1); }
    double at(int k) const { return k == n - 1 ? hi : lo + k * step(); }
    bool valid() const { return n >= 2 && hi > lo; }
};

// What a table maps from and to. FluxOfCurrent: x = i_d, y = i_q [A] -> (psi_d, psi_q) [Wb].
// CurrentOfFlux: x = psi_d, y = psi_q [Wb] -> (i_d, i_q) [A].
enum class TableKind { FluxOfCurrent, CurrentOfFlux };

// Regular-grid 2-D table with two outputs, values at the nodes: out_d(ix, iy), out_q(ix, iy)
// belong to (x.at(ix), y.at(iy)).
//
// Interpolation is bilinear within a cell. Outside the grid the edge cell's bilinear polynomial
// is continued (the cell index is clamped to the first/last cell, the local coordinate is not),
// i.e. linear extrapolation along each axis from the edge cell; no clamping of the value.
// The Jacobian is the derivative of that same polynomial (on a grid line, the cell on the
// upper side is used; the bilinear map is continuous but its derivative jumps across lines).
struct Table2D {
    TableKind kind = TableKind::FluxOfCurrent;
    GridAxis x, y;
    Eigen::MatrixXd out_d, out_q;  // (x.n, y.n)

    Table2D() = default;
    Table2D(TableKind k, const GridAxis& ax, const GridAxis& ay);  // zero-filled
    Vec2 node(int ix, int iy) const { return {out_d(ix, iy), out_q(ix, iy)}; }
    void set_node(int ix, int iy, const Vec2& v) { out_d(ix, iy) = v.x(); out_q(ix, iy) = v.y(); }
    Vec2 eval(const Vec2& p) const;
    Mat2 jacobian(const Vec2& p) const;  // d out / d (x, y)
    bool inside(const Vec2& p) const;    // within the grid rectangle (no extrapolation)
};
using FluxMapTable = Table2D;     // kind FluxOfCurrent
using CurrentMapTable = Table2D;  // kind CurrentOfFlux

// psi(i) on the grid id x iq from a model (its FluxModel::flux, warm-started along the grid).
FluxMapTable tabulate_flux_map(const FluxModel& m, const GridAxis& id, const GridAxis& iq);
// The same through a disk cache (sim/src/fluxmap_cache.cpp: $MCSIM_CACHE_DIR, else
// $XDG_CACHE_HOME/mcsim or ~/.cache/mcsim; MCSIM_CACHE=off: none): bit-identical tables, the
// Newton solves only the first time a model and grid are seen.
FluxMapTable tabulate_flux_map_cached(const FluxModel& m, const GridAxis& id, const GridAxis& iq);

struct InversionOptions {
    int max_iter = 100;
    // A point is converged when |psi_of_i(i) - psi_target| <= tol_rel * (largest |psi| of the table).
    double tol_rel = 1e-11;
};
struct InversionPoint {
    int ix = 0, iy = 0;
    Vec2 psi;          // target [Wb]
    Vec2 i;            // best current found [A]
    double residual;   // |psi_of_i(i) - psi| [Wb]
};
struct InversionResult {
    CurrentMapTable table;                 // i(psi) on the requested psi grid
    std::vector<InversionPoint> failed;    // not converged (their best value is still stored)
    int n_extrapolated = 0;                // converged, but i lies outside the psi(i) grid
    double max_residual = 0;               // over converged points [Wb]
    int max_iterations = 0;
};

// Thesis Fig. 4.3: for every node psi* of the psi_d x psi_q grid solve
// min_i |psi_of_i(i) - psi*|^2 with the bilinear-interpolated forward map (Levenberg-Marquardt,
// warm start from the neighbouring node already solved; fall back to the nearest forward node).
InversionResult invert_flux_map(const FluxMapTable& psi_of_i, const GridAxis& psi_d, const GridAxis& psi_q,
                                const InversionOptions& opt = {});
// Bounding box of the psi values of a forward table, as axes with n_d x n_q points.
std::pair<GridAxis, GridAxis> flux_extent_axes(const FluxMapTable& psi_of_i, int n_d, int n_q);

// Current-map model: i(psi) by bilinear interpolation of an inverted table (kind CurrentOfFlux).
// Energy: integral of i . dpsi along the straight line from psi0 = flux(0) to psi, exact for the
// piecewise-bilinear map (2-point Gauss per cell crossed). The interpolated table is only
// approximately a gradient field, so this W is path-dependent at the interpolation-error level.
class TableModel final : public FluxModel {
public:
    explicit TableModel(CurrentMapTable i_of_psi);
    Vec2 current(const Vec2& psi) const override { return t_.eval(psi); }
    Mat2 di_dpsi(const Vec2& psi) const override { return t_.jacobian(psi); }
    double energy(const Vec2& psi) const override;
    std::string kind() const override { return "table"; }
    const CurrentMapTable& table() const { return t_; }

protected:
    Vec2 flux_initial_guess(const Vec2& i) const override;  // node whose current is nearest to i

private:
    CurrentMapTable t_;
    Vec2 psi0_;
};

// Grid of make_table_model_from(): the forward table over id x iq, the inverted one over psi_d x
// psi_q. A psi axis with n == 0 takes the point count of the matching current axis; one with
// lo >= hi takes the extent of the tabulated psi values.
struct FluxMapGridSpec {
    GridAxis i_d{-20, 20, 81}, i_q{-20, 20, 81};
    GridAxis psi_d{0, 0, 0}, psi_q{0, 0, 0};
};
// Symmetric current grid +-span_factor * i_max with n points per axis, psi axes automatic.
FluxMapGridSpec default_flux_map_grid(double i_max, int n = 81, double span_factor = 1.5);

// Tabulate + invert; throws std::runtime_error if any point does not converge.
std::unique_ptr<TableModel> make_table_model_from(const FluxModel& m, const FluxMapGridSpec& grid,
                                                  InversionResult* diagnostics = nullptr);

// CSV, one grid node per line after a header line that names the kind:
//   FluxOfCurrent: "i_d_A,i_q_A,psi_d_Wb,psi_q_Wb"
//   CurrentOfFlux: "psi_d_Wb,psi_q_Wb,i_d_A,i_q_A"
// The first two columns are the grid co-ordinates; they must form a complete regular grid (rows
// in any order; written with the first column varying slowest). Blank lines and lines starting
// with '#' are ignored. Values are written with 17 significant digits (exact round trip).
// Errors throw std::runtime_error naming the file and line.
void write_table_csv(const std::string& path, const Table2D& t);
Table2D read_table_csv(const std::string& path);

}  // namespace mcsim
