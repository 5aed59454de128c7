/* The parameter table's interface (params.c) at its edges: names and groups, bad ids, the
 * "auto" marks, the integer conversion's refusals, the choice texts both ways, and the
 * validation: every entry at both ends of its range and just outside them, every cross-check
 * at its boundary, each refusal with its key, value and range. */
#include <math.h>
#include <string.h>

#include "../mc_test.h"
#include "mc/params.h"
#include "mc/svpwm.h"

static void test_names_and_groups(void **state)
{
    (void)state;
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        assert_int_equal(mc_param_find(mc_param_table[id].name), id);
    }
    assert_int_equal(mc_param_find(NULL), -1);
    assert_int_equal(mc_param_find(""), -1);
    assert_int_equal(mc_param_find("motor"), -1);
    assert_int_equal(mc_param_find("motor.pole_pairs "), -1);
    assert_int_equal(mc_param_find("motor.pole_pair"), -1);
    static const char *const names[MC_PG_COUNT] = {"motor", "hardware", "protection", "control",
                                                   "estimator", "injection", "startup"};
    for (int g = 0; g < (int)MC_PG_COUNT; ++g) {
        assert_string_equal(mc_param_group_name((mc_param_group_t)g), names[g]);
    }
    assert_string_equal(mc_param_group_name(MC_PG_COUNT), "?");
    assert_string_equal(mc_param_group_name((mc_param_group_t)-1), "?");
}

/* Ids outside the table: no value, no mark, nothing written; marks are per id, in any word. */
static void test_bad_ids_and_marks(void **state)
{
    (void)state;
    mc_params_t p, before;
    mc_params_default(&p);
    memcpy(&before, &p, sizeof p);
    static const int bad[] = {-1, -32, (int)MC_PARAM_COUNT, (int)MC_PARAM_COUNT + 1};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        assert_true(isnan(mc_param_get(&p, bad[k])));
        assert_false(mc_param_is_auto(&p, bad[k]));
        mc_param_set_auto(&p, bad[k], true);
        mc_param_err_t err;
        assert_false(mc_param_set(&p, bad[k], 1.0f, &err));
        assert_int_equal(err.kind, MC_PERR_UNKNOWN);
        assert_int_equal(err.param, bad[k]);
        assert_true(err.value == 1.0f && err.min == 0.0f && err.max == 0.0f);
        assert_false(mc_param_set_choice(&p, bad[k], "off", &err));
        assert_int_equal(err.kind, MC_PERR_UNKNOWN);
    }
    assert_memory_equal(&p, &before, sizeof p);
    /* the defaults mark exactly the entries with a rule */
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        assert_int_equal(mc_param_is_auto(&p, id), mc_param_table[id].rule != MC_RULE_NONE);
    }
    /* a mark set or cleared changes that id alone */
    const int ids[] = {0, 31, 32, (int)MC_PARAM_COUNT - 1};
    for (size_t k = 0; k < sizeof ids / sizeof ids[0]; ++k) {
        for (int on = 0; on < 2; ++on) {
            mc_params_t q;
            memcpy(&q, &p, sizeof q);
            mc_param_set_auto(&q, ids[k], on != 0);
            for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
                const bool want = id == ids[k] ? on != 0 : mc_param_is_auto(&p, id);
                assert_int_equal(mc_param_is_auto(&q, id), want);
            }
        }
    }
}

/* Integer entries take whole numbers within +-2e9 only (the conversion of anything else to
 * int32 is undefined); a refusal names the entry, the value and its range and changes nothing,
 * not even the "auto" mark; an accepted value clears it. Floats take anything (the validation
 * judges). */
static void test_set_integer_refusals(void **state)
{
    (void)state;
    mc_params_t p;
    mc_params_default(&p);
    const int id = MC_PARAM_control_offset_cal_samples;   /* I32 with a rule */
    assert_true(mc_param_is_auto(&p, id));
    const float refused[] = {NAN, INFINITY, -INFINITY, nextafterf(2.0e9f, INFINITY), -nextafterf(2.0e9f, INFINITY),
                             2.5f, -0.5f, 64.000008f, 1e-30f};
    const mc_param_err_kind_t kind[] = {MC_PERR_NOT_FINITE, MC_PERR_NOT_FINITE, MC_PERR_NOT_FINITE, MC_PERR_NOT_FINITE,
                                        MC_PERR_NOT_FINITE, MC_PERR_NOT_INTEGER, MC_PERR_NOT_INTEGER,
                                        MC_PERR_NOT_INTEGER, MC_PERR_NOT_INTEGER};
    for (size_t k = 0; k < sizeof refused / sizeof refused[0]; ++k) {
        mc_param_err_t err = {0};
        assert_false(mc_param_set(&p, id, refused[k], &err));
        assert_int_equal(err.kind, kind[k]);
        assert_int_equal(err.param, id);
        assert_int_equal(err.param2, -1);
        assert_true(err.value == refused[k] || (isnan(refused[k]) && isnan(err.value)));
        assert_true(err.min == 1.0f && err.max == 65535.0f);
        assert_non_null(err.text);
        assert_int_equal(p.control_offset_cal_samples, 64);
        assert_true(mc_param_is_auto(&p, id));
        assert_false(mc_param_set(&p, id, refused[k], NULL));
    }
    assert_true(mc_param_set(&p, id, 2.0e9f, NULL));
    assert_int_equal(p.control_offset_cal_samples, 2000000000);
    assert_false(mc_param_is_auto(&p, id));
    assert_true(mc_param_set(&p, id, -2.0e9f, NULL));
    assert_int_equal(p.control_offset_cal_samples, -2000000000);
    assert_true(mc_param_get(&p, id) == -2.0e9f);
    assert_true(mc_param_set(&p, id, -0.0f, NULL));
    assert_int_equal(p.control_offset_cal_samples, 0);
    /* a float entry */
    assert_true(mc_param_set(&p, MC_PARAM_control_i_trip_a, NAN, NULL));
    assert_true(isnan(p.control_i_trip_a));
    assert_true(mc_param_set(&p, MC_PARAM_control_i_trip_a, 2.5f, NULL));
    assert_true(p.control_i_trip_a == 2.5f && mc_param_get(&p, MC_PARAM_control_i_trip_a) == 2.5f);
}

/* The choices of every ENUM both ways: each by its text gives its position, the position reads
 * back as that text; near misses (a prefix, a longer word, two choices, the empty text) are
 * refused as out of range and change nothing. */
static void test_choices(void **state)
{
    (void)state;
    mc_params_t p;
    mc_params_default(&p);
    int enums = 0;
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        if (mc_param_table[id].type != MC_PT_ENUM) {
            mc_param_err_t err;
            assert_false(mc_param_set_choice(&p, id, "off", &err));
            assert_int_equal(err.kind, MC_PERR_UNKNOWN);
            char buf[8] = "xyz";
            mc_param_choice_text(&p, id, buf, sizeof buf);
            assert_string_equal(buf, "");
            continue;
        }
        ++enums;
        char list[128];
        assert_true(strlen(mc_param_table[id].choices) < sizeof list);
        strcpy(list, mc_param_table[id].choices);
        int n = 0;
        for (char *c = strtok(list, "|"); c != NULL; c = strtok(NULL, "|"), ++n) {
            mc_param_err_t err;
            assert_true(mc_param_set(&p, id, 0.0f, NULL));
            mc_param_set_auto(&p, id, true);
            assert_true(mc_param_set_choice(&p, id, c, &err));
            assert_int_equal((int)mc_param_get(&p, id), n);
            assert_false(mc_param_is_auto(&p, id));
            char buf[32];
            mc_param_choice_text(&p, id, buf, sizeof buf);
            assert_string_equal(buf, c);
            /* near misses */
            char w[40];
            const size_t len = strlen(c);
            snprintf(w, sizeof w, "%.*s", (int)(len - 1u), c);
            const char *miss[] = {w, "", "|", NULL};
            char longer[40], two[80];
            snprintf(longer, sizeof longer, "%sx", c);
            snprintf(two, sizeof two, "%s|%s", c, c);
            for (int m = 0; m < 5; ++m) {
                const char *t = m < 3 ? miss[m] : (m == 3 ? longer : two);
                assert_false(mc_param_set_choice(&p, id, t, &err));
                assert_int_equal(err.kind, MC_PERR_RANGE);
                assert_int_equal(err.param, id);
                assert_int_equal((int)mc_param_get(&p, id), n);
            }
            assert_false(mc_param_set_choice(&p, id, NULL, &err));
            assert_int_equal(err.kind, MC_PERR_UNKNOWN);
            /* short buffers: the text cut, always terminated; none at all: nothing written */
            char small[3] = {'#', '#', '#'};
            mc_param_choice_text(&p, id, small, 3u);
            assert_int_equal(small[2], '\0');
            assert_memory_equal(small, c, len < 2u ? len : 2u);
            char one = '#';
            mc_param_choice_text(&p, id, &one, 1u);
            assert_int_equal(one, '\0');
            char none[2] = {'#', '#'};
            mc_param_choice_text(&p, id, none, 0u);
            assert_int_equal(none[0], '#');
            assert_int_equal(none[1], '#');
        }
        assert_int_equal(n, (int)mc_param_table[id].max + 1);
        /* a value past the list has no text */
        assert_true(mc_param_set(&p, id, (float)n, NULL));
        char buf[16] = "xyz";
        mc_param_choice_text(&p, id, buf, sizeof buf);
        assert_string_equal(buf, "");
        assert_true(mc_param_set(&p, id, mc_param_table[id].def, NULL));
    }
    assert_true(enums >= 10);
    char buf[8] = "xyz";
    mc_param_choice_text(&p, -1, buf, sizeof buf);
    assert_string_equal(buf, "");
    mc_param_choice_text(&p, (int)MC_PARAM_COUNT, buf, sizeof buf);
    assert_string_equal(buf, "");
}

/* Every entry at its minimum and maximum passes the range check; just below and just above
 * (the next float, the next integer) it is refused with its key, the value and the range; a NaN
 * float is "not finite". */
static void test_validate_every_range(void **state)
{
    (void)state;
    for (int id = 0; id < (int)MC_PARAM_COUNT; ++id) {
        const mc_param_info_t *e = &mc_param_table[id];
        const bool is_f = e->type == MC_PT_F32;
        const float below = is_f ? nextafterf(e->min, -INFINITY) : e->min - 1.0f;
        const float above = is_f ? nextafterf(e->max, INFINITY) : e->max + 1.0f;
        const float vals[4] = {e->min, e->max, below, above};
        for (int k = 0; k < 4; ++k) {
            mc_params_t p;
            mc_params_default(&p);
            assert_true(mc_param_set(&p, id, vals[k], NULL));
            mc_param_err_t err = {0};
            const bool ok = mc_params_validate(&p, &err);
            if (k < 2) {
                if (!ok && err.param == id && (err.kind == MC_PERR_RANGE || err.kind == MC_PERR_NOT_FINITE)) {
                    fail_msg("%s = %.9g (its %s) refused as out of range", e->name, (double)vals[k], k == 0 ? "min" : "max");
                }
                continue;
            }
            if (ok || err.kind != MC_PERR_RANGE || err.param != id || err.value != vals[k] || err.min != e->min ||
                err.max != e->max || err.param2 != -1) {
                fail_msg("%s = %.9g: kind %d param %d value %g range %g..%g", e->name, (double)vals[k], (int)err.kind,
                         err.param, (double)err.value, (double)err.min, (double)err.max);
            }
        }
        if (is_f) {
            mc_params_t p;
            mc_params_default(&p);
            assert_true(mc_param_set(&p, id, NAN, NULL));
            mc_param_err_t err = {0};
            assert_false(mc_params_validate(&p, &err));
            assert_int_equal(err.kind, MC_PERR_NOT_FINITE);
            assert_int_equal(err.param, id);
        }
    }
    mc_params_t p;
    mc_params_default(&p);
    assert_true(mc_params_validate(&p, NULL));
    assert_true(mc_param_set(&p, MC_PARAM_motor_pole_pairs, 0.0f, NULL));
    assert_false(mc_params_validate(&p, NULL));
}

/* One cross-check refusal: kind, both keys, both values, the range it gives for the first. */
static void expect_cross(const mc_params_t *p, int id, int id2, float lo, float hi)
{
    mc_param_err_t err = {0};
    assert_false(mc_params_validate(p, &err));
    if (err.kind != MC_PERR_CROSS || err.param != id || err.param2 != id2) {
        fail_msg("kind %d param %d param2 %d, want CROSS %s / %s", (int)err.kind, err.param, err.param2,
                 mc_param_table[id].name, mc_param_table[id2].name);
    }
    assert_true(err.value == mc_param_get(p, id));
    assert_true(err.value2 == mc_param_get(p, id2));
    assert_near(err.min, lo, 1e-6 * fabs(lo));
    assert_near(err.max, hi, 1e-6 * fabs(hi));
    assert_non_null(err.text);
    assert_false(mc_params_validate(p, NULL));
}

static void expect_ok(const mc_params_t *p)
{
    mc_param_err_t err = {0};
    if (!mc_params_validate(p, &err)) {
        fail_msg("refused: kind %d param %s", (int)err.kind, err.param >= 0 ? mc_param_table[err.param].name : "-");
    }
}

/* The cross-checks at their boundaries on the default set (trip 20 A, limit 13.29 A, DC link
 * 300 V in 150..450 V, 10 kHz). */
static void test_validate_cross_checks(void **state)
{
    (void)state;
    mc_params_t p;
    mc_params_default(&p);
    expect_ok(&p);
    /* the current sensor's span: 1.1 x trip */
    p.hw_i_span_a = 1.1f * 20.0f;
    expect_ok(&p);
    p.hw_i_span_a = nextafterf(1.1f * 20.0f, 0.0f);
    expect_cross(&p, MC_PARAM_hw_i_span_a, MC_PARAM_control_i_trip_a, 22.0f, 10000.0f);
    mc_params_default(&p);
    /* the current limit below the trip */
    p.control_i_max_a = nextafterf(20.0f, 0.0f);
    expect_ok(&p);
    p.control_i_max_a = 20.0f;
    expect_cross(&p, MC_PARAM_control_i_max_a, MC_PARAM_control_i_trip_a, 0.01f, 20.0f);
    mc_params_default(&p);
    /* the nominal DC link inside the trip window, each side naming its own limit */
    p.hw_vdc_nominal_v = nextafterf(150.0f, 1000.0f);
    expect_ok(&p);
    p.hw_vdc_nominal_v = 150.0f;
    expect_cross(&p, MC_PARAM_hw_vdc_nominal_v, MC_PARAM_control_vdc_min_v, 150.0f, 450.0f);
    p.hw_vdc_nominal_v = nextafterf(450.0f, 0.0f);
    expect_ok(&p);
    p.hw_vdc_nominal_v = 450.0f;
    expect_cross(&p, MC_PARAM_hw_vdc_nominal_v, MC_PARAM_control_vdc_max_v, 150.0f, 450.0f);
    mc_params_default(&p);
    /* the DC-link sensor's span above the over-voltage trip */
    p.hw_vdc_span_v = nextafterf(450.0f, 1000.0f);
    expect_ok(&p);
    p.hw_vdc_span_v = 450.0f;
    expect_cross(&p, MC_PARAM_hw_vdc_span_v, MC_PARAM_control_vdc_max_v, 450.0f, 5000.0f);
    mc_params_default(&p);
    /* the references' voltage share within the current loop's */
    p.control_u_loop = 1.0f;
    p.control_u_margin = 1.0f;
    expect_ok(&p);
    p.control_u_margin = nextafterf(1.0f, 2.0f);
    expect_cross(&p, MC_PARAM_control_u_margin, MC_PARAM_control_u_loop, 0.1f, 1.0f);
    p.control_u_loop = 1.049f;
    p.control_u_margin = 1.049f;   /* the table's max, below (2.14a)'s 1.0491 */
    expect_ok(&p);
    mc_params_default(&p);
    /* the current loop's bandwidth up to f_s / 20 */
    p.control_current_bw_hz = 500.0f;
    expect_ok(&p);
    p.control_current_bw_hz = 501.0f;
    expect_cross(&p, MC_PARAM_control_current_bw_hz, MC_PARAM_control_ts_s, 10.0f, 500.0f);
    mc_params_default(&p);
    /* the Step III hold at least two periods */
    p.startup_step3_hold_s = 2.0f * 1e-4f;
    expect_ok(&p);
    p.startup_step3_hold_s = nextafterf(2.0f * 1e-4f, 0.0f);
    expect_cross(&p, MC_PARAM_startup_step3_hold_s, MC_PARAM_control_ts_s, 2e-4f, 1.0f);
    mc_params_default(&p);
    /* with the injection (unop): its frequency up to f_s / 2, its voltage inside Vdc / sqrt3 */
    p.injection_f_hz = 6000.0f;
    p.injection_v1_v = 500.0f;
    expect_ok(&p);   /* the encoder: no injection to check */
    p.control_angle_source = MC_ANGLE_SRC_unop;
    p.injection_v1_v = 70.0f;
    expect_cross(&p, MC_PARAM_injection_f_hz, MC_PARAM_control_ts_s, 1.0f, 5000.0f);
    p.injection_kind = MC_CHOICE_injection_kind_off;
    expect_ok(&p);
    p.injection_kind = MC_CHOICE_injection_kind_rect;
    p.injection_f_hz = 5000.0f;
    expect_ok(&p);
    p.injection_f_hz = 5001.0f;
    expect_cross(&p, MC_PARAM_injection_f_hz, MC_PARAM_control_ts_s, 1.0f, 5000.0f);
    p.injection_f_hz = 500.0f;
    p.injection_v1_v = 173.0f;
    expect_ok(&p);
    p.injection_v1_v = 174.0f;
    expect_cross(&p, MC_PARAM_injection_v1_v, MC_PARAM_hw_vdc_nominal_v, 0.0f, 300.0f * 0.57735027f);
    p.injection_kind = MC_CHOICE_injection_kind_off;
    expect_cross(&p, MC_PARAM_injection_v1_v, MC_PARAM_hw_vdc_nominal_v, 0.0f, 300.0f * 0.57735027f);
    mc_params_default(&p);
    /* the three-step start runs on the injection */
    p.startup_init_pos = MC_CHOICE_startup_init_pos_three_step;
    expect_cross(&p, MC_PARAM_startup_init_pos, MC_PARAM_control_angle_source, 0.0f, 0.0f);
    p.control_angle_source = MC_ANGLE_SRC_unop;
    expect_ok(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names_and_groups),
        cmocka_unit_test(test_bad_ids_and_marks),
        cmocka_unit_test(test_set_integer_refusals),
        cmocka_unit_test(test_choices),
        cmocka_unit_test(test_validate_every_range),
        cmocka_unit_test(test_validate_cross_checks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
