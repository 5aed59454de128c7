// Machine (magnetic) models: current from flux linkage, i_dq = f(psi_dq), per machines.md.
// Owner of implementations: sim/src/machine_*.cpp. Everything is in the rotor (d-q) frame,
// peak-value space vectors, amplitude-invariant Clarke (2.4), SI units.
#pragma once
#include <Eigen/Dense>
#include <memory>
#include <string>

namespace mcsim {
namespace detail {
struct AnalyticEval;
}
struct FluxMapData;  // a measured map (mcsim/fluxmap_file.hpp)

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;

// Analytic energy-consistent saturation model (machines.md):
//   i_d = G_d psi_d - i_f,  i_q = G_q psi_q
//   G_d = a_d0 + a_dd |psi_d|^S + a_dq/(V+2) |psi_d|^U |psi_q|^(V+2)
//   G_q = a_q0 + a_qq |psi_q|^T + a_dq/(U+2) |psi_d|^(U+2) |psi_q|^V
struct SaturationParams {
    double S = 2, T = 2, U = 1, V = 0;
    double a_d0 = 0, a_dd = 0, a_q0 = 0, a_qq = 0, a_dq = 0, i_f = 0;
};

// One machine preset (presets/*.toml); read by the sim and the Python tools alike.
struct MachineParams {
    std::string name;
    int pole_pairs = 1;
    double rs = 0;            // [ohm]
    double psi_pm = 0;        // [Wb]   small-signal, i = 0
    double ld = 0, lq = 0;    // [H]    small-signal, i = 0
    double inertia = 0;       // [kg m^2]
    double friction = 0;      // [N m s]
    double i_rated_peak = 0;  // [A]
    double torque_rated = 0;  // [N m]
    double vdc_nominal = 0;   // [V]
    double f_sample = 0;      // [Hz] bench sampling = switching frequency
    SaturationParams sat;     // [saturation]; unused when flux_map is set
    // [flux_map] file = "...": the measured map, read and checked (null for an analytic preset).
    // psi_pm, ld, lq are then the map's values at i = 0 unless the preset gives them.
    std::shared_ptr<const FluxMapData> flux_map;
};

// Interface every magnetic model implements. current() and its Jacobian are what the plant
// integrates with; flux() is the inverse (Newton), used for initial conditions and tables.
class FluxModel {
public:
    virtual ~FluxModel() = default;
    virtual Vec2 current(const Vec2& psi) const = 0;             // i_dq(psi_dq) [A]
    virtual Mat2 di_dpsi(const Vec2& psi) const = 0;            // Jacobian [1/H]
    // Both at once: the plant needs them together at every integration point, and a model that
    // shares the powers of psi between them is about twice as fast as the two calls.
    virtual void current_jacobian(const Vec2& psi, Vec2* i, Mat2* g) const {
        *i = current(psi);
        *g = di_dpsi(psi);
    }
    // The analytic model with integer exponents exposes its evaluator so the plant can inline it
    // (sim/src/analytic_eval.hpp); nullptr for every other model.
    virtual const detail::AnalyticEval* analytic_eval() const { return nullptr; }
    // Current, Jacobian and the Jacobian's derivative at psi: the energy's third derivatives, a
    // symmetric tensor of four numbers, k[0] = d g_dd/d psi_d, k[1] = d g_dd/d psi_q = d g_dq/d psi_d,
    // k[2] = d g_dq/d psi_q = d g_qq/d psi_d, k[3] = d g_qq/d psi_q [1/(H Wb)]. The plant's period-level
    // integrator expands i(psi) to second order with them (docs/plant.md "Taylor"). false: the model
    // has no closed form for them (tables, non-integer exponents); nothing is written then.
    virtual bool current_taylor(const Vec2& psi, Vec2* i, Mat2* g, double k[4]) const {
        (void)psi, (void)i, (void)g, (void)k;
        return false;
    }
    virtual Vec2 flux(const Vec2& i) const;                      // psi_dq(i_dq) by Newton [Wb]
    // Differential inductance matrix L = (di/dpsi)^-1 at current i [H].
    Mat2 l_diff(const Vec2& i) const { return di_dpsi(flux(i)).inverse(); }
    // Magnetic field energy stored, W(psi) = integral of i . dpsi from the no-current state
    // psi0 = flux(0) (so W = 0 at i = 0) [J]; 1.5 factor for three phases is applied by callers.
    virtual double energy(const Vec2& psi) const = 0;
    virtual std::string kind() const = 0;                       // "linear" | "analytic" | "table"

protected:
    // Starting point of the Newton iteration in flux(); models override it with something close
    // to the answer (the iteration itself is damped, so a poor guess costs iterations, not safety).
    virtual Vec2 flux_initial_guess(const Vec2& i) const;
};

// Options/diagnostics of the damped Newton solve behind FluxModel::flux().
struct FluxSolveStats {
    int iterations = 0;
    double residual = 0;  // |current(psi) - i| at exit [A]
    bool converged = false;
};
// Damped Newton on r(psi) = current(psi) - i from psi_start; stops when the step is below
// rel_tol * |psi| (or the residual is at round-off). Exposed for tests and table inversion.
Vec2 solve_flux(const FluxModel& m, const Vec2& i, const Vec2& psi_start, FluxSolveStats* stats = nullptr,
                double rel_tol = 1e-12, int max_iter = 100);

std::unique_ptr<FluxModel> make_linear_model(double ld, double lq, double psi_pm);
std::unique_ptr<FluxModel> make_analytic_model(const SaturationParams& p);
// The linear model written in the analytic parametrisation: a_d0 = 1/ld, a_q0 = 1/lq,
// i_f = psi_pm/ld, all saturation coefficients zero.
SaturationParams linear_saturation_params(double ld, double lq, double psi_pm);
// Magnetic co-ordinates of the model at i = 0: psi0 = flux(0) (psi0_d is the PM flux psi_pm)
// and L0 = l_diff(0) (small-signal Ld, Lq on the diagonal).
struct SmallSignal {
    double psi_pm = 0, ld = 0, lq = 0, ldq = 0;
};
SmallSignal small_signal(const FluxModel& m);
// Electromagnetic torque T = 1.5 p (psi_d i_q - psi_q i_d) at current i [N m].
double torque(const FluxModel& m, int pole_pairs, const Vec2& i);
// The model a preset describes: the analytic model of its [saturation] table, or the measured map
// of its [flux_map] inverted to i(psi) (MeasuredMapModel).
std::unique_ptr<FluxModel> make_preset_model(const MachineParams& mp);

// Loads presets/<name>.toml (or a path); throws std::runtime_error naming file, key, value.
MachineParams load_machine_preset(const std::string& name_or_path);

}  // namespace mcsim
