/* The first table version of the store's migration test (store_tables.h): this build's table
 * saves a set with the values of store_tables.h through the power-cut-safe store into the host
 * NVM and writes the NVM's bytes to the file argv[1], for test_store_tables.c (the second
 * version) to read. */
#include <stdio.h>
#include "hal_host/host.h"
#include "mc/param_store.h"
#include "store_tables.h"

static hal_nvm_t nvm;
static mc_drive_cfg_t cfg;

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: store_tables_write FILE\n");
        return 2;
    }
    hal_host_nvm_init(&nvm);
    mc_drive_cfg_default(&cfg);
    for (size_t k = 0; k < STORE_TABLES_N; ++k) {
        const int id = mc_param_find(store_tables_values[k].name);
        if (id < 0 || !mc_param_set(&cfg.p, id, store_tables_values[k].value, NULL)) {
            fprintf(stderr, "store_tables_write: cannot set %s\n", store_tables_values[k].name);
            return 1;
        }
    }
    uint8_t work[256];
    const mc_pstore_status_t st = mc_pstore_save(&nvm, &cfg, work, sizeof work, NULL);
    if (st != MC_PSTORE_OK && st != MC_PSTORE_MAP_DROPPED) {
        fprintf(stderr, "store_tables_write: save: %s\n", mc_pstore_status_name(st));
        return 1;
    }
    FILE *f = fopen(argv[1], "wb");
    if (f == NULL || fwrite(nvm.mem, hal_host_nvm_bytes(&nvm), 1u, f) != 1u || fclose(f) != 0) {
        fprintf(stderr, "store_tables_write: cannot write %s\n", argv[1]);
        return 1;
    }
    printf("store_tables_write: table hash %08x, %u parameters, into %s\n", (unsigned)mc_params_table_hash(),
           (unsigned)MC_PARAM_COUNT, argv[1]);
    return 0;
}
