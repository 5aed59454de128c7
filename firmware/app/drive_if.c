/* The drive's I/f hook (mc/if_start.h, issue 24 Deliver 4): below the hand-over speed, on a
 * motor whose saliency the injection cannot read (or with startup.init_pos = if_start), the
 * current loop runs on the I/f frame instead of the estimator's angle; the estimator runs on in
 * parallel and takes over above it, its speed loop preset with the torque then produced. The
 * I/f state shares the phase programs' workspace (they never run in RUN): it is set up again at
 * every RUN entry (the sequencer's first RUN period). */
#include <math.h>
#include "drive_internal.h"
#include "mc/angle.h"
#include "mc/sincos.h"
#include "mc/transforms.h"

void mc_drive_if_reset(mc_drive_t *d)
{
    d->if_open = false;
    d->tm.if_mode = 0u;
}

/* The torque of the current i_dq in the controller's model [N m] (1.5 p (psi i_q + (Ld - Lq)
 * i_d i_q)): the speed loop's integrator starts from it at the hand-over (bumpless). */
static float torque_of(const mc_drive_t *d, mc_dq_t i)
{
    const mc_lin_params_t *m = &d->cfg->tref.mach;
    return 1.5f * (float)d->cfg->blk.pole_pairs * (m->psi_pm * i.q + (m->ld - m->lq) * i.d * i.q);
}

/* RUN entered (from the calibration, Step III or a catch): closed loop; standing with no angle
 * known (if_start, or auto without saliency), the frame and the estimator start at 0 after the
 * alignment (the given angle is not used); a rotor caught turning keeps the catch's estimate. */
static void run_entry(mc_drive_t *d, const mc_drive_blk_t *b, mc_angle_out_t *ang)
{
    mc_if_init(&d->ifs);
    if (fabsf(ang->omega) >= b->ifs.w_l) {
        return;
    }
    const float sign = (d->cmd.mode == MC_MODE_SPEED ? d->cmd.speed_ref : d->cmd.torque_ref) < 0.0f ? -1.0f : 1.0f;
    if (b->if_from_zero) {
        d->src->reset(&d->src_state, 0.0f, 0.0f);
        ang->theta = 0.0f;
        ang->omega = 0.0f;
        mc_if_align(&d->ifs, &b->ifs, 0.0f, sign);
    } else {
        /* an angle known (given): the frame a quarter turn behind the rotor, where an unloaded
         * rotor rests under I_f (the current on its d axis), not a swing of 90 deg first */
        mc_if_enter(&d->ifs, &b->ifs, mc_wrap_pi(ang->theta - sign * 0.5f * MC_PI), 0.0f, sign);
    }
}

bool mc_drive_if_step(mc_drive_t *d, mc_angle_out_t *ang, mc_ab_t i_ab, mc_dq_t *i_ref)
{
    const mc_drive_blk_t *b = &d->cfg->blk;
    d->tm.if_on = b->if_on;
    d->if_open = false;
    d->tm.if_mode = 0u;
    if (!b->if_on || d->seq.state != MC_STATE_RUN || d->cmd.mode == MC_MODE_CURRENT) {
        return false;
    }
    if (d->seq.ticks == 1u) {
        run_entry(d, b, ang);
    }
    const bool speed = d->cmd.mode == MC_MODE_SPEED;
    const mc_if_in_t in = {.omega_target = speed ? d->cmd.speed_ref * (float)b->pole_pairs : 0.0f,
                           .theta_est = ang->theta, .omega_est = ang->omega,
                           .torque_sign = d->tm.torque_ref != 0.0f ? d->tm.torque_ref : (speed ? d->cmd.speed_ref : d->cmd.torque_ref),
                           .est_only = !speed};
    mc_if_out_t out;
    mc_if_step(&d->ifs, &b->ifs, &in, &out);
    d->tm.if_mode = (uint8_t)d->ifs.mode;
    if (out.handover) {
        /* the loop goes on from the current that flows, seen in the estimator's frame, and the
         * speed loop from the torque it makes */
        const mc_dq_t i_est = mc_park(i_ab, mc_sincos(ang->theta));
        d->i_ref_prev = i_est;
        mc_sc_reset(&d->sc, torque_of(d, i_est));
        return false;
    }
    if (!out.open) {
        return false;
    }
    if (out.reseed) {
        d->src->reset(&d->src_state, out.theta_reseed, out.omega);
    }
    ang->theta = out.theta;
    ang->omega = out.omega;
    *i_ref = out.i_ref;
    d->if_open = true;
    return true;
}
