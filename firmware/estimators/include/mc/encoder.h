/* Encoder angle source: counter -> electrical angle (2.18), speed through the PLL (3.9) instead of
 * the count difference (2.19), which is too coarse at 10 kHz. */
#ifndef MC_ENCODER_H
#define MC_ENCODER_H
#include "mc/angle_source.h"
#include "mc/pll.h"

typedef struct {
    int      pole_pairs;
    uint32_t counts_per_rev;   /* 4 * lines                                          */
    float    offset_rad;       /* electrical rotor angle at count 0 (theta = count angle + offset) */
    float    ts;               /* [s]                                                 */
    float    pll_bw_hz;        /* speed-estimation bandwidth                          */
    float    speed_fc_hz;      /* speed output filter                                 */
} mc_encoder_cfg_t;

typedef struct {
    mc_encoder_cfg_t cfg;
    mc_pll_t pll;
    float rad_per_count;       /* electrical rad per (count * p) */
    bool narrow;               /* counts_per_rev * p fits 32 bits: 32-bit residue arithmetic */
    uint32_t max_step;         /* largest count change tracked without a division: step * p < cpr */
    bool tracking;             /* last_count / last_elec hold a computed pair                  */
    uint32_t last_count;       /* counter of the previous step                                 */
    uint32_t last_elec;        /* (last_count * p) mod cpr                                     */
    bool primed;
} mc_encoder_t;

void mc_encoder_init(mc_encoder_t *s, const mc_encoder_cfg_t *cfg);
void mc_encoder_reset(mc_encoder_t *s);
void mc_encoder_step(mc_encoder_t *s, const mc_angle_in_t *in, mc_angle_out_t *out);

#endif
