/* co-gen: the CANopen object dictionary (mc/co.h) written out as an EDS (CiA 306) and as the
 * object tables of docs/can.md. Everything comes from the firmware: the objects and their types,
 * access, ranges, names and units from the dictionary's description (mc_co_od_at), the default
 * values read from a device initialised like the firmware (the default drive configuration on
 * the host HAL, node 1: COB-IDs are written $NODEID-relative).
 *
 *   co-gen eds FILE     write the EDS
 *   co-gen md           print the object tables (markdown) to stdout
 *   co-gen faults md    print the drive faults' EMCY table (markdown) to stdout
 *   co-gen faults json  print the fault table for the tools (tools/mctools/data/faults.json)
 *
 * The fault tables come from mc/faults.h through the firmware's own mapping (mc_co_emcy_code,
 * mc_co_error_register), so they say what the device sends.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "hal_host/host.h"
#include "mc/bits.h"
#include "mc/co.h"

typedef struct {
    hal_pwm_t pwm;
    hal_adc_t adc;
    hal_qep_t qep;
    hal_can_t can;
    mc_drive_cfg_t cfg;
    mc_drive_t d;
    mc_drive_link_t link;
    mc_scope_t scope;
    float scope_buf[64];
    mc_co_t co;
} rig_t;

static rig_t rig;

static void rig_init(void)
{
    memset(&rig, 0, sizeof rig);
    mc_drive_cfg_default(&rig.cfg);
    hal_host_pwm_init(&rig.pwm, rig.cfg.p.control_ts_s, rig.cfg.p.hw_dead_time_s);
    hal_host_can_init(&rig.can);
    if (!mc_drive_init(&rig.d, &rig.link, &rig.cfg, &rig.adc, &rig.pwm, &rig.qep)) {
        fprintf(stderr, "co-gen: the default configuration was refused\n");
        exit(1);
    }
    mc_scope_init(&rig.scope, rig.scope_buf, 64u, rig.cfg.p.control_ts_s);
    const mc_co_cfg_t c = {.node_id = 1u, .heartbeat_ms = 1000u, .step_s = 1e-3f, .vendor_id = 0u,
                           .product_code = 1u, .revision = 0x00020000u, .serial = 0u};
    if (!mc_co_init(&rig.co, &c, &rig.can, &rig.d, NULL, &rig.scope, MC_PSTORE_EMPTY)) {
        fprintf(stderr, "co-gen: mc_co_init failed\n");
        exit(1);
    }
}

static const char *type_name(uint8_t t)
{
    switch (t) {
    case MC_CO_BOOL: return "BOOLEAN";
    case MC_CO_I8: return "INTEGER8";
    case MC_CO_I16: return "INTEGER16";
    case MC_CO_I32: return "INTEGER32";
    case MC_CO_U8: return "UNSIGNED8";
    case MC_CO_U16: return "UNSIGNED16";
    case MC_CO_U32: return "UNSIGNED32";
    case MC_CO_REAL32: return "REAL32";
    case MC_CO_VSTRING: return "VISIBLE_STRING";
    default: return "DOMAIN";
    }
}

static bool is_signed(uint8_t t)
{
    return t == MC_CO_I8 || t == MC_CO_I16 || t == MC_CO_I32;
}

/* EDS AccessType (CiA 306 §4.6.3): rww / rwr mark the PDO direction of a writable object. */
static const char *access_name(const mc_co_entry_t *e)
{
    switch (e->access) {
    case MC_CO_RO: return "ro";
    case MC_CO_WO: return "wo";
    case MC_CO_CONST: return "const";
    default: return (e->flags & MC_CO_F_RPDO) ? "rww" : (e->flags & MC_CO_F_TPDO) ? "rwr" : "rw";
    }
}

/* The value as text (a number in the EDS's form), false if there is none to give. */
static bool value_text(const mc_co_entry_t *e, char *out, size_t cap)
{
    uint8_t d[MC_CO_SDO_BUF + 1];
    uint32_t len = 0u;
    if (e->type == MC_CO_DOMAIN || mc_co_od_read(&rig.co, e->index, e->sub, d, MC_CO_SDO_BUF, &len) != 0u) {
        return false;
    }
    if (e->type == MC_CO_VSTRING) {
        d[len] = 0u;
        snprintf(out, cap, "%s", (const char *)d);
        return true;
    }
    uint32_t w = 0u;
    for (uint32_t k = 0u; k < len; ++k) {
        w |= (uint32_t)d[k] << (8u * k);
    }
    if (e->type == MC_CO_REAL32) {
        snprintf(out, cap, "%.9g", (double)mc_bits_f32(w));
    } else if (is_signed(e->type)) {
        const uint32_t shift = 32u - 8u * len;
        snprintf(out, cap, "%" PRId32, (int32_t)(w << shift) >> shift);
    } else if ((e->flags & MC_CO_F_NODEID) != 0u) {
        snprintf(out, cap, "$NODEID+0x%" PRIX32, w - rig.co.cfg.node_id);
    } else {
        snprintf(out, cap, "0x%" PRIX32, w);
    }
    return true;
}

static int cmp_entry(const void *a, const void *b)
{
    const mc_co_entry_t *x = a, *y = b;
    const uint32_t kx = ((uint32_t)x->index << 8) | x->sub, ky = ((uint32_t)y->index << 8) | y->sub;
    return kx < ky ? -1 : kx > ky ? 1 : 0;
}

static mc_co_entry_t *entries(uint32_t *n)
{
    *n = mc_co_od_count();
    mc_co_entry_t *e = calloc(*n, sizeof *e);
    for (uint32_t k = 0u; k < *n; ++k) {
        if (!mc_co_od_at(k, &e[k])) {
            fprintf(stderr, "co-gen: entry %" PRIu32 " missing\n", k);
            exit(1);
        }
    }
    qsort(e, *n, sizeof *e, cmp_entry);
    return e;
}

/* The sub-indices of the object starting at e[k]; 0 for a plain variable. */
static uint32_t subs_of(const mc_co_entry_t *e, uint32_t n, uint32_t k)
{
    uint32_t m = 0u;
    while (k + m < n && e[k + m].index == e[k].index) {
        m++;
    }
    return (m == 1u && e[k].sub == 0u && e[k].sname[0] == '\0') ? 0u : m;
}

static void var_section(FILE *f, const mc_co_entry_t *e, bool sub)
{
    char v[64];
    if (sub) {
        fprintf(f, "[%04Xsub%X]\n", e->index, e->sub);
    } else {
        fprintf(f, "[%04X]\n", e->index);
    }
    fprintf(f, "ParameterName=%s\nObjectType=0x7\nDataType=0x%04X\nAccessType=%s\n", sub ? e->sname : e->oname,
            e->type, access_name(e));
    const bool dynamic_ro = e->access == MC_CO_RO && e->kind != MC_CO_K_HOOK && e->kind != MC_CO_K_PARAM;
    if ((e->access != MC_CO_RO || e->index == 0x2FF0u || e->kind == MC_CO_K_PARAM) && !dynamic_ro &&
        value_text(e, v, sizeof v)) {
        fprintf(f, "DefaultValue=%s\n", v);
    }
    const bool ranged = e->access != MC_CO_RO && e->access != MC_CO_CONST && e->type != MC_CO_VSTRING &&
                        e->type != MC_CO_DOMAIN && e->index >= 0x2000u;
    if (e->kind == MC_CO_K_PARAM) {
        const mc_param_info_t *p = &mc_param_table[e->arg];
        if (p->type == MC_PT_F32) {
            fprintf(f, "LowLimit=%.9g\nHighLimit=%.9g\n", (double)p->min, (double)p->max);
        } else {
            fprintf(f, "LowLimit=%" PRId64 "\nHighLimit=%" PRId64 "\n", e->min, e->max);
        }
        static const char *const acc[] = {"INIT", "STANDSTILL", "RUNTIME"};
        fprintf(f, "Access=%s\n", acc[p->access < 3u ? p->access : 2u]);
        if (p->choices != NULL && p->choices[0] != '\0') {
            fprintf(f, "Choices=%s\n", p->choices);
        } else if (p->type == MC_PT_BOOL) {
            fprintf(f, "Choices=false|true\n");
        }
    } else if (ranged && e->type != MC_CO_REAL32) {
        fprintf(f, "LowLimit=%" PRId64 "\nHighLimit=%" PRId64 "\n", e->min, e->max);
    }
    fprintf(f, "PDOMapping=%d\n", (e->flags & (MC_CO_F_RPDO | MC_CO_F_TPDO)) ? 1 : 0);
    if (e->unit[0] != '\0') {
        fprintf(f, "Unit=%s\n", e->unit);
    }
    if (e->doc[0] != '\0') {
        fprintf(f, "Description=%s\n", e->doc);
    }
    fprintf(f, "\n");
}

static void list_section(FILE *f, const char *name, const mc_co_entry_t *e, uint32_t n, uint32_t lo, uint32_t hi)
{
    uint32_t count = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        count += (e[k].index >= lo && e[k].index <= hi && (k == 0u || e[k - 1u].index != e[k].index)) ? 1u : 0u;
    }
    fprintf(f, "[%s]\nSupportedObjects=%" PRIu32 "\n", name, count);
    uint32_t j = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        if (e[k].index >= lo && e[k].index <= hi && (k == 0u || e[k - 1u].index != e[k].index)) {
            fprintf(f, "%" PRIu32 "=0x%04X\n", ++j, e[k].index);
        }
    }
    fprintf(f, "\n");
}

static int write_eds(const char *path)
{
    uint32_t n;
    mc_co_entry_t *e = entries(&n);
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        perror(path);
        return 1;
    }
    fprintf(f, "; Generated by co-gen from the firmware's object dictionary (firmware/comms/co_objects.h,\n"
               "; mc/params_table.h, mc/telem_channels.h). Do not edit: rebuild and run\n"
               "; scripts/gen_docs.py. Parameter defaults are those of the compiled default motor; the\n"
               "; ones with a rule follow the motor data on the device.\n\n");
    fprintf(f, "[FileInfo]\nFileName=drive.eds\nFileVersion=1\nFileRevision=0\nEDSVersion=4.0\n"
               "Description=IPMSM sensorless drive (CiA 402), parameter table hash 0x%08" PRIX32 "\n"
               "CreatedBy=co-gen\n\n",
            mc_params_table_hash());
    fprintf(f, "[DeviceInfo]\nVendorName=open IPMSM drive project\nVendorNumber=0x0\n"
               "ProductName=ipmsm-sensorless-drive\nProductNumber=0x1\nRevisionNumber=0x20000\nOrderCode=\n"
               "BaudRate_10=0\nBaudRate_20=0\nBaudRate_50=0\nBaudRate_125=1\nBaudRate_250=1\nBaudRate_500=1\n"
               "BaudRate_800=0\nBaudRate_1000=1\nSimpleBootUpMaster=0\nSimpleBootUpSlave=1\nGranularity=8\n"
               "DynamicChannelsSupported=0\nGroupMessaging=0\nNrOfRXPDO=%u\nNrOfTXPDO=%u\nLSS_Supported=0\n\n",
            MC_CO_PDO_N, MC_CO_PDO_N);
    fprintf(f, "[DummyUsage]\nDummy0001=0\nDummy0002=0\nDummy0003=0\nDummy0004=0\nDummy0005=0\nDummy0006=0\n"
               "Dummy0007=0\n\n");
    fprintf(f, "[MandatoryObjects]\nSupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n\n");
    /* optional: the communication area without the mandatory three, and the profile area */
    uint32_t count = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        const uint16_t i = e[k].index;
        if ((k == 0u || e[k - 1u].index != i) && i != 0x1000u && i != 0x1001u && i != 0x1018u &&
            (i < 0x2000u || i >= 0x6000u)) {
            count++;
        }
    }
    fprintf(f, "[OptionalObjects]\nSupportedObjects=%" PRIu32 "\n", count);
    uint32_t j = 0u;
    for (uint32_t k = 0u; k < n; ++k) {
        const uint16_t i = e[k].index;
        if ((k == 0u || e[k - 1u].index != i) && i != 0x1000u && i != 0x1001u && i != 0x1018u &&
            (i < 0x2000u || i >= 0x6000u)) {
            fprintf(f, "%" PRIu32 "=0x%04X\n", ++j, i);
        }
    }
    fprintf(f, "\n");
    list_section(f, "ManufacturerObjects", e, n, 0x2000u, 0x5FFFu);
    for (uint32_t k = 0u; k < n;) {
        const uint32_t m = subs_of(e, n, k);
        if (m == 0u) {
            var_section(f, &e[k], false);
            k++;
            continue;
        }
        fprintf(f, "[%04X]\nParameterName=%s\nObjectType=0x9\nSubNumber=%" PRIu32 "\n\n", e[k].index, e[k].oname, m);
        for (uint32_t s = 0u; s < m; ++s) {
            var_section(f, &e[k + s], true);
        }
        k += m;
    }
    fclose(f);
    free(e);
    return 0;
}

static const char *md_access(const mc_co_entry_t *e)
{
    const char *a = access_name(e);
    if (e->kind == MC_CO_K_PARAM) {
        static const char *const acc[] = {"ro (init)", "rw (outputs off)", "rw"};
        return acc[mc_param_table[e->arg].access < 3u ? mc_param_table[e->arg].access : 2u];
    }
    return a;
}

/* A table cell: '|' would end it. */
static void cell(const char *s)
{
    for (; *s != '\0'; ++s) {
        if (*s == '|') {
            fputs("\\|", stdout);
        } else {
            putchar(*s);
        }
    }
}

/* One table row per object and sub-index. */
static int write_md(void)
{
    uint32_t n;
    mc_co_entry_t *e = entries(&n);
    printf("| index | sub | name | type | access | PDO | unit | default | notes |\n");
    printf("|---|---|---|---|---|---|---|---|---|\n");
    for (uint32_t k = 0u; k < n; ++k) {
        const mc_co_entry_t *x = &e[k];
        char v[64] = "";
        if (x->access != MC_CO_RO || x->kind == MC_CO_K_PARAM || x->index == 0x2FF0u) {
            if (!value_text(x, v, sizeof v)) {
                v[0] = '\0';
            }
        }
        const char *name = x->sname[0] != '\0' ? x->sname : x->oname;
        printf("| 0x%04X | %u | %s%s%s | %s | %s | %s | %s | ", x->index, x->sub, x->sname[0] != '\0' ? x->oname : "",
               x->sname[0] != '\0' ? ": " : "", name, type_name(x->type), md_access(x),
               (x->flags & MC_CO_F_RPDO) ? "R" : (x->flags & MC_CO_F_TPDO) ? "T" : "", x->unit);
        cell(v);
        fputs(" | ", stdout);
        cell(x->kind == MC_CO_K_PARAM ? "" : x->doc);
        fputs(" |\n", stdout);
    }
    free(e);
    return 0;
}

/* The meaning of an EMCY code the fault table uses (mc/faults.h MC_EMCY_CODES). */
static const char *emcy_meaning(uint16_t code)
{
#define MC_EMCY_TEXT_(c, text) if (code == (c)) { return text; }
    MC_EMCY_CODES(MC_EMCY_TEXT_)
#undef MC_EMCY_TEXT_
    return "?";
}

static void reg_text(uint8_t reg, char *buf, size_t cap)
{
    static const char *const names[8] = {"generic", "current", "voltage", "temperature", "communication",
                                         "device profile", "reserved", "manufacturer"};
    size_t len = (size_t)snprintf(buf, cap, "0x%02X (", reg);
    const char *sep = "";
    for (unsigned b = 0u; b < 8u && len < cap; ++b) {
        if ((reg & (1u << b)) != 0u) {
            len += (size_t)snprintf(buf + len, cap - len, "%s%s", sep, names[b]);
            sep = ", ";
        }
    }
    if (len < cap) {
        snprintf(buf + len, cap - len, ")");
    }
}

/* docs/can.md's EMCY table: one row per fault, in bit order. */
static int write_faults_md(void)
{
    printf("Generated by `co-gen faults md` from `firmware/control/include/mc/faults.h` through the device's mapping "
           "(`mc_co_emcy_code`, `mc_co_error_register`).\n\n");
    printf("| bit | drive fault | EMCY code | error register 0x1001 | meaning (CiA 301 / CiA 402 tables) |\n");
    printf("|---:|---|---|---|---|\n");
#define MC_FAULT_MD_(NAME, bit, name, emcy, reg, reaction, rec, doc)                                   \
    {                                                                                                 \
        const uint16_t code = mc_co_emcy_code(bit);                                                   \
        char r[80];                                                                                   \
        reg_text(mc_co_error_register(MC_FAULT_##NAME), r, sizeof r);                                 \
        printf("| %d | `%s` | 0x%04X | %s | %s |\n", bit, name, code, r, emcy_meaning(code));          \
    }
    MC_FAULTS(MC_FAULT_MD_)
#undef MC_FAULT_MD_
    return 0;
}

/* The fault table for the tools (mctune names a fault from its EMCY or the fault word). */
static int write_faults_json(void)
{
    printf("{\n  \"generated_by\": \"co-gen faults json from firmware/control/include/mc/faults.h; do not edit, run "
           "scripts/gen_docs.py\",\n  \"faults\": [\n");
    const char *sep = "";
#define MC_FAULT_JSON_(NAME, bit, name, emcy, reg, reaction, rec, doc)                                 \
    printf("%s    {\"bit\": %d, \"name\": \"%s\", \"emcy\": %u, \"error_register\": %u, "                 \
           "\"reaction\": \"%s\", \"recoverable\": %s, \"doc\": \"%s\"}",                                \
           sep, bit, name, (unsigned)mc_co_emcy_code(bit), (unsigned)mc_co_error_register(MC_FAULT_##NAME), \
           MC_FAULT_REACT_##reaction == MC_FAULT_REACT_HOLD_FW ? "hold_fw" : "off", (rec) ? "true" : "false", doc); \
    sep = ",\n";
    MC_FAULTS(MC_FAULT_JSON_)
#undef MC_FAULT_JSON_
    printf("\n  ]\n}\n");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "eds") == 0) {
        rig_init();
        return write_eds(argv[2]);
    }
    if (argc == 2 && strcmp(argv[1], "md") == 0) {
        rig_init();
        return write_md();
    }
    if (argc == 3 && strcmp(argv[1], "faults") == 0 && strcmp(argv[2], "md") == 0) {
        return write_faults_md();
    }
    if (argc == 3 && strcmp(argv[1], "faults") == 0 && strcmp(argv[2], "json") == 0) {
        return write_faults_json();
    }
    fprintf(stderr, "usage: co-gen eds FILE | co-gen md | co-gen faults md|json\n");
    return 2;
}
