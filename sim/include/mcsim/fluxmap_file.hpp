// Measured flux maps as machine presets (`[flux_map] file = "NAME.csv"`, docs/machine-models.md
// "Measured flux maps"): the checked CSV reader, the figures derived from the map at i = 0, the
// reciprocity report, and the map model the plant integrates (the map inverted to i(psi), thesis
// 4.2.3, Fig. 4.3). tools/mctools/fluxmap.py is the second implementation of the reader; both are
// tested against each other on the same files.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "mcsim/fluxmap.hpp"

namespace mcsim {

// Header line of a measured map (peak-value rotor d-q quantities, PM on +d).
constexpr const char* kFluxMapFileHeader = "i_d_A,i_q_A,psi_d_Vs,psi_q_Vs";
// Reciprocity mismatch above which loading warns (relative, see FluxMapData::recip_*).
constexpr double kFluxMapReciprocityWarn = 0.10;

// A measured psi(i) map as read and checked, and what is derived from it.
struct FluxMapData {
    std::string file;            // the path as resolved
    FluxMapTable table;          // psi(i) on the file's regular grid (kind FluxOfCurrent)
    // At i = 0 (bilinear interpolation with the table's extrapolation, central differences of one
    // grid step either side): psi_pm = psi_d(0, 0); ld = d psi_d/d i_d, lq = d psi_q/d i_q,
    // ldq = d psi_d/d i_q.
    double psi_pm = 0, psi_q0 = 0, ld = 0, lq = 0, ldq = 0;
    // Reciprocity (energy consistency): per grid cell, the cross slopes of the cell's bilinear
    // polynomial at its centre, l_dq = d psi_d/d i_q and l_qd = d psi_q/d i_d, compared relative to
    // the geometric mean of the cell's self slopes: |l_dq - l_qd| / sqrt(l_dd l_qq). rms and max over
    // all cells, and the cell centre of the max.
    double recip_rms = 0, recip_max = 0;
    double recip_max_id = 0, recip_max_iq = 0;
    std::vector<std::string> warnings;  // each names the file; printed by mcsim on stderr
    bool in_grid(const Vec2& i) const { return table.inside(i); }
};

// Reads and checks a measured map; throws std::runtime_error "FILE:LINE: reason" (or "FILE: reason"
// for what no single line holds: a missing grid point, too few points, no PM flux on +d).
FluxMapData read_flux_map_file(const std::string& path);

// The plant's model of a measured map: the map, bilinear with its edge-cell extrapolation, inverted
// (invert_flux_map) onto a psi grid over the map's flux extent with 4 (n - 1) + 1 nodes per axis
// (n: the map's points on the matching current axis; capped at 161); current() interpolates that
// table. measured() is the map as read: the estimator's map is resampled from it.
class MeasuredMapModel final : public FluxModel {
public:
    explicit MeasuredMapModel(std::shared_ptr<const FluxMapData> map);
    Vec2 current(const Vec2& psi) const override { return inv_->current(psi); }
    Mat2 di_dpsi(const Vec2& psi) const override { return inv_->di_dpsi(psi); }
    Vec2 flux(const Vec2& i) const override { return inv_->flux(i); }
    double energy(const Vec2& psi) const override { return inv_->energy(psi); }
    std::string kind() const override { return "table"; }
    const FluxMapData& measured() const { return *map_; }
    const TableModel& inverted() const { return *inv_; }

private:
    std::shared_ptr<const FluxMapData> map_;
    std::unique_ptr<TableModel> inv_;
};

}  // namespace mcsim
