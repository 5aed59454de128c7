/* The fault table (mc/faults.h) is consistent, and what the device sends follows it: bits unique
 * and below 24 (the telemetry's float32 word), names unique and plain, every EMCY code one the
 * table declares and in its CiA 301 class with a matching error-register bit, the generated masks
 * and the EMCY mapping (co_emcy.c) equal to the rows, and the rows on the bus frozen. */
#include <string.h>
#include "../mc_test.h"
#include "mc/co.h"
#include "mc/faults.h"

typedef struct {
    uint32_t mask;   /* MC_FAULT_<NAME> */
    int bit;
    const char *name;
    uint16_t emcy;
    uint8_t reg;
    int reaction;
    int recoverable;
    const char *doc;
} row_t;

static const row_t rows[] = {
#define ROW(NAME, bit, name, emcy, reg, reaction, rec, doc) \
    {(uint32_t)MC_FAULT_##NAME, bit, name, emcy, MC_ERR_REG_##reg, MC_FAULT_REACT_##reaction, rec, doc},
    MC_FAULTS(ROW)
#undef ROW
};
#define N_ROWS (sizeof rows / sizeof rows[0])

static const uint16_t codes[] = {
#define CODE(code, text) code,
    MC_EMCY_CODES(CODE)
#undef CODE
};
#define N_CODES (sizeof codes / sizeof codes[0])

static void test_bits_unique_and_in_range(void **st)
{
    (void)st;
    uint32_t seen = 0u;
    for (size_t k = 0; k < N_ROWS; ++k) {
        const row_t *r = &rows[k];
        /* < 24: telem.faults (0x221B) is a REAL32, exact up to 2^24 */
        if (r->bit < 0 || r->bit >= 24) {
            fail_msg("%s: bit %d outside 0..23", r->name, r->bit);
        }
        if ((seen & (1u << r->bit)) != 0u) {
            fail_msg("%s: bit %d given twice", r->name, r->bit);
        }
        if (k > 0 && r->bit <= rows[k - 1].bit) {
            fail_msg("%s: the table is not in bit order (bit %d after %d)", r->name, r->bit, rows[k - 1].bit);
        }
        assert_int_equal(r->mask, 1u << r->bit);
        seen |= 1u << r->bit;
    }
    assert_int_equal(MC_FAULTS_ALL, seen);
}

static void test_names_and_docs(void **st)
{
    (void)st;
    for (size_t k = 0; k < N_ROWS; ++k) {
        const char *n = rows[k].name;
        if (n[0] == '\0' || strspn(n, "abcdefghijklmnopqrstuvwxyz0123456789_") != strlen(n)) {
            fail_msg("bit %d: name \"%s\" is not a lower-case identifier", rows[k].bit, n);
        }
        for (size_t j = 0; j < k; ++j) {
            if (strcmp(n, rows[j].name) == 0) {
                fail_msg("name \"%s\" given twice (bits %d and %d)", n, rows[j].bit, rows[k].bit);
            }
        }
        const char *d = rows[k].doc;
        const size_t len = strlen(d);
        if (len < 10u || d[len - 1u] != '.' || strchr(d, '|') != NULL || strchr(d, '"') != NULL ||
            strchr(d, '\\') != NULL) {
            fail_msg("%s: the doc line must be a sentence without | \" or \\ (markdown, JSON)", n);
        }
    }
}

/* A code in CiA 301 Table 21's classes (main class, first digit; sub-class, second, where the
 * table closes it; CiA 402 refines 5xxx, 7xxx and 8xxx) that names a fault: not 00xx (reset)
 * nor 10xx (generic: what a bit without a row gets) */
static bool cia301_class(uint16_t code)
{
    const unsigned main = code >> 12, sub = (code >> 8) & 0xFu;
    switch (main) {
    case 0x2: case 0x3: case 0x6: return sub <= 3u;   /* current, voltage, software */
    case 0x4: return sub <= 2u;                       /* temperature */
    case 0x5: case 0x7: case 0x8: return true;        /* hardware, modules, monitoring */
    case 0x9: return sub == 0u;                       /* external */
    case 0xF: return sub == 0u || sub == 0xFu;        /* additional functions, device specific */
    default: return false;
    }
}

static void test_emcy_codes_valid(void **st)
{
    (void)st;
    for (size_t k = 0; k < N_CODES; ++k) {
        if (!cia301_class(codes[k])) {
            fail_msg("MC_EMCY_CODES: 0x%04X is not a fault code of CiA 301 Table 21", codes[k]);
        }
        for (size_t j = 0; j < k; ++j) {
            assert_true(codes[j] != codes[k]);
        }
    }
    static const uint8_t reg_bits[] = {MC_ERR_REG_GENERIC,       MC_ERR_REG_CURRENT, MC_ERR_REG_VOLTAGE,
                                       MC_ERR_REG_TEMPERATURE,   MC_ERR_REG_COMMUNICATION,
                                       MC_ERR_REG_PROFILE,       MC_ERR_REG_MANUFACTURER};
    for (size_t k = 0; k < N_ROWS; ++k) {
        const row_t *r = &rows[k];
        bool listed = false;
        for (size_t j = 0; j < N_CODES; ++j) {
            listed = listed || codes[j] == r->emcy;
        }
        if (!listed) {
            fail_msg("%s: EMCY 0x%04X is not in MC_EMCY_CODES", r->name, r->emcy);
        }
        bool one = false;
        for (size_t j = 0; j < sizeof reg_bits; ++j) {
            one = one || r->reg == reg_bits[j];
        }
        if (!one) {
            fail_msg("%s: error-register class 0x%02X is not one bit of 0x1001", r->name, r->reg);
        }
        /* CiA 301: the current, voltage, temperature and communication classes set their bit */
        static const struct { uint8_t hi; uint8_t reg; } need[] = {
            {0x2, MC_ERR_REG_CURRENT}, {0x3, MC_ERR_REG_VOLTAGE}, {0x4, MC_ERR_REG_TEMPERATURE}};
        for (size_t j = 0; j < sizeof need / sizeof need[0]; ++j) {
            if ((r->emcy >> 12) == need[j].hi && r->reg != need[j].reg) {
                fail_msg("%s: EMCY 0x%04X needs error-register bit 0x%02X", r->name, r->emcy, need[j].reg);
            }
        }
        if ((r->emcy >> 8) == 0x81u && r->reg != MC_ERR_REG_COMMUNICATION) {
            fail_msg("%s: EMCY 0x%04X needs the communication bit", r->name, r->emcy);
        }
    }
}

/* co_emcy.c sends what the table says; a bit without a row is generic */
static void test_device_mapping_follows_table(void **st)
{
    (void)st;
    for (size_t k = 0; k < N_ROWS; ++k) {
        assert_int_equal(mc_co_emcy_code((uint32_t)rows[k].bit), rows[k].emcy);
        assert_int_equal(mc_co_error_register(rows[k].mask), MC_ERR_REG_GENERIC | rows[k].reg);
    }
    for (uint32_t b = 0u; b < 40u; ++b) {
        if (b >= 32u || (MC_FAULTS_ALL & (1u << b)) == 0u) {
            assert_int_equal(mc_co_emcy_code(b), 0x1000u);
        }
        if (b < 32u && (MC_FAULTS_ALL & (1u << b)) == 0u) {
            assert_int_equal(mc_co_error_register(1u << b), MC_ERR_REG_GENERIC);
        }
    }
    assert_int_equal(mc_co_error_register(0u), 0u);
    uint8_t all = MC_ERR_REG_GENERIC;
    for (size_t k = 0; k < N_ROWS; ++k) {
        all |= rows[k].reg;
    }
    assert_int_equal(mc_co_error_register(MC_FAULTS_ALL), all);
}

/* the class masks the drive uses (startup.c) and the text the parameter table shows */
static void test_class_masks(void **st)
{
    (void)st;
    uint32_t rec = 0u, hold = 0u;
    char names[256] = "";
    for (size_t k = 0; k < N_ROWS; ++k) {
        assert_true(rows[k].recoverable == 0 || rows[k].recoverable == 1);
        assert_true(rows[k].reaction == MC_FAULT_REACT_OFF || rows[k].reaction == MC_FAULT_REACT_HOLD_FW);
        if (rows[k].recoverable) {
            rec |= rows[k].mask;
            strcat(names, " ");
            strcat(names, rows[k].name);
        }
        hold |= rows[k].reaction == MC_FAULT_REACT_HOLD_FW ? rows[k].mask : 0u;
    }
    assert_int_equal(MC_FAULTS_RECOVERABLE, rec);
    assert_int_equal(MC_FAULTS_HOLD_FW, hold);
    assert_string_equal(MC_FAULTS_RECOVERABLE_NAMES, names);
}

/* The bits, names and codes on the bus, in metrics and in stored error history today: rows may
 * be added, these never renumbered or renamed (tools and stored histories decode them). */
static void test_bus_contract_frozen(void **st)
{
    (void)st;
    static const struct { uint32_t mask; int bit; const char *name; uint16_t emcy; } frozen[] = {
        {MC_FAULT_OVERCURRENT, 0, "overcurrent", 0x2310u},
        {MC_FAULT_OVERVOLTAGE, 1, "overvoltage", 0x3210u},
        {MC_FAULT_UNDERVOLTAGE, 2, "undervoltage", 0x3220u},
        {MC_FAULT_OFFSET_CAL, 3, "offset_calibration", 0x5210u},
        {MC_FAULT_CONFIG, 4, "config", 0x6320u},
        {MC_FAULT_INIT_POS, 5, "init_pos", 0x7300u},
        {MC_FAULT_TIMEOUT, 6, "timeout", 0x6100u},
        {MC_FAULT_NUMERIC, 7, "numeric", 0x6100u},
        {MC_FAULT_OVERSPEED, 8, "overspeed", 0x8400u},
        {MC_FAULT_CURRENT_SENSOR, 9, "current_sensor", 0x5210u},
        {MC_FAULT_TRACKING, 10, "tracking", 0x8300u},
        {MC_FAULT_LOSS_OF_LOCK, 11, "loss_of_lock", 0x7300u},
        {MC_FAULT_STALL, 12, "stall", 0x7121u},
        {MC_FAULT_OVERRUN, 13, "isr_overrun", 0x6100u},
        {MC_FAULT_VOLTAGE_MODEL, 14, "voltage_model", 0x7300u},
        {MC_FAULT_TORQUE, 15, "torque_plausibility", 0x8300u},
    };
    for (size_t j = 0; j < sizeof frozen / sizeof frozen[0]; ++j) {
        const row_t *r = NULL;
        for (size_t k = 0; k < N_ROWS; ++k) {
            r = rows[k].mask == frozen[j].mask ? &rows[k] : r;
        }
        assert_non_null(r);
        assert_int_equal(r->bit, frozen[j].bit);
        assert_string_equal(r->name, frozen[j].name);
        assert_int_equal(r->emcy, frozen[j].emcy);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bits_unique_and_in_range),
        cmocka_unit_test(test_names_and_docs),
        cmocka_unit_test(test_emcy_codes_valid),
        cmocka_unit_test(test_device_mapping_follows_table),
        cmocka_unit_test(test_class_masks),
        cmocka_unit_test(test_bus_contract_frozen),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
