/* The object dictionary (mc/co.h): the communication objects of CiA 301 §7.5 this device has,
 * and the manufacturer area 0x2000 + id generated from the parameter table at run time. */
#include <string.h>
#include "mc/bits.h"
#include "mc/co.h"

#define DEVICE_NAME "ipmsm-sensorless-drive"

static void le32(uint8_t *d, uint32_t w)
{
    d[0] = (uint8_t)w;
    d[1] = (uint8_t)(w >> 8);
    d[2] = (uint8_t)(w >> 16);
    d[3] = (uint8_t)(w >> 24);
}

static uint32_t rd32(const uint8_t *d)
{
    return (uint32_t)d[0] | ((uint32_t)d[1] << 8) | ((uint32_t)d[2] << 16) | ((uint32_t)d[3] << 24);
}

static uint32_t put_u(uint8_t *data, uint32_t cap, uint32_t *len, uint32_t v, uint32_t n)
{
    if (cap < n) {
        return MC_SDO_ABORT_GENERAL;
    }
    uint8_t b[4];
    le32(b, v);
    memcpy(data, b, n);
    *len = n;
    return 0u;
}

/* A parameter's value on the bus: REAL32 for F32, INTEGER32 for I32, BOOL and ENUM (the
 * choice's position), 4 bytes either way. */
static uint32_t param_read(const mc_co_t *co, int id, uint8_t *data, uint32_t cap, uint32_t *len)
{
    const float v = mc_param_get(mc_drive_params(co->drive), id);
    const uint32_t w = mc_param_table[id].type == MC_PT_F32 ? mc_f32_bits(v) : (uint32_t)(int32_t)v;
    return put_u(data, cap, len, w, 4u);
}

static uint32_t param_write(mc_co_t *co, int id, const uint8_t *data, uint32_t len)
{
    if (len != 4u) {
        return len > 4u ? MC_SDO_ABORT_LENGTH_HIGH : MC_SDO_ABORT_LENGTH_LOW;
    }
    const mc_param_info_t *e = &mc_param_table[id];
    const uint32_t w = rd32(data);
    const float v = e->type == MC_PT_F32 ? mc_bits_f32(w) : (float)(int32_t)w;
    if (e->type != MC_PT_F32 && (int32_t)w != (int32_t)v) {
        return MC_SDO_ABORT_VALUE;   /* not representable exactly */
    }
    if (v > e->max) {
        return MC_SDO_ABORT_VALUE_HIGH;
    }
    if (v < e->min) {
        return MC_SDO_ABORT_VALUE_LOW;
    }
    mc_param_err_t err;
    if (mc_drive_param_write(co->drive, id, v, &err)) {
        return 0u;
    }
    switch (err.kind) {
    case MC_PERR_ACCESS:
    case MC_PERR_BUSY:
        return MC_SDO_ABORT_STATE;
    case MC_PERR_RANGE:
        return err.value > err.max ? MC_SDO_ABORT_VALUE_HIGH : MC_SDO_ABORT_VALUE_LOW;
    case MC_PERR_UNKNOWN:
        return MC_SDO_ABORT_NO_OBJECT;
    default:
        return MC_SDO_ABORT_VALUE;   /* not finite, not integral, a cross-check, the model */
    }
}

uint32_t mc_co_od_read(mc_co_t *co, uint16_t index, uint8_t sub, uint8_t *data, uint32_t cap, uint32_t *len)
{
    if (index >= 0x2000u && index < 0x2000u + (uint32_t)MC_PARAM_COUNT) {
        return sub == 0u ? param_read(co, (int)(index - 0x2000u), data, cap, len) : MC_SDO_ABORT_NO_SUB;
    }
    switch (index) {
    case 0x1000u:
        return sub == 0u ? put_u(data, cap, len, MC_CO_DEVICE_TYPE, 4u) : MC_SDO_ABORT_NO_SUB;
    case 0x1001u:   /* error register (§7.5.2.2) of the latched faults */
        return sub == 0u ? put_u(data, cap, len, mc_co_error_register(mc_drive_faults(co->drive)), 1u)
                         : MC_SDO_ABORT_NO_SUB;
    case 0x1003u:   /* pre-defined error field (§7.5.2.3), newest first */
        if (sub == 0u) {
            return put_u(data, cap, len, co->err_count, 1u);
        }
        return sub <= co->err_count ? put_u(data, cap, len, co->err_hist[sub - 1u], 4u) : MC_SDO_ABORT_NO_SUB;
    case 0x1008u: {
        const uint32_t n = (uint32_t)strlen(DEVICE_NAME);
        if (sub != 0u) {
            return MC_SDO_ABORT_NO_SUB;
        }
        if (cap < n) {
            return MC_SDO_ABORT_GENERAL;
        }
        memcpy(data, DEVICE_NAME, n);
        *len = n;
        return 0u;
    }
    case 0x1017u:
        return sub == 0u ? put_u(data, cap, len, co->heartbeat_ms, 2u) : MC_SDO_ABORT_NO_SUB;
    case 0x1018u: {
        const uint32_t v[5] = {4u, co->cfg.vendor_id, co->cfg.product_code, co->cfg.revision, co->cfg.serial};
        return sub <= 4u ? put_u(data, cap, len, v[sub], sub == 0u ? 1u : 4u) : MC_SDO_ABORT_NO_SUB;
    }
    default:
        return MC_SDO_ABORT_NO_OBJECT;
    }
}

uint32_t mc_co_od_write(mc_co_t *co, uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len)
{
    if (index >= 0x2000u && index < 0x2000u + (uint32_t)MC_PARAM_COUNT) {
        return sub == 0u ? param_write(co, (int)(index - 0x2000u), data, len) : MC_SDO_ABORT_NO_SUB;
    }
    switch (index) {
    case 0x1003u:   /* writing 0 to sub 0 clears the history; anything else is refused */
        if (sub != 0u) {
            return sub <= 8u ? MC_SDO_ABORT_READ_ONLY : MC_SDO_ABORT_NO_SUB;
        }
        if (len != 1u) {
            return len > 1u ? MC_SDO_ABORT_LENGTH_HIGH : MC_SDO_ABORT_LENGTH_LOW;
        }
        if (data[0] != 0u) {
            return MC_SDO_ABORT_VALUE;
        }
        co->err_count = 0u;
        return 0u;
    case 0x1017u:
        if (sub != 0u) {
            return MC_SDO_ABORT_NO_SUB;
        }
        if (len != 2u) {
            return len > 2u ? MC_SDO_ABORT_LENGTH_HIGH : MC_SDO_ABORT_LENGTH_LOW;
        }
        co->heartbeat_ms = (uint16_t)(data[0] | (data[1] << 8));
        return 0u;
    case 0x1000u:
    case 0x1001u:
    case 0x1008u:
    case 0x1018u: {
        uint8_t tmp[MC_CO_SDO_BUF];
        uint32_t n;
        const uint32_t a = mc_co_od_read(co, index, sub, tmp, sizeof tmp, &n);
        return a != 0u ? a : MC_SDO_ABORT_READ_ONLY;
    }
    default:
        return MC_SDO_ABORT_NO_OBJECT;
    }
}
