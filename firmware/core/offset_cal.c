/* Offsets over whole electrical half-periods (mc/offset_cal.h). */
#include "mc/offset_cal.h"

#include <math.h>

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
