/* The drive's parameters: one struct generated from the table (mc/params_table.h), its runtime
 * description, and the three steps of the flow (docs/parameters.md):
 *
 *   mc_params_default()  constants, rule parameters marked "auto"
 *   mc_param_set*()      user overrides (an override clears "auto")
 *   mc_params_derive()   rules fill every parameter still "auto" from the motor data
 *   mc_params_validate() every value finite and in its range, then the cross-checks; the first
 *                        violation is reported with the parameter's name, value and range
 *
 * All of this runs outside the ISR (init or the background loop). */
#ifndef MC_PARAMS_H
#define MC_PARAMS_H
#include "mc/types.h"
#include "mc/params_table.h"

typedef enum { MC_PT_F32 = 0, MC_PT_I32, MC_PT_BOOL, MC_PT_ENUM } mc_param_type_t;
typedef enum {
    MC_PG_MOTOR = 0, MC_PG_HW, MC_PG_PROTECTION, MC_PG_CONTROL, MC_PG_ESTIMATOR, MC_PG_INJECTION,
    MC_PG_STARTUP, MC_PG_COUNT
} mc_param_group_t;
typedef enum { MC_PA_INIT = 0, MC_PA_STANDSTILL, MC_PA_RUNTIME } mc_param_access_t;

/* Default rules (params.c documents each one's reason). */
typedef enum {
    MC_RULE_NONE = 0, MC_RULE_I_TRIP, MC_RULE_VDC_MIN, MC_RULE_VDC_MAX, MC_RULE_I_MAX, MC_RULE_CC_BW,
    MC_RULE_I_SLEW, MC_RULE_SPEED_BW, MC_RULE_SPEED_KP, MC_RULE_SPEED_KI, MC_RULE_TORQUE_MAX,
    MC_RULE_I_SMALL, MC_RULE_ENC_FC, MC_RULE_INJ_F, MC_RULE_INJ_I, MC_RULE_INJ_V1, MC_RULE_N1,
    MC_RULE_PLL_BW, MC_RULE_PLL_FC, MC_RULE_K2, MC_RULE_SC_DEC, MC_RULE_OVERSPEED, MC_RULE_I_SUM, MC_RULE_TRACK, MC_RULE_RESID, MC_RULE_LOCK_FLOOR, MC_RULE_STALL, MC_RULE_STEP1_M, MC_RULE_V_POL, MC_RULE_STEP3_TOL, MC_RULE_T_STEP12, MC_RULE_CATCH_I, MC_RULE_CATCH_MIN, MC_RULE_POL_BIAS, MC_RULE_OFFSET_CAL, MC_RULE_L_ADAPT, MC_RULE_IF_I, MC_RULE_IF_ACCEL, MC_RULE_IF_W_H,
    MC_RULE_COUNT
} mc_param_rule_t;

#define MC_PCTYPE_F32  float
#define MC_PCTYPE_I32  int32_t
#define MC_PCTYPE_BOOL int32_t
#define MC_PCTYPE_ENUM int32_t

/* Parameter ids: MC_PARAM_<member>; the index is stable (CANopen 0x2000 + id, stored block). */
typedef enum {
#define MC_X(g, k, type, unit, lo, hi, def, rule, group, access, choices, doc) MC_PARAM_##g##_##k,
    MC_PARAMS(MC_X)
#undef MC_X
    MC_PARAM_COUNT
} mc_param_id_t;

#define MC_PARAM_MASK_WORDS ((MC_PARAM_COUNT + 31) / 32)

/* The named choices of every ENUM parameter: MC_CHOICE_<member>_<choice> is its stored value
 * (p->estimator_model == MC_CHOICE_estimator_model_fluxmap), MC_CHOICE_<member>_COUNT how many there are
 * (0 for the other types). */
#define MC_CH_ENUM(m, c) MC_CHOICE_##m##_##c,
#define MC_X(g, k, type, unit, lo, hi, def, rule, group, access, choices, doc) \
    enum { choices(MC_CH_ENUM) MC_CHOICE_##g##_##k##_COUNT };
MC_PARAMS(MC_X)
#undef MC_X

typedef struct mc_params {
#define MC_X(g, k, type, unit, lo, hi, def, rule, group, access, choices, doc) MC_PCTYPE_##type g##_##k;
    MC_PARAMS(MC_X)
#undef MC_X
    uint32_t auto_mask[MC_PARAM_MASK_WORDS];   /* bit set: derive this parameter by its rule */
} mc_params_t;

typedef struct {
    const char *name;        /* "group.key", stable: scenario key, tuning name, docs        */
    const char *unit;
    const char *choices;     /* ENUM: "a|b|c", the stored value is the position; else ""    */
    const char *doc;         /* one line for the docs and tools ("" in a target image)      */
    uint16_t offset;         /* of the member in mc_params_t                                */
    uint8_t type;            /* mc_param_type_t   */
    uint8_t group;           /* mc_param_group_t  */
    uint8_t access;          /* mc_param_access_t */
    uint8_t rule;            /* mc_param_rule_t   */
    float min, max, def;
} mc_param_info_t;

extern const mc_param_info_t mc_param_table[MC_PARAM_COUNT];

/* Why a configuration was refused: the parameter (and for a cross-check the other one), the
 * values, the allowed range and a short reason. */
typedef enum {
    MC_PERR_NONE = 0,
    MC_PERR_NOT_FINITE,      /* NaN or infinite                                            */
    MC_PERR_RANGE,           /* outside [min, max] of the table                            */
    MC_PERR_NOT_INTEGER,     /* I32 / BOOL / ENUM given a fraction                         */
    MC_PERR_CROSS,           /* violates a relation with param2 (see text)                 */
    MC_PERR_MODEL,           /* the estimator model or flux map (not a table entry)        */
    MC_PERR_UNKNOWN,         /* no parameter of that name / id                             */
    MC_PERR_ACCESS,          /* not writable in this state (INIT: never after init;
                                STANDSTILL: only while the outputs are off)                */
    MC_PERR_BUSY             /* the previous change is not taken by the ISR yet: retry    */
} mc_param_err_kind_t;

typedef struct mc_param_err {
    mc_param_err_kind_t kind;
    int param, param2;       /* ids, -1 if none                                            */
    float value, value2;
    float min, max;          /* the allowed range of param (for CROSS: derived from param2) */
    const char *text;        /* static text, e.g. "must be below hw.i_span_a / 1.1"       */
} mc_param_err_t;

/* Fill err (may be NULL) with kind, parameter id (its table range as min/max), value and a static
 * text; returns false, so that a check can `return mc_param_fail(...)`. */
bool mc_param_fail(mc_param_err_t *err, mc_param_err_kind_t kind, int id, float value, const char *text);
/* Name of a group (for docs and tools). */
const char *mc_param_group_name(mc_param_group_t g);
/* Id of "group.key", or -1. */
int mc_param_find(const char *name);

void mc_params_default(mc_params_t *p);
bool mc_param_is_auto(const mc_params_t *p, int id);
void mc_param_set_auto(mc_params_t *p, int id, bool on);
/* Value as float (I32/BOOL/ENUM converted); NaN for a bad id. */
float mc_param_get(const mc_params_t *p, int id);
/* Set a value and clear "auto". Integer types need an integral finite value within int32
 * (else false, err filled, nothing changed); range checks are mc_params_validate's. */
bool mc_param_set(mc_params_t *p, int id, float value, mc_param_err_t *err);
/* ENUM by its choice text ("sine"); false with err if not one of the choices. */
bool mc_param_set_choice(mc_params_t *p, int id, const char *choice, mc_param_err_t *err);
/* Text of the current choice of an ENUM (a pointer into a static buffer-free table is not
 * possible in C without allocation: the choice is written into buf, at most n bytes). */
void mc_param_choice_text(const mc_params_t *p, int id, char *buf, unsigned n);

/* The table's identity for the stored parameter block and the CANopen object dictionary (the
 * hook the CAN issue fills): FNV-1a over every entry's index, name, type and unit. A stored
 * block whose hash differs was written by another table: it falls back to the defaults. The
 * object of an entry is 0x2000 + its id (sub-index 0), its data type the entry's type. */
uint32_t mc_params_table_hash(void);

/* Fill every "auto" parameter from its rule (may read any other parameter; runs until stable). */
void mc_params_derive(mc_params_t *p);
/* Every entry finite and in range, integers integral, then the cross-checks. */
bool mc_params_validate(const mc_params_t *p, mc_param_err_t *err);

#endif
