/* Maximum torque per ampere (2.22)-(2.24), current circle (2.21), voltage ellipse (2.20) and the
 * field-weakening d current (2.26). Constant-parameter (Ld, Lq, psi_pm) forms plus a table MTPA. */
#ifndef MC_MTPA_H
#define MC_MTPA_H
#include "mc/types.h"

typedef struct { float ld, lq, psi_pm; } mc_lin_params_t;

/* (2.24): d current of the MTPA point for a given q current (sign of iq ignored). */
float mc_mtpa_id(const mc_lin_params_t *p, float iq);
/* (2.8) torque per pole pair: 1.5 * (psi_pm iq + (ld - lq) id iq); multiply by p. */
float mc_torque_pp(const mc_lin_params_t *p, mc_dq_t i);

#define MC_MTPA_TABLE_N 33
/* MTPA table indexed by current magnitude |I| on a uniform grid 0..i_max: gives (id, iq>=0). */
typedef struct {
    float i_max;
    float id[MC_MTPA_TABLE_N];
    float iq[MC_MTPA_TABLE_N];
} mc_mtpa_table_t;
/* Fill from the analytic (2.24) law; a measured/FEM table may be loaded instead. */
void    mc_mtpa_table_fill_linear(mc_mtpa_table_t *t, const mc_lin_params_t *p, float i_max);
mc_dq_t mc_mtpa_table_lookup(const mc_mtpa_table_t *t, float i_mag);   /* linear interp */

/* (2.21): scale-free limit keeping id (priority to the d axis), reducing |iq|. */
mc_dq_t mc_limit_current_circle(mc_dq_t i, float i_max);
/* limit a voltage vector to a circle of radius u_max, d axis priority. */
mc_dq_t mc_limit_voltage_circle(mc_dq_t u, float u_max);
/* (2.26): the largest id (closest to zero from below) the voltage ellipse (2.20) allows for a
 * given iq at speed omega_e with voltage u_max; returns +inf-like FLT_MAX when not limiting. */
float   mc_fw_id_max(const mc_lin_params_t *p, float iq, float omega_e, float u_max);

#endif
