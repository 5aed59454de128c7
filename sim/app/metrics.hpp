// Metrics accumulated every control period; written to metrics.json (keys: docs/simulator.md).
#pragma once
#include <cmath>
#include <string>
#include <vector>
#include "scenario.hpp"

namespace mcsim {

struct Sample {
    double t;
    bool running;           // drive in RUN
    double angle_err_deg;   // wrapped (controller angle - true angle)
    double speed_rpm, speed_ref_rpm;   // ref NaN when none
    double id, iq, id_ref, iq_ref;
    double torque;
    double i_peak;          // max |i_abc| (true)
    int iters;              // estimator Newton iterations this period (-1: no estimator)
    // startup (thesis ch. 5)
    int state = 2;          // drive state (mc_state_t), init step (mc_init_step_t)
    int init_step = 0;
    double angle_err_any = NAN;   // angle error whenever the control pipeline runs (RUN, Step III)
    double theta_true_deg = 0;    // electrical
    double theta_e_unwrapped = 0; // electrical angle travelled [rad], for the reverse rotation
    double theta1_deg = NAN, theta2_deg = NAN;   // Step I (mod 180) and Step II results
    double direction = 1;         // sign of the intended rotation
    double ts = 1e-4;
    bool if_on = false;           // the drive is configured for I/f (mc/if_start.h)
    bool if_open = false;         // ... and its open loop runs: the angle is the frame's, not an
                                  // estimate (left out of the angle-error statistics)
};

class Metrics {
public:
    explicit Metrics(const Scenario& sc);
    void add(const Sample& s);
    // faults: names of latched faults; extra: further "key": value pairs (already JSON).
    std::string json(const std::vector<std::string>& faults, const std::string& final_state,
                     const std::vector<std::pair<std::string, std::string>>& extra) const;

private:
    struct Acc {
        double n = 0, err_sum = 0, err_absmax = 0;
        double sp_n = 0, sp_sq = 0, sp_max_abs = 0, sp_sum = 0, ref_sum = 0;
        double id_sum = 0, iq_sum = 0, tq_sum = 0, i_peak = 0, speed_sum = 0;
        double tq_all_sum = 0;   // the machine's torque over every sample, running or not
        double run_n = 0;
        double err_n = 0, if_n = 0;   // running samples with an estimated angle / in I/f's open loop
    };
    void acc_add(Acc& a, const Sample& s) const;
    void add_startup(const Sample& s);
    double start_, settle_from_, band_;
    std::string settle_signal_;
    std::vector<Window> windows_;
    std::vector<Acc> win_acc_;
    Acc steady_;
    double angle_err_max_ = 0, i_peak_ = 0;
    bool if_seen_ = false;        // I/f configured: its metrics are written (else the keys are absent)
    double if_open_s_ = 0;        // time in I/f's open loop
    double iter_sum_ = 0, iter_n_ = 0;
    double e0_ = NAN, t90_ = NAN, t10_ = NAN;   // rise time of the settle signal's error
    // startup
    double t_enable_ = NAN, t_init_ = NAN, t_step3_ = NAN, t_run_ = NAN, t_last_bad_ = NAN;
    double t_fault_ = NAN;   // first period in FAULT
    double t_catch_ = NAN, t_catch_end_ = NAN;   // the flying-start catch (init step 4)
    double t_unlocked_ = NAN;   // last sample after the enable not in RUN within 10 deg
    double i_peak_enable_ = 0;  // phase-current peak from the enable on
    double t_first_run_ = NAN;   // first period in RUN
    double step12_err_ = NAN, step1_err_ = NAN, init_err_ = NAN;
    double post_sum_ = 0, post_n_ = 0;   // mean error over the 20 ms after the hand-over
    double th0_ = NAN, reverse_max_ = 0;
    bool was_init_ = false;
    double ts_ = 1e-4;
    int iter_max_ = -1;
    double last_out_of_band_ = -1;     // time of last sample outside the band
    bool any_settle_sample_ = false;
    double last_t_ = 0;
};

std::string json_number(double v);
// A JSON string literal, quotes included (RFC 8259): '"' and '\\' escaped, control characters as
// \n, \t, ... or \u00XX, and bytes that are not valid UTF-8 replaced by U+FFFD, so that any
// std::string (a scenario or window name with quotes, NUL bytes, binary) gives valid JSON.
std::string json_string(const std::string& s);
// ["a", "b"]: json_string of each
std::string json_string_array(const std::vector<std::string>& v);

}  // namespace mcsim
