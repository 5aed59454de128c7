// The plant: flux-linkage state machine model + inverter + mechanics, advanced one PWM period
// at a time. Implementation: sim/src/plant.cpp, inverter.cpp, mechanics.cpp.
#pragma once
#include <array>
#include <functional>
#include <memory>
#include "mcsim/machine.hpp"

namespace mcsim {

// Inverter. Centre-aligned PWM over one period [t0, t0+Ts]: phase x's high side is on for
// duty_x*Ts centred at t0 + Ts/2; ADC samples are taken at t0 (centre of the zero vector V000).
struct InverterConfig {
    enum class Mode { Averaged, Switching } mode = Mode::Switching;
    double vdc = 300.0;          // [V]
    double t_dead = 0.5e-6;      // [s] both switches off; phase voltage then set by current sign
    double v_device = 0.0;       // [V] device on-state drop (diode/MOSFET), sign follows current
    double i_zero_band = 0.05;   // [A] current below which a phase in dead time is taken as 0 A
    bool averaged_dead_time = false;  // Averaged mode: add -sign(i) vdc t_dead/Ts per phase
};

struct MechanicsConfig {
    enum class Mode { Inertia, Dyno } mode = Mode::Inertia;
    double inertia = 0.013;      // [kg m^2]
    double friction = 1.3e-3;    // [N m s]
    bool locked = false;         // rotor held at theta_m0 (omega = 0) whatever the torque
    std::function<double(double)> load_torque;   // T_load(t) [N m] (Inertia mode), may be empty
    // false: an active load (gravity-like: the torque acts whatever the speed); true: a reactive
    // load (friction-like: |T_load| opposes the motion, and at rest holds the rotor up to |T_load|)
    bool reactive_load = false;
    std::function<double(double)> dyno_speed;    // omega_m(t) [rad/s mech] (Dyno mode)
};

struct PlantConfig {
    MachineParams machine;
    InverterConfig inverter;
    MechanicsConfig mech;
    double theta_m0 = 0.0;       // initial mechanical angle [rad]
    double omega_m0 = 0.0;       // initial mechanical speed [rad/s]
    // Step bound: h <= Ts/substeps. Each interval between switching instants gets
    // ceil(length / (Ts/substeps)) steps (at least one), the averaged inverter `substeps` steps.
    // 2 keeps the i_dq error below 1e-6 A at 785 rad/s electrical (docs/plant.md).
    int substeps = 2;
    // Keep the energy ledger and the period-average voltages (energy(), u_dq_avg_last(),
    // u_ab_avg_last(), v_phase_avg_last()) while the outputs are enabled. Verification runs need
    // them; the scenario runner reads none of them and switches them off (~20 % of the plant's
    // time). Periods with the outputs disabled always keep them.
    bool energy_ledger = true;
    // Enabled periods: the two-point Hermite integrator (one model evaluation per step, default)
    // or classical RK4 on the rotor-frame state (four per step; kept as an independent reference
    // for the tests, always with the ledger). Disabled periods always use RK4.
    // Taylor: the whole switching period at once: the exact voltage integral, the current map
    // expanded to second order about mid-period, Simpson on the mean-voltage path plus the PWM
    // ripple's moments, one exact model evaluation at the period end (sim/src/taylor.hpp); the
    // scenario runner's default. It keeps no energy ledger and takes no device drop: with either,
    // or with a model without FluxModel::current_taylor (tables), the period goes edge by edge
    // with Hermite instead.
    enum class Integrator { Hermite, Rk4, Taylor } integrator = Integrator::Hermite;
    // Decide dead-time edges ahead when the current cannot reach the zero band before them
    // (fewer integration splits, same outcome); false decides every edge at its instant (the
    // tests' reference for that claim).
    bool predecide_edges = true;
    // DC-link voltage over time [V] (optional): evaluated at each period's middle, clamped to
    // >= 0 and held over the period (inverter.vdc then reads the last period's value). Empty:
    // inverter.vdc stays as set (constructor, set_vdc).
    std::function<double(double)> vdc_profile;
};

// Energy ledger since construction [J]; all three-phase (1.5 factor applied).
struct EnergyLedger {
    double electrical_in = 0;    // integral of 1.5 u_dq . i_dq dt (at the machine terminals)
    double copper_loss = 0;      // integral of 1.5 Rs |i|^2 dt
    double mech_out = 0;         // integral of T_e * omega_m dt
    double magnetic = 0;         // 1.5 * (W(psi) - W(psi at construction)), kept current
};

class Plant {
public:
    Plant(const PlantConfig& cfg, std::unique_ptr<FluxModel> model);
    // Advance one PWM period [t, t+Ts] with the given high-side duties (clamped to [0,1]);
    // outputs_enabled = false: all six switches off (currents decay through the diodes).
    void step_period(double Ts, const std::array<double, 3>& duty, bool outputs_enabled);

    double time() const;
    Vec2 psi_dq() const;
    Vec2 i_dq() const;
    std::array<double, 3> i_abc() const;        // instantaneous phase currents [A]
    double theta_e() const;                      // electrical angle, wrapped to [-pi, pi)
    double theta_m() const;                      // mechanical angle, unwrapped [rad]
    double omega_m() const;                      // [rad/s]
    double omega_e() const;
    double torque() const;                       // electromagnetic torque T_e [N m]
    Vec2 u_dq_avg_last() const;                  // average terminal voltage over last period
    Vec2 u_ab_avg_last() const;                  // same, stationary frame (exact: piecewise const)
    std::array<double, 3> v_phase_avg_last() const;  // phase-to-DC-midpoint averages, last period
    Vec2 psi_no_current() const;                 // flux(0): the magnet flux, initial state
    bool floating() const;                       // outputs disabled and all currents gone
    // Overwrite the state (tests, scenario initial conditions); the energy ledger restarts at 0.
    void reset_state(const Vec2& psi_dq, double theta_m, double omega_m);
    const EnergyLedger& energy() const;
    const PlantConfig& config() const;
    const FluxModel& model() const;
    void set_vdc(double vdc);
    // Open-phase fault (docs/plant.md "Open phase"): phase 0..2 disconnected between inverter
    // and machine from now on (its terminal floats, its current is 0; the other two carry i and
    // -i), -1 reconnects none. Opening a phase that carries current snaps its current to 0 (the
    // magnetic energy released is booked as electrical input, as at the floating snap).
    void set_open_phase(int phase);
    int open_phase() const;
    // Phase currents a short time delta after the period boundary (the ADC's conversion delay),
    // to first order: i + delta di/dt with the voltage-time integral over [t, t + delta] of the
    // pattern the duties will switch (rising edges with dead time, device drop), the model's
    // Jacobian at the present state and the back-EMF term; outputs disabled or floating: i_abc().
    std::array<double, 3> i_abc_ahead(double delta, double Ts, const std::array<double, 3>& duty,
                                      bool outputs_enabled) const;

private:
    struct Impl;
    std::shared_ptr<Impl> impl_;
};

}  // namespace mcsim
