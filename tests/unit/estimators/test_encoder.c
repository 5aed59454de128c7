/* Encoder angle source: the electrical angle (2.18) from (count * p) mod cpr, whichever way the
 * block gets the residue (tracked from the last count, 32-bit or 64-bit division), and the PLL
 * speed of a steady count ramp. */
#include "../mc_test.h"

#include "mc/angle.h"
#include "mc/encoder.h"

static void make(mc_encoder_t *s, int pp, uint32_t cpr)
{
    const mc_encoder_cfg_t c = {.pole_pairs = pp, .counts_per_rev = cpr, .offset_rad = 0.3f, .ts = 1e-4f,
                                .pll_bw_hz = 150.0f, .speed_fc_hz = 500.0f};
    mc_encoder_init(s, &c);
}

/* the angle as the block documents it, residue taken in 64 bits */
static float ref_theta(const mc_encoder_t *s, uint32_t count)
{
    const uint64_t r = ((uint64_t)count * (uint64_t)s->cfg.pole_pairs) % s->cfg.counts_per_rev;
    return mc_wrap_pi((float)(uint32_t)r * s->rad_per_count + s->cfg.offset_rad);
}

static void step_and_check(mc_encoder_t *s, uint32_t count)
{
    const mc_angle_in_t in = {.qep_count = count};
    mc_angle_out_t out;
    mc_encoder_step(s, &in, &out);
    const float want = ref_theta(s, count);
    if (out.theta != want) {
        fail_msg("pp %d cpr %u count %u (last %u): theta %.9g, want %.9g", s->cfg.pole_pairs,
                 (unsigned)s->cfg.counts_per_rev, (unsigned)count, (unsigned)s->last_count,
                 (double)out.theta, (double)want);
    }
}

static void check_counts(mc_encoder_t *s)
{
    uint64_t st = 12345u;
    for (int k = 0; k < 200000; ++k) {
        uint32_t count;
        if (k < 1000) {
            count = (uint32_t)k;                       /* around zero            */
        } else if (k < 2000) {
            count = UINT32_MAX - (uint32_t)(k - 1000);   /* up to the counter wrap */
        } else {
            st = st * 6364136223846793005ULL + 1442695040888963407ULL;
            count = (uint32_t)(st >> 32);
        }
        step_and_check(s, count);
    }
}

static void test_angle_is_the_residue(void **state)
{
    (void)state;
    mc_encoder_t s;
    make(&s, 5, 80000u);                 /* the bench encoder: 32-bit residue */
    assert_true(s.narrow);
    check_counts(&s);
    make(&s, 5, 858993459u);             /* cpr * p = 2^32 - 1: the widest 32-bit case */
    assert_true(s.narrow);
    check_counts(&s);
    make(&s, 4, 1073741824u);            /* cpr * p = 2^32: 64-bit residue */
    assert_false(s.narrow);
    check_counts(&s);
    make(&s, 3, 4000000000u);
    assert_false(s.narrow);
    check_counts(&s);
    make(&s, 1, 4u);
    assert_true(s.narrow);
    check_counts(&s);
}

/* The residue is tracked from the last count without a division when the counter moved less
 * than max_step: steps on both sides of that bound, both directions, across the counter wrap
 * (where 2^32 is no multiple of cpr and the full path must take over). */
static void test_tracked_residue(void **state)
{
    (void)state;
    const struct { int pp; uint32_t cpr; } cfgs[] = {
        {5, 80000u}, {4, 4096u}, {7, 10000u}, {1, 4u}, {5, 858993459u}, {3, 4000000000u}, {5, 4u},
    };
    for (size_t c = 0; c < sizeof cfgs / sizeof cfgs[0]; ++c) {
        mc_encoder_t s;
        make(&s, cfgs[c].pp, cfgs[c].cpr);
        const uint32_t m = s.max_step;
        assert_true((uint64_t)m * (uint64_t)cfgs[c].pp < cfgs[c].cpr);
        uint64_t st = 777u + c;
        uint32_t count = UINT32_MAX - 3u * m - 50u;
        for (int k = 0; k < 100000; ++k) {
            st = st * 6364136223846793005ULL + 1442695040888963407ULL;
            const uint32_t r = (uint32_t)(st >> 33);
            int64_t delta;
            switch (r % 8u) {
            case 0u: delta = (int64_t)m; break;          /* the largest tracked step */
            case 1u: delta = (int64_t)m + 1; break;      /* one beyond: full path    */
            case 2u: delta = -(int64_t)m; break;
            case 3u: delta = -(int64_t)m - 1; break;
            case 4u: delta = (int64_t)(r >> 3) - (int64_t)(UINT32_MAX >> 4); break;   /* jumps */
            default: delta = (int64_t)((r >> 3) % (2u * m + 1u)) - (int64_t)m; break;
            }
            count = (uint32_t)((int64_t)count + delta);   /* wraps like the hardware counter */
            step_and_check(&s, count);
        }
        /* a steady forward ramp through the counter wrap */
        count = UINT32_MAX - 5u * (m + 1u);
        for (int k = 0; k < 20; ++k) {
            step_and_check(&s, count);
            count += (m > 0u) ? m : 1u;
        }
    }
    /* new parameters: the tracked pair of the old ones must not be used */
    mc_encoder_t s;
    make(&s, 5, 80000u);
    step_and_check(&s, 123456u);
    assert_true(s.tracking);
    make(&s, 4, 80000u);
    assert_false(s.tracking);
    step_and_check(&s, 123457u);
    make(&s, 4, 70000u);
    step_and_check(&s, 123458u);
}

static void test_speed_of_a_ramp(void **state)
{
    (void)state;
    mc_encoder_t s;
    make(&s, 5, 80000u);
    /* 600 rpm = 80 counts per period of 0.1 ms; the counter wraps after 1250 periods (a jump
     * in angle, as 2^32 is no multiple of cpr) and the PLL has settled again 75 ms later */
    uint32_t count = UINT32_MAX - 100000u;
    mc_angle_out_t out = {0.0f, 0.0f};
    for (int k = 0; k < 2000; ++k) {
        const mc_angle_in_t in = {.qep_count = count};
        mc_encoder_step(&s, &in, &out);
        count += 80u;
    }
    const double we = 600.0 / 60.0 * 2.0 * PI_D * 5.0;
    assert_near(out.omega, we, 1e-3 * we);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_angle_is_the_residue),
        cmocka_unit_test(test_tracked_residue),
        cmocka_unit_test(test_speed_of_a_ramp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
