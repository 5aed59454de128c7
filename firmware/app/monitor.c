/* Monitor block packing (mc/monitor.h). */
#include "mc/monitor.h"
#include <string.h>
#include "mc/bits.h"



void mc_monitor_pack_cmd(const mc_drive_cmd_t *c, uint32_t w[MC_MONITOR_CMD_WORDS])
{
    w[0] = c->enable ? 1u : 0u;
    w[1] = (uint32_t)c->mode;
    w[2] = mc_f32_bits(c->i_ref.d);
    w[3] = mc_f32_bits(c->i_ref.q);
    w[4] = mc_f32_bits(c->torque_ref);
    w[5] = mc_f32_bits(c->speed_ref);
    w[6] = mc_f32_bits(c->theta_init);
}

void mc_monitor_unpack_cmd(const uint32_t w[MC_MONITOR_CMD_WORDS], mc_drive_cmd_t *c)
{
    c->enable = w[0] != 0u;
    /* an unknown mode stays unknown: the drive refuses it at the hand-over (MC_CMD_BAD_MODE) */
    c->mode = w[1] < (uint32_t)MC_MODE_COUNT ? (mc_mode_t)w[1] : MC_MODE_COUNT;
    c->i_ref.d = mc_bits_f32(w[2]);
    c->i_ref.q = mc_bits_f32(w[3]);
    c->torque_ref = mc_bits_f32(w[4]);
    c->speed_ref = mc_bits_f32(w[5]);
    c->theta_init = mc_bits_f32(w[6]);
}

/* One table for both directions: the telemetry's fields in word order (kind: U unsigned, I int,
 * F float, B bool, E enum of the given type). */
#define MC_TM_FIELDS(U, I, F, B, E)                                                              \
    E(state, mc_state_t) E(init_step, mc_init_step_t) U(faults) U(period) F(i_abc.a) F(i_abc.b)    \
    F(i_abc.c) F(vdc) F(theta) F(omega) F(i_dq.d) F(i_dq.q) F(i_ref.d) F(i_ref.q) F(u_dq.d)         \
    F(u_dq.q) F(u_ab.alpha) F(u_ab.beta) F(torque_ref) F(theta_raw) F(omega_raw) I(est_iters)      \
    F(est_cost) F(est_cond) F(u_inj) F(theta1) F(theta2) F(c1) F(c2) B(pol_flip) F(duty[0])        \
    F(duty[1]) F(duty[2]) B(u_limited) B(fw_active) U(cmd_rejected) U(recoveries)                  \
    U(recovered_from) U(polarity_checks) U(polarity_flips) I(polarity_last)                        \
    E(cmd_reject_last, mc_cmd_reject_t) F(pol_z) E(pol_verdict, uint8_t)

void mc_monitor_pack_telem(const mc_drive_telem_t *t, uint32_t w[MC_MONITOR_TM_WORDS])
{
    unsigned k = 0u;
#define PU(f) w[k++] = t->f;
#define PI(f) w[k++] = (uint32_t)t->f;
#define PF(f) w[k++] = mc_f32_bits(t->f);
#define PB(f) w[k++] = t->f ? 1u : 0u;
#define PE(f, type) w[k++] = (uint32_t)t->f;
    MC_TM_FIELDS(PU, PI, PF, PB, PE)
#undef PU
#undef PI
#undef PF
#undef PB
#undef PE
    while (k < MC_MONITOR_TM_WORDS) {
        w[k++] = 0u;
    }
}

void mc_monitor_unpack_telem(const uint32_t w[MC_MONITOR_TM_WORDS], mc_drive_telem_t *t)
{
    unsigned k = 0u;
    memset(t, 0, sizeof *t);
#define UU(f) t->f = w[k++];
#define UI(f) t->f = (int)w[k++];
#define UF(f) t->f = mc_bits_f32(w[k++]);
#define UB(f) t->f = w[k++] != 0u;
#define UE(f, type) t->f = (type)w[k++];
    MC_TM_FIELDS(UU, UI, UF, UB, UE)
#undef UU
#undef UI
#undef UF
#undef UB
#undef UE
}

/* The table must fit the block. */
enum {
#define CU(f) +1
#define CE(f, type) +1
    MC_TM_COUNT = 0 MC_TM_FIELDS(CU, CU, CU, CU, CE)
#undef CU
#undef CE
};
_Static_assert(MC_TM_COUNT <= MC_MONITOR_TM_WORDS, "telemetry does not fit the monitor block");
