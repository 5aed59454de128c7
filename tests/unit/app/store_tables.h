/* The store's migration test across two table versions (app_store_tables): the values the first
 * version (this build's table, store_tables_write.c) stores, which the second version (the table
 * params_variant.py writes, test_store_tables.c) reads back by name. */
#ifndef TEST_STORE_TABLES_H
#define TEST_STORE_TABLES_H

typedef struct {
    const char *name;
    float value;
} store_tables_value_t;

/* kept: moved by the added row (current_bw_hz), swapped (iter_max, lock_action), a BOOL, an I32;
 * k1 = 0.75 is beyond the second version's narrowed range; lock_jump_deg is removed there */
static const store_tables_value_t store_tables_values[] = {
    {"control.current_bw_hz", 80.0f},  {"estimator.iter_max", 6.0f}, {"protection.lock_action", 1.0f},
    {"control.decouple", 0.0f},        {"hw.encoder_lines", 4096.0f}, {"estimator.k1", 0.75f},
    {"protection.lock_jump_deg", 45.0f},
};
#define STORE_TABLES_N (sizeof store_tables_values / sizeof store_tables_values[0])

#endif
