// Flux-map tables: bilinear interpolation/extrapolation, CSV, LUT inversion round trip against
// the analytic model (machines.md "Tables"), the table-based FluxModel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>
#include <fstream>
#include <random>

#include "mcsim/fluxmap.hpp"
#include "mcsim/machine.hpp"

using namespace mcsim;

namespace {

std::unique_ptr<FluxModel> sun_model() { return make_preset_model(load_machine_preset("sun2016-ipm-5kw")); }

// A table whose outputs are an exactly bilinear function of the inputs: interpolation and
// extrapolation must reproduce it everywhere.
Table2D bilinear_table() {
    Table2D t(TableKind::FluxOfCurrent, GridAxis{-2, 3, 6}, GridAxis{-1, 1, 5});
    for (int a = 0; a < t.x.n; ++a)
        for (int b = 0; b < t.y.n; ++b) {
            const double x = t.x.at(a), y = t.y.at(b);
            t.set_node(a, b, Vec2(1 + 2 * x - 3 * y, 0.5 * x + y));
        }
    return t;
}

// Round trip: tabulate psi(i) of the analytic model on +-1.5 i_rated with n points per axis,
// invert, and compare the table's i(psi) with the exact current at random off-grid points whose
// current lies in |i| <= 13.3 A. Returns the max error [A].
double round_trip_error(const FluxModel& m, int n, InversionResult* inv_out = nullptr) {
    InversionResult inv;
    const auto table = make_table_model_from(m, default_flux_map_grid(13.29, n), &inv);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-13.3, 13.3);
    double worst = 0;
    int count = 0;
    while (count < 2000) {
        const Vec2 i(u(rng), u(rng));
        if (i.norm() > 13.3) continue;
        ++count;
        const Vec2 psi = m.flux(i);
        worst = std::max(worst, (table->current(psi) - i).norm());
    }
    if (inv_out) *inv_out = std::move(inv);
    return worst;
}

}  // namespace

TEST(Table2D, BilinearInterpolationAndLinearExtrapolationAreExact) {
    const Table2D t = bilinear_table();
    for (const Vec2& p : {Vec2(0.3, 0.1), Vec2(-2, -1), Vec2(3, 1), Vec2(5, 0.2), Vec2(-4, -3), Vec2(1.1, 2.5)}) {
        EXPECT_NEAR((t.eval(p) - Vec2(1 + 2 * p.x() - 3 * p.y(), 0.5 * p.x() + p.y())).norm(), 0, 1e-13)
            << p.transpose();
        Mat2 j;
        j << 2, -3, 0.5, 1;
        EXPECT_NEAR((t.jacobian(p) - j).norm(), 0, 1e-13) << p.transpose();
    }
    EXPECT_TRUE(t.inside(Vec2(3, 1)));
    EXPECT_FALSE(t.inside(Vec2(3.01, 0)));
}

TEST(Table2D, JacobianIsTheDerivativeOfTheCellPolynomial) {
    const auto m = sun_model();
    const Table2D t = tabulate_flux_map(*m, GridAxis{-20, 20, 9}, GridAxis{-20, 20, 9});
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-24, 24);  // includes extrapolated points
    for (int k = 0; k < 200; ++k) {
        const Vec2 p(u(rng), u(rng));
        const double h = 1e-6;
        Mat2 fd;
        fd.col(0) = (t.eval(p + Vec2(h, 0)) - t.eval(p - Vec2(h, 0))) / (2 * h);
        fd.col(1) = (t.eval(p + Vec2(0, h)) - t.eval(p - Vec2(0, h))) / (2 * h);
        EXPECT_NEAR((fd - t.jacobian(p)).norm(), 0, 1e-8) << p.transpose();
    }
}

TEST(Table2D, CsvRoundTripIsExactAndErrorsNameTheLine) {
    const auto m = sun_model();
    const Table2D t = tabulate_flux_map(*m, GridAxis{-10, 10, 5}, GridAxis{-5, 15, 6});
    const std::string path = ::testing::TempDir() + "/mcsim_fwd.csv";
    write_table_csv(path, t);
    const Table2D r = read_table_csv(path);
    EXPECT_EQ(r.kind, TableKind::FluxOfCurrent);
    EXPECT_EQ(r.x.n, 5);
    EXPECT_EQ(r.y.n, 6);
    EXPECT_EQ(r.x.lo, -10);
    EXPECT_EQ(r.y.hi, 15);
    EXPECT_EQ((r.out_d - t.out_d).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((r.out_q - t.out_q).cwiseAbs().maxCoeff(), 0.0);

    auto expect_error = [](const std::string& text, const std::string& needle) {
        const std::string p = ::testing::TempDir() + "/mcsim_bad.csv";
        std::ofstream(p) << text;
        try {
            read_table_csv(p);
            ADD_FAILURE() << "no error for: " << text;
        } catch (const std::runtime_error& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    expect_error("a,b,c,d\n", "header");
    expect_error("i_d_A,i_q_A,psi_d_Wb,psi_q_Wb\n0,0,1,2\n1,0,x,2\n", ":3: column 3");
    expect_error("i_d_A,i_q_A,psi_d_Wb,psi_q_Wb\n0,0,1,2\n1,0,1,2\n2,0,1,2\n0,1,1,2\n1,1,1,2\n", "do not fill");
    expect_error("i_d_A,i_q_A,psi_d_Wb,psi_q_Wb\n0,0,1,2\n1,0,1,2\n0,1,1,2\n0,1,1,2\n", "duplicate grid node");
    expect_error("i_d_A,i_q_A,psi_d_Wb,psi_q_Wb\n0,0,1,2\n1,0,1,2\n3,0,1,2\n0,1,1,2\n1,1,1,2\n3,1,1,2\n",
                 "not a regular grid");
    expect_error("i_d_A,i_q_A,psi_d_Wb,psi_q_Wb\n0,0,1\n", "expected 4 columns");
}

TEST(FluxMapInversion, RoundTripAgainstTheAnalyticModel) {
    const auto m = sun_model();
    InversionResult inv;
    const double e81 = round_trip_error(*m, 81, &inv);
    EXPECT_TRUE(inv.failed.empty());
    std::printf("inversion 81 x 81: max residual %.2e Wb, max iterations %d, %d of %d nodes extrapolated\n",
                inv.max_residual, inv.max_iterations, inv.n_extrapolated, 81 * 81);
    const double e41 = round_trip_error(*m, 41), e161 = round_trip_error(*m, 161);
    std::printf("round trip max |i_table(psi) - i_exact(psi)| over |i| <= 13.3 A (sun2016, +-19.9 A grid):\n"
                "  41 x 41: %.4f A   81 x 81: %.4f A   161 x 161: %.5f A\n", e41, e81, e161);
    EXPECT_LT(e81, 0.02);  // 0.15 % of rated current
    // Two bilinear interpolations: error O(h^2); halving h must cut it by about four.
    EXPECT_LT(e161, 0.35 * e81);
    EXPECT_LT(e81, 0.35 * e41);
}

TEST(FluxMapInversion, ReportsUnreachableTargets) {
    // psi_q does not depend on i at all: targets with psi_q != 0.2 cannot be met.
    Table2D t(TableKind::FluxOfCurrent, GridAxis{-1, 1, 3}, GridAxis{-1, 1, 3});
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) t.set_node(a, b, Vec2(t.x.at(a) + 0.1 * t.y.at(b), 0.2));
    const InversionResult r = invert_flux_map(t, GridAxis{-0.5, 0.5, 3}, GridAxis{0.0, 0.4, 3});
    EXPECT_EQ(r.failed.size(), 6u);  // psi_q = 0 and 0.4 rows
    for (const auto& p : r.failed) EXPECT_NE(p.iy, 1);
    EXPECT_THROW(invert_flux_map(r.table, GridAxis{0, 1, 2}, GridAxis{0, 1, 2}), std::invalid_argument);
}

TEST(TableModel, BehavesLikeTheModelItWasBuiltFrom) {
    const auto m = sun_model();
    const auto t = make_table_model_from(*m, default_flux_map_grid(13.29));
    EXPECT_EQ(t->kind(), "table");
    const SmallSignal s = small_signal(*t), s0 = small_signal(*m);
    std::printf("table model at i = 0: psi_pm %.5f Wb (exact %.5f), Ld %.4f mH (%.4f), Lq %.4f mH (%.4f)\n",
                s.psi_pm, s0.psi_pm, 1e3 * s.ld, 1e3 * s0.ld, 1e3 * s.lq, 1e3 * s0.lq);
    EXPECT_NEAR(s.psi_pm, s0.psi_pm, 1e-4);
    // Differential inductances come from a cell slope: first-order accurate.
    EXPECT_NEAR(s.ld, s0.ld, 0.02 * s0.ld);
    EXPECT_NEAR(s.lq, s0.lq, 0.02 * s0.lq);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-13, 13);
    for (int k = 0; k < 100; ++k) {
        const Vec2 i(u(rng), u(rng));
        const Vec2 psi = t->flux(i);
        EXPECT_LT((t->current(psi) - i).norm(), 1e-9);  // Newton on the table converged
        EXPECT_LT((psi - m->flux(i)).norm(), 2e-4);
        EXPECT_NEAR(t->energy(psi), m->energy(psi), 2e-3 * std::abs(m->energy(psi)) + 1e-4);
        // Energy gradient is the current (inside a cell, away from grid lines).
        const double h = 1e-7;
        const Vec2 g((t->energy(psi + Vec2(h, 0)) - t->energy(psi - Vec2(h, 0))) / (2 * h),
                     (t->energy(psi + Vec2(0, h)) - t->energy(psi - Vec2(0, h))) / (2 * h));
        EXPECT_LT((g - i).norm(), 0.05) << i.transpose();
    }
}

// The disk cache of tabulate_flux_map: the first call writes, the second reads, both give the
// fresh table to the bit; another model gets another file; a damaged file is recomputed and
// rewritten; MCSIM_CACHE=off writes nothing.
TEST(FluxMapCache, BitIdenticalAndKeyedByTheModel) {
    char tmpl[] = "/tmp/mcsim_cache_test_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    const std::string dir = tmpl;
    setenv("MCSIM_CACHE_DIR", dir.c_str(), 1);
    unsetenv("MCSIM_CACHE");
    const auto m = sun_model();
    const GridAxis ax{-20, 20, 9};
    const FluxMapTable fresh = tabulate_flux_map(*m, ax, ax);
    auto same = [&](const FluxMapTable& t) {
        for (int a = 0; a < ax.n; ++a)
            for (int b = 0; b < ax.n; ++b)
                if (t.node(a, b) != fresh.node(a, b)) return false;
        return true;
    };
    auto files = [&] {
        std::vector<std::string> out;
        for (const auto& e : std::filesystem::directory_iterator(dir)) out.push_back(e.path().string());
        return out;
    };
    EXPECT_TRUE(same(tabulate_flux_map_cached(*m, ax, ax)));   // computed, written
    ASSERT_EQ(files().size(), 1u);
    EXPECT_TRUE(same(tabulate_flux_map_cached(*m, ax, ax)));   // read back
    // damaged: truncated to half, then recomputed and rewritten whole
    const std::string f = files()[0];
    const auto full = std::filesystem::file_size(f);
    std::filesystem::resize_file(f, full / 2);
    EXPECT_TRUE(same(tabulate_flux_map_cached(*m, ax, ax)));
    EXPECT_EQ(std::filesystem::file_size(f), full);
    // another grid, another model: other files
    const GridAxis ax2{-20, 20, 7};
    (void)tabulate_flux_map_cached(*m, ax2, ax2);
    const auto lin = make_preset_model(load_machine_preset("brodatzki-35kw"));
    (void)tabulate_flux_map_cached(*lin, ax, ax);
    EXPECT_EQ(files().size(), 3u);
    // off: nothing new
    setenv("MCSIM_CACHE", "off", 1);
    const GridAxis ax3{-10, 10, 5};
    (void)tabulate_flux_map_cached(*m, ax3, ax3);
    EXPECT_EQ(files().size(), 3u);
    unsetenv("MCSIM_CACHE");
    unsetenv("MCSIM_CACHE_DIR");
    std::filesystem::remove_all(dir);
}
