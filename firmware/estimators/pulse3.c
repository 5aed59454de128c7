/* Three-phase pulse reference method (3.19)-(3.21) with Table 3.1. */
#include "mc/pulse3.h"

#include <math.h>
#include <stddef.h>

#include "mc/angle.h"
#include "mc/transforms.h"

enum { ST_RUN = 0, ST_DONE, ST_FAILED };

#define DEG2RAD (MC_PI / 180.0f)
/* relative fluctuation |dI| / I_0 below which there is no saliency to measure */
#define SAL_MIN 1e-4f

static float absf(float x) { return (x < 0.0f) ? -x : x; }

void mc_pulse3_cfg_default(mc_pulse3_cfg_t *cfg)
{
    cfg->rs = 0.0f;
    cfg->n = 5;
    cfg->gap_min = 2;
    cfg->gap_max = 50;
    cfg->i_rest = 0.3f;
    cfg->i_trip = 0.0f;
}

bool mc_pulse3_start(mc_pulse3_t *s, const mc_pulse3_cfg_t *cfg)
{
    static const unsigned v[3] = {MC_IP_V100, MC_IP_V010, MC_IP_V001};
    s->cfg = *cfg;
    s->state = ST_FAILED;
    s->calls = 0;
    s->sector = -1;
    s->theta = 0.0f;
    s->theta_atan = 0.0f;
    for (int k = 0; k < 3; ++k) {
        s->ipk[k] = 0.0f;
        s->di[k] = 0.0f;
        s->i_start[k] = 0.0f;
        s->seen[k] = false;
    }
    mc_ip_run_init(&s->prog, cfg->rs, cfg->i_rest, cfg->i_trip, cfg->gap_max);
    if (cfg->n < 1 || cfg->n > MC_IP_M_MAX) {
        return false;
    }
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
        ok = ok && mc_ip_run_direct(&s->prog, v[k], cfg->n, k);
        ok = ok && mc_ip_run_direct(&s->prog, 7u & ~v[k], cfg->n, -1);
        if (k < 2) {
            ok = ok && mc_ip_run_gap(&s->prog, cfg->gap_min);
        }
    }
    if (ok) {
        s->state = ST_RUN;
    }
    return ok;
}

int mc_pulse3_sector(const float di[3])
{
    /* Table 3.1 in the firmware's phase order: the signs of cos 2t, cos(2t + 120),
     * cos(2t - 120) on each 30-deg sector (the thesis's b and c columns exchanged, see the
     * header); index = 4 [dIa > 0] + 2 [dIb > 0] + [dIc > 0] */
    static const int8_t row[8] = {
        -1, /* - - - */ 2, /* - - + : [45, 75]  */ 4, /* - + - : [105, 135] */
        3,  /* - + + : [75, 105] */ 0, /* + - - : [-15, 15] */ 1, /* + - + : [15, 45]   */
        5,  /* + + - : [135, 165] */ -1 /* + + + */};
    int idx = (di[0] > 0.0f ? 4 : 0) + (di[1] > 0.0f ? 2 : 0) + (di[2] > 0.0f ? 1 : 0);
    return row[idx];
}

bool mc_pulse3_angle(const float ipk[3], float *theta, float *theta_atan, int *sector)
{
    float i0 = (ipk[0] + ipk[1] + ipk[2]) * (1.0f / 3.0f);
    float di[3] = {ipk[0] - i0, ipk[1] - i0, ipk[2] - i0};
    float num = MC_SQRT3 * (di[2] - di[1]);
    float den = 2.0f * di[0] - di[1] - di[2];
    *sector = mc_pulse3_sector(di);
    *theta_atan = 0.0f;
    *theta = 0.0f;
    if (!(absf(num) + absf(den) > SAL_MIN * absf(i0)) || *sector < 0) {
        return false;
    }
    /* (3.21) with b and c exchanged; arctan of the ratio: 2 theta only known modulo pi */
    float ta = (absf(den) > 0.0f) ? 0.5f * atanf(num / den)
                                  : ((num > 0.0f) ? 0.25f * MC_PI : -0.25f * MC_PI);
    *theta_atan = ta;
    /* Table 3.1 picks theta_atan or theta_atan + 90 deg: the one nearer the sector centre */
    float centre = (float)(*sector) * 30.0f * DEG2RAD;
    float c0 = ta, c1 = ta + 0.5f * MC_PI;
    float e0 = absf(mc_wrap_pi(2.0f * (c0 - centre))), e1 = absf(mc_wrap_pi(2.0f * (c1 - centre)));
    float t = mc_wrap_2pi((e0 <= e1) ? c0 : c1);
    if (t >= MC_PI) {
        t -= MC_PI;
    }
    *theta = (t >= 0.0f && t < MC_PI) ? t : 0.0f;
    return true;
}

/* (3.19) peak rise of pulse t on one of its intervals; the intervals arrive in time order.
 * Measured from the pulse's first sample: the gap leaves up to i_rest, which would otherwise
 * enter (3.19) as a false fluctuation. */
static void track_peak(mc_pulse3_t *s, const mc_ip_rec_t *r, int t)
{
    mc_abc_t p0 = mc_clarke_inv(r->i0), p1 = mc_clarke_inv(r->i1);
    float v0 = (t == 0) ? p0.a : ((t == 1) ? p0.b : p0.c);
    float v1 = (t == 0) ? p1.a : ((t == 1) ? p1.b : p1.c);
    if (!s->seen[t]) {
        s->i_start[t] = v0;
        s->seen[t] = true;
    }
    if (v1 - s->i_start[t] > s->ipk[t]) {
        s->ipk[t] = v1 - s->i_start[t];
    }
}

mc_ip_status_t mc_pulse3_step(mc_pulse3_t *s, mc_ab_t i_ab, float vdc, mc_abc_t *duty)
{
    duty->a = duty->b = duty->c = 0.0f;
    if (s->state != ST_RUN) {
        return (s->state == ST_DONE) ? MC_IP_DONE : MC_IP_FAILED;
    }
    s->calls++;
    mc_ip_rec_t r;
    int tag;
    mc_ip_status_t st = mc_ip_run_step(&s->prog, i_ab, vdc, duty, &r, &tag);
    if (st == MC_IP_FAILED) {
        s->state = ST_FAILED;
        duty->a = duty->b = duty->c = 0.0f;
        return MC_IP_FAILED;
    }
    if (tag >= 0 && tag <= 2) {
        track_peak(s, &r, tag);
    }
    if (st != MC_IP_DONE) {
        return MC_IP_RUNNING;
    }
    float i0 = (s->ipk[0] + s->ipk[1] + s->ipk[2]) * (1.0f / 3.0f);
    for (int k = 0; k < 3; ++k) {
        s->di[k] = s->ipk[k] - i0;
    }
    if (!mc_pulse3_angle(s->ipk, &s->theta, &s->theta_atan, &s->sector)) {
        s->state = ST_FAILED;
        return MC_IP_FAILED;
    }
    s->state = ST_DONE;
    return MC_IP_DONE;
}
