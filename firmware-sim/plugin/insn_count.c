/*
 * A QEMU TCG plugin that counts guest instructions executed between two marker functions.
 *
 * Arguments: start=<address>,stop=<address> (the entry addresses of the firmware's
 * neurosurf_region_start / neurosurf_region_stop; the Thumb bit is ignored), and optionally
 * profile=1 (see print_profile).
 * Every time the stop marker is reached it prints, through qemu_plugin_outs (enable with
 * `-d plugin`, send to a file with `-D`):
 *
 *     neurosurf-region <index> <instructions>
 *
 * Counting is per translation block: when a block executes while a region is open, its
 * instruction count is added. The start marker opens the region at its first instruction
 * (the rest of its block is not counted), the stop marker's whole block is counted; that
 * constant is measured by the firmware's empty first region and subtracted by the runner.
 * Exact and deterministic: the firmware takes no interrupts.
 *
 * Debian's qemu-system-arm ships no qemu-plugin.h, so the few API functions used are declared
 * here, as in QEMU 7.2's include/qemu/qemu-plugin.h (plugin API version 1).
 */
#include <inttypes.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
typedef struct qemu_info_t qemu_info_t;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb *tb, qemu_plugin_vcpu_udata_cb_t cb,
                                          enum qemu_plugin_cb_flags flags, void *userdata);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn, qemu_plugin_vcpu_udata_cb_t cb,
                                            enum qemu_plugin_cb_flags flags, void *userdata);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void *userdata);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *insn);
void qemu_plugin_outs(const char *string);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

static uint64_t start_address, stop_address;
static bool open_region;
static uint64_t count, regions;

/* profile=1: also attribute the counted instructions to translation blocks, and print the
   heaviest blocks of the whole run at exit (up to PROFILE_LINES of them, enough to cover every
   executed block of an N = 9 leaf's field and gradient) as
   `neurosurf-profile <address> <instructions in the block> <instructions executed>`. */
#define PROFILE_LINES 400
static bool profile;
#define PROFILE_SLOTS 8192
static struct block {
    uint64_t address;
    uint64_t n_insns;
    uint64_t executed;
} blocks[PROFILE_SLOTS];
static size_t block_count;

static void on_block(unsigned int vcpu, void *data) {
    (void)vcpu;
    if (!open_region) {
        return;
    }
    if (profile) {
        struct block *b = data;
        b->executed++;
        count += b->n_insns;
    } else {
        count += (uint64_t)(uintptr_t)data;
    }
}

static int heavier(const void *a, const void *b) {
    const struct block *x = a, *y = b;
    uint64_t wx = x->executed * x->n_insns, wy = y->executed * y->n_insns;
    return wx < wy ? 1 : wx > wy ? -1 : 0;
}

static void print_profile(qemu_plugin_id_t id, void *unused) {
    char line[96];
    (void)id;
    (void)unused;
    qsort(blocks, block_count, sizeof blocks[0], heavier);
    for (size_t i = 0; i < block_count && i < PROFILE_LINES && blocks[i].executed > 0; i++) {
        snprintf(line, sizeof line, "neurosurf-profile 0x%" PRIx64 " %" PRIu64 " %" PRIu64 "\n",
                 blocks[i].address, blocks[i].n_insns, blocks[i].executed * blocks[i].n_insns);
        qemu_plugin_outs(line);
    }
}

static void on_start(unsigned int vcpu, void *unused) {
    (void)vcpu;
    (void)unused;
    open_region = true;
    count = 0;
}

static void on_stop(unsigned int vcpu, void *unused) {
    char line[80];
    (void)vcpu;
    (void)unused;
    if (!open_region) {
        return;
    }
    open_region = false;
    snprintf(line, sizeof line, "neurosurf-region %" PRIu64 " %" PRIu64 "\n", regions, count);
    qemu_plugin_outs(line);
    regions++;
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    size_t n = qemu_plugin_tb_n_insns(tb);
    (void)id;
    void *data = (void *)(uintptr_t)n;
    if (profile && n > 0 && block_count < PROFILE_SLOTS) {
        struct block *b = &blocks[block_count++];
        b->address = qemu_plugin_insn_vaddr(qemu_plugin_tb_get_insn(tb, 0));
        b->n_insns = n;
        data = b;
    }
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_block, QEMU_PLUGIN_CB_NO_REGS, data);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t at = qemu_plugin_insn_vaddr(insn) & ~(uint64_t)1;
        if (at == start_address) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_start, QEMU_PLUGIN_CB_NO_REGS, NULL);
        } else if (at == stop_address) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_stop, QEMU_PLUGIN_CB_NO_REGS, NULL);
        }
    }
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info,
                                                               int argc, char **argv) {
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "start=", 6) == 0) {
            start_address = strtoull(argv[i] + 6, NULL, 0) & ~(uint64_t)1;
        } else if (strncmp(argv[i], "stop=", 5) == 0) {
            stop_address = strtoull(argv[i] + 5, NULL, 0) & ~(uint64_t)1;
        } else if (strcmp(argv[i], "profile=1") == 0) {
            profile = true;
        } else {
            fprintf(stderr, "insn_count: unknown argument %s\n", argv[i]);
            return -1;
        }
    }
    if (start_address == 0 || stop_address == 0) {
        fprintf(stderr, "insn_count: needs start=<address>,stop=<address>\n");
        return -1;
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    if (profile) {
        qemu_plugin_register_atexit_cb(id, print_profile, NULL);
    }
    return 0;
}
