// Pieces shared by every FluxModel: the Newton inversion psi(i) and small-signal helpers.
#include "mcsim/machine.hpp"
#include "mcsim/fluxmap_file.hpp"

#include <cmath>
#include <stdexcept>

namespace mcsim {

Vec2 FluxModel::flux_initial_guess(const Vec2&) const { return Vec2::Zero(); }

Vec2 solve_flux(const FluxModel& m, const Vec2& i, const Vec2& psi_start, FluxSolveStats* stats,
                double rel_tol, int max_iter) {
    // Newton on r(psi) = i(psi) - i_target. The Newton direction is a descent direction of |r|^2
    // whenever the Jacobian is regular, so halving the step until |r| decreases (Armijo-like)
    // keeps the iteration safe far from the solution; near it the full step is taken and
    // convergence is quadratic.
    Vec2 psi = psi_start;
    Vec2 r = m.current(psi) - i;
    double rn = r.norm();
    // Round-off floor of the residual: the terms of i(psi) are of the order of the largest
    // current involved, so |r| cannot be pushed below a few ulps of it.
    const double i_scale = std::max({i.norm(), m.current(Vec2::Zero()).norm(), 1.0});
    FluxSolveStats st;
    for (int k = 0; k < max_iter; ++k) {
        st.iterations = k + 1;
        const Mat2 jac = m.di_dpsi(psi);
        const Vec2 step = jac.fullPivLu().solve(-r);
        if (!step.allFinite()) break;
        // Converged when the full Newton step is negligible: near the root |r| sits at round-off
        // level and need not decrease any more, so this test comes before the line search.
        if (step.norm() <= rel_tol * std::max(psi.norm(), 1e-9)) {
            psi += step;
            r = m.current(psi) - i;
            rn = r.norm();
            st.converged = true;
            break;
        }
        double lambda = 1.0;
        Vec2 psi_new = psi + step;
        Vec2 r_new = m.current(psi_new) - i;
        while (!(r_new.norm() < rn) && lambda > 1e-6) {
            lambda *= 0.5;
            psi_new = psi + lambda * step;
            r_new = m.current(psi_new) - i;
        }
        if (!(r_new.norm() < rn)) {
            // No decrease even for tiny steps: at the round-off floor the residual cannot
            // shrink, which counts as converged; otherwise the iteration has stalled.
            st.converged = rn <= 1e-14 * i_scale;
            break;
        }
        psi = psi_new;
        r = r_new;
        rn = r.norm();
    }
    st.residual = rn;
    if (stats) *stats = st;
    return psi;
}

Vec2 FluxModel::flux(const Vec2& i) const {
    FluxSolveStats st;
    Vec2 psi = solve_flux(*this, i, flux_initial_guess(i), &st);
    if (st.converged) return psi;
    // Continuation in the current: walk from the no-current state towards i in steps small
    // enough for Newton to converge from the previous solution (strong saturation).
    psi = solve_flux(*this, Vec2::Zero(), flux_initial_guess(Vec2::Zero()), &st);
    constexpr int n_steps = 32;
    for (int k = 1; k <= n_steps && st.converged; ++k)
        psi = solve_flux(*this, i * (double(k) / n_steps), psi, &st);
    if (!st.converged)
        throw std::runtime_error("FluxModel::flux: Newton did not converge for i = (" + std::to_string(i.x()) +
                                 ", " + std::to_string(i.y()) + ") A in model '" + kind() + "'");
    return psi;
}

SmallSignal small_signal(const FluxModel& m) {
    const Vec2 psi0 = m.flux(Vec2::Zero());
    const Mat2 l0 = m.di_dpsi(psi0).inverse();
    SmallSignal s;
    s.psi_pm = psi0.x();
    s.ld = l0(0, 0);
    s.lq = l0(1, 1);
    s.ldq = l0(0, 1);
    return s;
}

double torque(const FluxModel& m, int pole_pairs, const Vec2& i) {
    const Vec2 psi = m.flux(i);
    return 1.5 * pole_pairs * (psi.x() * i.y() - psi.y() * i.x());
}

std::unique_ptr<FluxModel> make_preset_model(const MachineParams& mp) {
    if (mp.flux_map) return std::make_unique<MeasuredMapModel>(mp.flux_map);
    return make_analytic_model(mp.sat);
}

}  // namespace mcsim
