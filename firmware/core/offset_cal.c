/* Offsets over whole electrical half-periods (mc/offset_cal.h). */
#include "mc/offset_cal.h"

#include <math.h>

#include "mc/transforms.h"

void mc_ocal_reset(mc_ocal_t *s)
{
    s->n = 0u;
    s->total[0] = s->total[1] = s->total[2] = 0.0f;
}

void mc_ocal_add(mc_ocal_t *s, const uint16_t raw[3])
{
    uint16_t *slot = s->buf[s->n % MC_OCAL_N];
    for (int k = 0; k < 3; ++k) {
        slot[k] = raw[k];
        s->total[k] += (float)raw[k];
    }
    s->n++;
}

bool mc_ocal_mean(const mc_ocal_t *s, float off[3])
{
    if (s->n == 0u) {
        return false;
    }
    for (int k = 0; k < 3; ++k) {
        off[k] = s->total[k] / (float)s->n;
    }
    return true;
}

/* kept sample j (0: the oldest kept), channel k */
static float kept_at(const mc_ocal_t *s, uint32_t kept, uint32_t j, int k)
{
    return (float)s->buf[(s->n - kept + j) % MC_OCAL_N][k];
}

bool mc_ocal_periodic(const mc_ocal_t *s, float omega_e, float ts, float off[3])
{
    const uint32_t kept = s->n < MC_OCAL_N ? s->n : MC_OCAL_N;
    const float w = fabsf(omega_e) * ts;
    if (!(w > 0.0f) || !(ts > 0.0f)) {
        return false;   /* also NaN */
    }
    const float lag = 3.14159265f / w;   /* (O.1)'s L [samples] */
    if (!(lag + 1.0f + (float)MC_OCAL_MIN_PAIRS <= (float)kept)) {
        return false;
    }
    const uint32_t li = (uint32_t)lag;
    const float fr = lag - (float)li;
    const uint32_t pairs = kept - li - 1u;   /* j + li + 1 <= kept - 1 */
    float acc[3] = {0.0f, 0.0f, 0.0f};
    for (uint32_t j = 0u; j < pairs; ++j) {
        for (int k = 0; k < 3; ++k) {
            const float a = kept_at(s, kept, j + li, k), b = kept_at(s, kept, j + li + 1u, k);
            acc[k] += kept_at(s, kept, j, k) + a + fr * (b - a);
        }
    }
    for (int k = 0; k < 3; ++k) {
        off[k] = acc[k] / (2.0f * (float)pairs);
    }
    return true;
}

/* Offsets within the plausible range of mid-scale, or false (then none changes). */
static bool plausible(const mc_offsets_cfg_t *c, const float off[3])
{
    for (int k = 0; k < 3; ++k) {
        if (!(fabsf(off[k] - c->nominal) <= c->tol)) {
            return false;
        }
    }
    return true;
}

void mc_offsets_init(mc_offsets_t *s, const mc_offsets_cfg_t *c)
{
    mc_offsets_restart(s);
    for (int k = 0; k < 3; ++k) {
        s->offset[k] = c->nominal;
    }
}

void mc_offsets_restart(mc_offsets_t *s)
{
    s->count = 0u;
    mc_ocal_reset(&s->ocal);
    s->moved = false;
}

mc_offsets_status_t mc_offsets_add(mc_offsets_t *s, const mc_offsets_cfg_t *c, const uint16_t raw[3])
{
    if (s->count >= c->samples) {
        s->count++;
        return MC_OFFSETS_COUNTING;
    }
    mc_ocal_add(&s->ocal, raw);
    if (++s->count < c->samples) {
        return MC_OFFSETS_COLLECTING;
    }
    float off[3];
    if (!mc_ocal_mean(&s->ocal, off) || !plausible(c, off)) {
        return MC_OFFSETS_FAILED;
    }
    for (int k = 0; k < 3; ++k) {
        s->offset[k] = off[k];
    }
    return MC_OFFSETS_DONE;
}

bool mc_offsets_at_speed(mc_offsets_t *s, const mc_offsets_cfg_t *c, float omega, mc_ab_t *di)
{
    float off[3];
    const bool ok = mc_ocal_periodic(&s->ocal, omega, c->ts, off) && plausible(c, off);
    /* once: the samples belong to this enable's calibration, not to a later catch (a recovery
     * at another speed would pair them at the wrong lag) */
    mc_ocal_reset(&s->ocal);
    if (!ok) {
        *di = (mc_ab_t){0.0f, 0.0f};
        return false;
    }
    const float k = c->amps_per_count;
    const mc_abc_t d = {(s->offset[0] - off[0]) * k, (s->offset[1] - off[1]) * k, (s->offset[2] - off[2]) * k};
    for (int j = 0; j < 3; ++j) {
        s->offset[j] = off[j];
    }
    *di = mc_clarke(d);
    s->moved = true;
    return true;
}
