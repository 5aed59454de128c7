// Measured flux maps as presets (docs/machine-models.md "Measured flux maps"): every refusal of the
// reader names file, line and reason; a good map's figures at i = 0 and its reciprocity; the preset
// keys ([flux_map] file, psi_pm_wb / ld_h / lq_h optional); the map model the plant integrates
// (inversion, extrapolation outside the grid); the Baldor PM-SyRM preset.
#include <gtest/gtest.h>

#include <cmath>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "mcsim/fluxmap_file.hpp"
#include "mcsim/machine.hpp"

using namespace mcsim;
namespace fs = std::filesystem;

namespace {

using Map = std::function<Vec2(double, double)>;

// psi = psi_pm + L i with a symmetric L (reciprocal, with cross-coupling)
Vec2 linear(double d, double q) { return {0.3 + 0.010 * d + 0.001 * q, 0.001 * d + 0.02 * q}; }

std::string dir() {
    static const std::string d = [] {
        const fs::path p = fs::temp_directory_path() / ("mcsim-fluxmap-file-" + std::to_string(::getpid()));
        fs::create_directories(p);
        return p.string();
    }();
    return d;
}

std::vector<std::string> rows(const Map& f = linear, std::vector<double> ds = {-2, -1, 0, 1, 2},
                              std::vector<double> qs = {-3, 0, 3}) {
    std::vector<std::string> out;
    char b[160];
    for (double d : ds)
        for (double q : qs) {
            const Vec2 p = f(d, q);
            std::snprintf(b, sizeof b, "%.17g,%.17g,%.17g,%.17g", d, q, p.x(), p.y());
            out.push_back(b);
        }
    return out;
}

std::string write(const std::string& name, const std::vector<std::string>& lines,
                  const std::string& header = kFluxMapFileHeader) {
    const std::string p = dir() + "/" + name;
    std::ofstream f(p);
    if (!header.empty()) f << header << "\n";
    for (const auto& l : lines) f << l << "\n";
    return p;
}

std::string error_of(const std::string& path) {
    try {
        read_flux_map_file(path);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

std::vector<std::string> with(std::vector<std::string> v, size_t at, const std::string& row) {
    v[at] = row;
    return v;
}

}  // namespace

TEST(FluxMapFile, EachRefusalNamesFileLineAndReason) {
    const auto g = rows();
    struct Bad {
        std::string file;
        int line;  // 0: no line (what no single row holds)
        std::string reason;
    };
    auto erase = [](std::vector<std::string> v, size_t k) { v.erase(v.begin() + long(k)); return v; };
    auto append = [](std::vector<std::string> v, const std::string& r) { v.push_back(r); return v; };
    const std::vector<Bad> cases = {
        {write("header.csv", g, "i_d_A,i_q_A,psi_d_Wb,psi_q_Wb"), 1, "is not 'i_d_A,i_q_A,psi_d_Vs,psi_q_Vs'"},
        {write("ragged.csv", with(g, 4, "0,0,0.3")), 6, "expected 4 columns"},
        {write("ragged5.csv", with(g, 2, g[2] + ",1")), 4, "got 5"},
        {write("nan.csv", with(g, 7, "0,0,nan,0")), 9, "column psi_d_Vs: 'nan' is not a finite number"},
        {write("inf.csv", with(g, 7, "0,0,1e999,0")), 9, "is not a finite number"},
        {write("text.csv", with(g, 3, "-1,-3,abc,0")), 5, "'abc' is not a finite number"},
        {write("dup.csv", append(g, g[7])), 17, "duplicate grid point (i_d, i_q) = (0, 0) A, first given on line 9"},
        {write("missing.csv", erase(g, 10)), 0, "no row for grid point (i_d, i_q) = (1, 0) A"},
        {write("offgrid.csv", rows(linear, {-2, -1, 0, 1.5, 2})), 11, "off the equally spaced grid"},
        {write("two.csv", rows(linear, {-2, -1, 0, 1, 2}, {-3, 3})), 0, "at least 3 grid points per axis"},
        {write("mono_d.csv", rows([](double d, double q) { return Vec2(0.3 - 0.02 * (d == 1) + 0.01 * d, 0.02 * q); })),
         11, "does not rise with i_d"},
        {write("mono_q.csv", rows([](double d, double q) { return Vec2(0.3 + 0.01 * d, 0.02 * q * (d == 2 ? -1 : 1)); })),
         15, "does not rise with i_q"},
        {write("no_pm.csv", rows([](double d, double q) { return Vec2(-0.05 + 0.01 * d, 0.02 * q); })), 0,
         "no PM flux on +d"},
        {write("no_zero.csv", rows(linear, {1, 2, 3, 4})), 0, "does not contain i = 0"},
        {write("empty.csv", {}, ""), 0, "empty file"},
        {dir() + "/absent.csv", 0, "no such flux-map file"},
    };
    for (const Bad& c : cases) {
        const std::string e = error_of(c.file);
        const std::string prefix = c.file + (c.line ? ":" + std::to_string(c.line) : std::string()) + ": ";
        EXPECT_EQ(e.rfind(prefix, 0), 0u) << "expected '" << prefix << "' at the start of: " << e;
        EXPECT_NE(e.find(c.reason), std::string::npos) << "'" << c.reason << "' not in: " << e;
        std::printf("  %s\n", e.c_str());
    }
}

TEST(FluxMapFile, GoodMapFiguresAtZeroAndReciprocity) {
    auto g = rows();
    std::rotate(g.begin(), g.begin() + 7, g.end());  // any row order
    g.insert(g.begin() + 3, "# a comment");
    g.insert(g.begin() + 5, "");
    const FluxMapData d = read_flux_map_file(write("lin.csv", g));
    EXPECT_EQ(d.table.x.n, 5);
    EXPECT_EQ(d.table.y.n, 3);
    EXPECT_NEAR(d.psi_pm, 0.3, 1e-15);
    EXPECT_NEAR(d.ld, 0.010, 1e-14);
    EXPECT_NEAR(d.lq, 0.020, 1e-14);
    EXPECT_NEAR(d.ldq, 0.001, 1e-14);
    EXPECT_LT(d.recip_max, 1e-12);
    EXPECT_TRUE(d.warnings.empty());
    // d psi_d/d i_q = 0.004 against d psi_q/d i_d = 0: a warning, never a refusal
    const FluxMapData n = read_flux_map_file(
        write("nonrecip.csv", rows([](double dd, double q) { return Vec2(0.3 + 0.01 * dd + 0.004 * q, 0.02 * q); })));
    EXPECT_NEAR(n.recip_max, 0.004 / std::sqrt(0.01 * 0.02), 1e-9);
    EXPECT_NEAR(n.recip_rms, n.recip_max, 1e-9);
    ASSERT_EQ(n.warnings.size(), 1u);
    EXPECT_NE(n.warnings[0].find("reciprocity"), std::string::npos);
}

TEST(FluxMapFile, PresetKeysAndDerivedValues) {
    write("lin.csv", rows());
    const std::string base =
        "name = \"x\"\npole_pairs = 2\nrs_ohm = 0.1\ninertia_kgm2 = 0.01\nfriction_nms = 0\n"
        "i_rated_peak_a = 2\ntorque_rated_nm = 1\nvdc_nominal_v = 48\nf_sample_hz = 10000\n";
    auto preset = [&](const std::string& name, const std::string& body) {
        const std::string p = dir() + "/" + name;
        std::ofstream(p) << base << body;
        return p;
    };
    // relative to the preset's folder; psi_pm_wb, ld_h, lq_h from the map
    const MachineParams m = load_machine_preset(preset("rel.toml", "[flux_map]\nfile = \"lin.csv\"\n"));
    ASSERT_TRUE(m.flux_map);
    EXPECT_NEAR(m.psi_pm, 0.3, 1e-15);
    EXPECT_NEAR(m.ld, 0.01, 1e-14);
    EXPECT_NEAR(m.lq, 0.02, 1e-14);
    // given values win; an absolute path
    const MachineParams g =
        load_machine_preset(preset("abs.toml", "ld_h = 0.012\n[flux_map]\nfile = \"" + dir() + "/lin.csv\"\n"));
    EXPECT_EQ(g.ld, 0.012);
    EXPECT_NEAR(g.lq, 0.02, 1e-14);
    auto err = [](const std::string& p) {
        try {
            load_machine_preset(p);
        } catch (const std::exception& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    const std::string both = err(preset("both.toml", "[flux_map]\nfile = \"lin.csv\"\n[saturation]\na_d0 = 1\n"));
    EXPECT_NE(both.find("key 'flux_map': a preset gives either [saturation] or [flux_map], not both"), std::string::npos)
        << both;
    write("dup.csv", [] { auto v = rows(); v.push_back(v[3]); return v; }());
    const std::string bad = err(preset("bad.toml", "[flux_map]\nfile = \"dup.csv\"\n"));
    EXPECT_NE(bad.find("key 'flux_map.file': " + dir() + "/dup.csv:17: duplicate grid point"), std::string::npos) << bad;
    const std::string none = err(preset("none.toml", "psi_pm_wb = 0.3\nld_h = 0.01\nlq_h = 0.02\n"));
    EXPECT_NE(none.find("key 'saturation': missing"), std::string::npos) << none;
    const std::string nofile = err(preset("nofile.toml", "[flux_map]\n"));
    EXPECT_NE(nofile.find("key 'flux_map.file': missing"), std::string::npos) << nofile;
}

TEST(FluxMapFile, MapModelInvertsTheMapAndExtrapolatesLinearly) {
    // A linear map: the inverted table is exact inside and its edge-cell continuation is the same
    // linear function, so current() is exact everywhere (the documented linear extrapolation).
    const auto lin = std::make_shared<FluxMapData>(read_flux_map_file(write("lin.csv", rows())));
    const MeasuredMapModel lm(lin);
    Mat2 l;
    l << 0.010, 0.001, 0.001, 0.02;
    for (const Vec2& i : {Vec2(0.5, 0.7), Vec2(-2, 3), Vec2(6, -9), Vec2(-15, 20)}) {
        const Vec2 psi = linear(i.x(), i.y());
        EXPECT_LT((lm.current(psi) - i).norm(), 1e-8) << i.transpose();
        EXPECT_LT((lm.di_dpsi(psi) - l.inverse()).norm(), 1e-5 * l.inverse().norm());
    }
    EXPECT_EQ(lm.kind(), "table");
    EXPECT_NEAR(small_signal(lm).psi_pm, 0.3, 1e-10);

    // The measured Baldor map: current(map(i)) returns i inside the grid (interpolation error of the
    // inverted table), and across the grid border the forward map is continuous with its edge-cell
    // slope continued outside (C1 along the normal direction: the same cell polynomial).
    const MachineParams bp = load_machine_preset("baldor-5p6kw-pmsyrm");
    ASSERT_TRUE(bp.flux_map);
    const auto model = make_preset_model(bp);
    const FluxMapTable& t = bp.flux_map->table;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ud(-19.5, 19.5), uq(-25.5, 25.5);
    double worst = 0;
    for (int k = 0; k < 500; ++k) {
        const Vec2 i(ud(rng), uq(rng));
        worst = std::max(worst, (model->current(t.eval(i)) - i).norm());
    }
    std::printf("  Baldor: max |i(psi(i)) - i| over 500 points in the grid: %.4f A\n", worst);
    EXPECT_LT(worst, 0.1);  // 2 A grid, double interpolation (observed 0.043 A); 0.8 % of the rated 12.45 A
    for (const double q : {-25.0, -7.3, 0.0, 11.1, 25.0}) {
        const double e = 1e-7;
        const Vec2 in = t.eval(Vec2(20 - e, q)), out = t.eval(Vec2(20 + e, q));
        EXPECT_LT((out - in).norm(), 1e-7);
        const Mat2 j_edge = t.jacobian(Vec2(20 - e, q)), j_far = t.jacobian(Vec2(26, q));
        EXPECT_LT((j_edge.col(0) - j_far.col(0)).norm(), 1e-9) << "d psi/d i_d continues the edge cell's";
    }
    EXPECT_TRUE(bp.flux_map->in_grid(Vec2(20, -26)));
    EXPECT_FALSE(bp.flux_map->in_grid(Vec2(20.01, 0)));
}

TEST(FluxMapFile, BaldorPresetFromTheMeasuredMap) {
    const MachineParams m = load_machine_preset("baldor-5p6kw-pmsyrm");
    EXPECT_EQ(m.pole_pairs, 2);
    EXPECT_EQ(m.flux_map->table.x.n, 21);
    EXPECT_EQ(m.flux_map->table.y.n, 27);
    EXPECT_DOUBLE_EQ(m.psi_pm, m.flux_map->table.out_d(10, 13));  // the (0, 0) node, PM on +d
    EXPECT_DOUBLE_EQ(m.flux_map->table.out_q(10, 13), 0.0);
    EXPECT_GT(m.lq, 4 * m.ld);  // PM-SyRM: the q axis is the high-permeance one near i = 0
    std::printf("  baldor: psi_pm %.5f Wb, Ld %.3f mH, Lq %.3f mH, reciprocity rms %.2f %%, max %.2f %%\n", m.psi_pm,
                1e3 * m.ld, 1e3 * m.lq, 100 * m.flux_map->recip_rms, 100 * m.flux_map->recip_max);
    EXPECT_TRUE(m.flux_map->warnings.empty());
}
