/* I/f open-loop start and low-speed mode (mc/if_start.h; Fatu et al. 2008). */
#include "mc/if_start.h"
#include <math.h>
#include "mc/angle.h"

bool mc_if_cfg_valid(const mc_if_cfg_t *c)
{
    return c->ts > 0.0f && c->i_f > 0.0f && isfinite(c->i_f) && c->accel > 0.0f && isfinite(c->accel) &&
           c->w_l > 0.0f && c->w_h > c->w_l && isfinite(c->w_h) && c->w_tol > 0.0f && c->i_drop >= 0.0f &&
           c->i_min >= 0.0f && c->i_min <= c->i_f && c->delta_h > 0.0f && c->damp >= 0.0f && c->damp < 1.0f;
}

void mc_if_init(mc_if_t *s)
{
    *s = (mc_if_t){.mode = MC_IF_CLOSED, .theta = 0.0f, .omega = 0.0f, .i_mag = 0.0f, .sign = 1.0f, .n = 0u};
}

void mc_if_enter(mc_if_t *s, const mc_if_cfg_t *c, float theta, float omega, float sign)
{
    *s = (mc_if_t){.mode = MC_IF_OPEN, .theta = mc_wrap_pi(theta), .omega = omega, .i_mag = c->i_f,
                   .sign = sign < 0.0f ? -1.0f : 1.0f, .n = 0u, .align = 0u};
}

void mc_if_align(mc_if_t *s, const mc_if_cfg_t *c, float theta, float sign)
{
    mc_if_enter(s, c, theta, 0.0f, sign);
    s->align = 2u * c->n_align;
}

/* Synchronous above w_h: the ramp and the command on the same side beyond w_h, and the
 * estimator's speed on the ramp's (the rotor follows the frame; the EMF estimate is good). */
/* The estimate where a synchronous rotor can be: its load angle between -45 and 135 deg, its
 * speed of the frame's sign. */
static bool plausible(const mc_if_t *s, const mc_if_in_t *in, float delta)
{
    return delta > -0.25f * MC_PI && delta < 0.75f * MC_PI && in->omega_est * s->omega >= 0.0f;
}

static bool sync_above(const mc_if_t *s, const mc_if_cfg_t *c, const mc_if_in_t *in, float delta)
{
    if (in->est_only) {
        return fabsf(in->omega_est) >= c->w_h;
    }
    return plausible(s, in, delta) && fabsf(s->omega) >= c->w_h && s->omega * in->omega_target > 0.0f && fabsf(in->omega_target) >= c->w_h &&
           fabsf(in->omega_est - s->omega) <= c->w_tol;
}

/* To closed loop: this period already on the estimator's angle; i_ref is the current the frame
 * asked for last (the caller takes the loop on from the current that flows). */
static void hand_over(mc_if_t *s, const mc_if_in_t *in, mc_if_out_t *out)
{
    s->mode = MC_IF_CLOSED;
    s->n = 0u;
    out->open = false;
    out->handover = true;
    out->theta = in->theta_est;
    out->omega = in->omega_est;
    out->i_ref = (mc_dq_t){0.0f, s->sign * s->i_mag};
}

void mc_if_step(mc_if_t *s, const mc_if_cfg_t *c, const mc_if_in_t *in, mc_if_out_t *out)
{
    out->handover = false;
    out->entered = false;
    out->reseed = false;
    out->slip = 0.0f;
    out->theta_reseed = 0.0f;
    if (s->mode == MC_IF_CLOSED) {
        if (!(fabsf(in->omega_est) < c->w_l)) {
            out->open = false;
            out->theta = in->theta_est;
            out->omega = in->omega_est;
            out->i_ref = (mc_dq_t){0.0f, 0.0f};
            out->delta = 0.0f;
            return;
        }
        /* below w_l the EMF no longer carries the estimate: open loop from where it is */
        mc_if_enter(s, c, in->theta_est, in->omega_est, in->torque_sign);
        out->entered = true;
    }
    if (s->align > 0u) {
        s->align--;
        out->open = true;
        /* the first step held, the second turned to theta over its length: a jump of the frame
         * would be a current step the loop's delay overshoots (a tracking fault at 2 kHz) */
        const float back = s->align >= c->n_align ? 1.0f : (float)s->align / (float)c->n_align;
        out->theta = mc_wrap_pi(s->theta - s->sign * 0.5f * MC_PI * back);
        out->omega = 0.0f;
        out->delta = s->sign * mc_wrap_pi(in->theta_est - s->theta);
        out->i_ref = (mc_dq_t){0.0f, s->sign * s->i_mag};
        return;
    }
    /* this period's frame; then the ramp (accel ts per period) and the integration for the next */
    out->theta = s->theta;
    out->omega = s->omega;
    const float delta = s->sign * mc_wrap_pi(in->theta_est - s->theta);
    out->delta = delta;
    /* pull-out: from w_l on, where the estimate sees the rotor, the frame's advance since the
     * last period against the estimate's; a rotor in step keeps the sum within its load angle */
    const bool counted = !in->est_only && fabsf(s->omega) >= c->w_l;
    if (counted && s->slip_on) {
        s->slip += s->sign * (mc_wrap_pi(s->theta - s->frame_prev) - mc_wrap_pi(in->theta_est - s->est_prev));
    }
    s->slip_on = counted;
    s->frame_prev = s->theta;
    s->est_prev = in->theta_est;
    out->slip = s->slip;
    const float dw = c->accel * c->ts;
    const float e = (in->est_only ? 0.0f : in->omega_target) - s->omega;
    s->omega += e > dw ? dw : (e < -dw ? -dw : e);
    /* from w_l on the estimate's speed is usable: the frame yields to the rotor's swing a share
     * damp of it, a stabilising feedback as in V/f drives */
    const bool est_ok = !in->est_only && fabsf(s->omega) >= c->w_l && plausible(s, in, delta);
    const float w_frame = est_ok ? s->omega + c->damp * (in->omega_est - s->omega) : s->omega;
    s->theta = mc_wrap_pi(s->theta + w_frame * c->ts);

    const bool sync = sync_above(s, c, in, delta);
    /* from w_l on the EMF carries the estimate: one that cannot be right is moved to the frame */
    out->reseed = !in->est_only && fabsf(out->omega) >= c->w_l && !plausible(s, in, delta);
    out->theta_reseed = mc_wrap_pi(out->theta + s->sign * 0.25f * MC_PI);
    if (out->reseed) {
        s->est_prev = out->theta_reseed;   /* the estimate's jump is not the rotor's motion */
    }
    if (s->mode == MC_IF_OPEN) {
        s->n = sync ? s->n + 1u : 0u;
        if (s->n >= c->n_sync && in->est_only) {
            hand_over(s, in, out);   /* no synchronous frame to reduce in: at once */
            return;
        }
        if (s->n >= c->n_sync) {
            s->mode = MC_IF_REDUCE;
        }
    } else if (!(fabsf(s->omega) >= c->w_h && s->omega * in->omega_target > 0.0f && plausible(s, in, delta))) {
        /* the command went back below w_h, or the estimate left the frame: full current again
         * (a rotor swinging about the frame, which nothing damps, does not count) */
        s->mode = MC_IF_OPEN;
        s->i_mag = c->i_f;
        s->n = 0u;
    } else {
        /* reduce until the torque just balances: the load angle near zero (Fatu et al.) */
        s->i_mag -= c->i_drop * c->ts;
        /* |delta| beyond 90 deg: the load turned (the current's torque opposes its sign), the
         * reduction would only widen it; the speed loop takes over from the torque as it is */
        if (fabsf(delta) <= c->delta_h || fabsf(delta) >= 0.5f * MC_PI || s->i_mag <= c->i_min) {
            s->i_mag = s->i_mag > c->i_min ? s->i_mag : c->i_min;
            hand_over(s, in, out);
            return;
        }
    }
    out->open = true;
    out->i_ref = (mc_dq_t){0.0f, s->sign * s->i_mag};
}
