/* The drive's telemetry channels: every number of mc_drive_telem_t a PC may want to see, once,
 * with a stable id (1-based; 0 means "no channel"), a name, a unit and how it is read from a
 * telemetry record. Used by the scope (mc/scope.h: its channels are these ids), the CANopen
 * telemetry objects 0x2200 + id (REAL32, read-only, PDO-mappable) and the generated EDS and
 * docs/can.md. Append new channels, never reorder (an id is part of the bus contract).
 *
 * X(id, name, "unit", expression over `const mc_drive_telem_t *t`, "doc") */
#ifndef MC_TELEM_CHANNELS_H
#define MC_TELEM_CHANNELS_H
#include "mc/drive.h"

/* clang-format off */
#define MC_TELEM_CHANNELS(X) \
X(1,  state,      "",       (float)t->state,        "Drive state (mc_state_t: 0 idle, 1 offset calibration, 2 run, 3 fault, 4 initial position, 5 fault reaction).") \
X(2,  init_step,  "",       (float)t->init_step,    "Initial-position step (0 none, 1 Step I, 2 Step II, 3 Step III, 4 flying-start catch).") \
X(3,  i_a,        "A",      t->i_abc.a,             "Phase current a.") \
X(4,  i_b,        "A",      t->i_abc.b,             "Phase current b.") \
X(5,  i_c,        "A",      t->i_abc.c,             "Phase current c.") \
X(6,  vdc,        "V",      t->vdc,                 "DC-link voltage.") \
X(7,  theta,      "rad",    t->theta,               "Electrical angle the controller used.") \
X(8,  omega,      "rad/s",  t->omega,               "Electrical speed estimate (after the PLL / encoder filter).") \
X(9,  i_d,        "A",      t->i_dq.d,              "d current in the controller's frame.") \
X(10, i_q,        "A",      t->i_dq.q,              "q current in the controller's frame.") \
X(11, i_d_ref,    "A",      t->i_ref.d,             "d current reference.") \
X(12, i_q_ref,    "A",      t->i_ref.q,             "q current reference.") \
X(13, u_d,        "V",      t->u_dq.d,              "Commanded d voltage.") \
X(14, u_q,        "V",      t->u_dq.q,              "Commanded q voltage.") \
X(15, u_alpha,    "V",      t->u_ab.alpha,          "Voltage the modulator realised, alpha.") \
X(16, u_beta,     "V",      t->u_ab.beta,           "Voltage the modulator realised, beta.") \
X(17, torque_ref, "N m",    t->torque_ref,          "Torque reference.") \
X(18, theta_raw,  "rad",    t->theta_raw,           "Angle source before its filter (UNOP's raw estimate).") \
X(19, omega_raw,  "rad/s",  t->omega_raw,           "Speed of the angle source before its filter.") \
X(20, est_iters,  "",       (float)t->est_iters,    "Estimator Newton iterations this period.") \
X(21, est_cost,   "",       t->est_cost,            "Estimator final cost (6.5).") \
X(22, est_cond,   "",       t->est_cond,            "Estimator Hessian conditioning.") \
X(23, u_inj,      "V",      t->u_inj,               "Injected d voltage (6.4).") \
X(24, duty_a,     "1",      t->duty[0],             "Duty of phase a.") \
X(25, duty_b,     "1",      t->duty[1],             "Duty of phase b.") \
X(26, duty_c,     "1",      t->duty[2],             "Duty of phase c.") \
X(27, faults,     "",       (float)(t->faults & MC_FAULTS_ALL), "Latched fault bits (mc/faults.h MC_FAULT_*).")
/* clang-format on */

#define MC_TELEM_CHANNEL_COUNT 27

/* The value of channel id (1..MC_TELEM_CHANNEL_COUNT) in t; NaN for an unknown id. */
static inline float mc_telem_channel(const mc_drive_telem_t *t, unsigned id)
{
    switch (id) {
#define MC_TELEM_CASE_(id_, name_, unit_, expr_, doc_) \
    case id_:                                         \
        return (expr_);
        MC_TELEM_CHANNELS(MC_TELEM_CASE_)
#undef MC_TELEM_CASE_
    default:
        return __builtin_nanf("");
    }
}

#endif
