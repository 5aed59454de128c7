// Constant-parameter model (thesis (3.2)): psi_d = Ld i_d + psi_pm, psi_q = Lq i_q.
#include "mcsim/machine.hpp"

#include <stdexcept>

namespace mcsim {
namespace {

class LinearModel final : public FluxModel {
public:
    LinearModel(double ld, double lq, double psi_pm) : ld_(ld), lq_(lq), psi_pm_(psi_pm) {
        if (!(ld > 0) || !(lq > 0))
            throw std::invalid_argument("make_linear_model: ld and lq must be > 0 H");
    }
    Vec2 current(const Vec2& psi) const override { return {(psi.x() - psi_pm_) / ld_, psi.y() / lq_}; }
    Mat2 di_dpsi(const Vec2&) const override {
        Mat2 j;
        j << 1.0 / ld_, 0.0, 0.0, 1.0 / lq_;
        return j;
    }
    Vec2 flux(const Vec2& i) const override { return {ld_ * i.x() + psi_pm_, lq_ * i.y()}; }
    bool current_taylor(const Vec2& psi, Vec2* i, Mat2* g, double k[4]) const override {
        *i = current(psi);
        *g = di_dpsi(psi);
        k[0] = k[1] = k[2] = k[3] = 0.0;  // constant inductances: the expansion is exact
        return true;
    }
    // Quadratic form around psi0 = (psi_pm, 0), where i = 0.
    double energy(const Vec2& psi) const override {
        const double dd = psi.x() - psi_pm_;
        return 0.5 * dd * dd / ld_ + 0.5 * psi.y() * psi.y() / lq_;
    }
    std::string kind() const override { return "linear"; }

protected:
    Vec2 flux_initial_guess(const Vec2& i) const override { return flux(i); }

private:
    double ld_, lq_, psi_pm_;
};

}  // namespace

std::unique_ptr<FluxModel> make_linear_model(double ld, double lq, double psi_pm) {
    return std::make_unique<LinearModel>(ld, lq, psi_pm);
}

SaturationParams linear_saturation_params(double ld, double lq, double psi_pm) {
    SaturationParams p;
    p.a_d0 = 1.0 / ld;
    p.a_q0 = 1.0 / lq;
    p.i_f = psi_pm / ld;
    return p;
}

}  // namespace mcsim
