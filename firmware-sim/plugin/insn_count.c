/*
 * A QEMU TCG plugin that counts guest instructions executed between two marker functions, and
 * estimates the Cortex-M4 cycles they take (m4_cycles.h: the TRM's cycle table).
 *
 * Arguments: start=<address>,stop=<address> (the entry addresses of the firmware's
 * neurosurf_region_start / neurosurf_region_stop; the Thumb bit is ignored), and optionally
 * profile=1 (see print_profile).
 * Every time the stop marker is reached it prints, through qemu_plugin_outs (enable with
 * `-d plugin`, send to a file with `-D`):
 *
 *     neurosurf-region <index> <instructions> <estimated cycles>
 *
 * Counting is per translation block: when a block executes while a region is open, its
 * instruction count and the sum of its instructions' prices are added, plus M4_REFILL when
 * the block does not start where the previously executed block falls through (the previous
 * block ended in a taken branch). The start marker opens the region at its first instruction
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

#include "m4_cycles.h"

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
const void *qemu_plugin_insn_data(const struct qemu_plugin_insn *insn);
size_t qemu_plugin_insn_size(const struct qemu_plugin_insn *insn);
void qemu_plugin_outs(const char *string);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

static uint64_t start_address, stop_address;
static bool open_region;
static uint64_t count, cycles, regions;

/* One translated block: where it starts and falls through, what it holds and costs. */
struct block {
    uint64_t address;
    uint64_t fall_through; /* the address after its last instruction */
    uint64_t n_insns;
    uint64_t cycles; /* the sum of m4_cycles over its instructions */
    uint64_t executed; /* inside regions */
};
/* The block executed last, in or out of a region. */
static const struct block *previous;

/* profile=1: also attribute the counted instructions to translation blocks, and print the
   heaviest blocks of the whole run at exit (up to PROFILE_LINES of them, enough to cover every
   executed block of an N = 9 leaf's field and gradient) as
   `neurosurf-profile <address> <instructions in the block> <instructions executed>
   <estimated cycles, refills excluded>`. */
#define PROFILE_LINES 400
static bool profile;
#define PROFILE_SLOTS 8192
static struct block *profiled[PROFILE_SLOTS];
static size_t profiled_count;

static void on_block(unsigned int vcpu, void *data) {
    struct block *b = data;
    bool redirected = previous != NULL && previous->fall_through != b->address;
    (void)vcpu;
    previous = b;
    if (!open_region) {
        return;
    }
    b->executed++;
    count += b->n_insns;
    cycles += b->cycles + (redirected ? M4_REFILL : 0);
}

static int heavier(const void *a, const void *b) {
    const struct block *x = *(struct block *const *)a, *y = *(struct block *const *)b;
    uint64_t wx = x->executed * x->n_insns, wy = y->executed * y->n_insns;
    return wx < wy ? 1 : wx > wy ? -1 : 0;
}

static void print_profile(qemu_plugin_id_t id, void *unused) {
    char line[128];
    (void)id;
    (void)unused;
    qsort(profiled, profiled_count, sizeof profiled[0], heavier);
    for (size_t i = 0; i < profiled_count && i < PROFILE_LINES && profiled[i]->executed > 0; i++) {
        const struct block *b = profiled[i];
        snprintf(line, sizeof line,
                 "neurosurf-profile 0x%" PRIx64 " %" PRIu64 " %" PRIu64 " %" PRIu64 "\n", b->address,
                 b->n_insns, b->executed * b->n_insns, b->executed * b->cycles);
        qemu_plugin_outs(line);
    }
}

static void on_start(unsigned int vcpu, void *unused) {
    (void)vcpu;
    (void)unused;
    open_region = true;
    count = 0;
    cycles = 0;
}

static void on_stop(unsigned int vcpu, void *unused) {
    char line[96];
    (void)vcpu;
    (void)unused;
    if (!open_region) {
        return;
    }
    open_region = false;
    snprintf(line, sizeof line, "neurosurf-region %" PRIu64 " %" PRIu64 " %" PRIu64 "\n", regions, count,
             cycles);
    qemu_plugin_outs(line);
    regions++;
}

/* The price of one instruction, read from its bytes (little-endian halfwords). */
static unsigned price(const struct qemu_plugin_insn *insn) {
    const uint8_t *bytes = qemu_plugin_insn_data(insn);
    size_t size = qemu_plugin_insn_size(insn);
    uint16_t hw1 = (uint16_t)(bytes[0] | bytes[1] << 8);
    uint16_t hw2 = size == 4 ? (uint16_t)(bytes[2] | bytes[3] << 8) : 0;
    return m4_cycles(hw1, hw2, size);
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    size_t n = qemu_plugin_tb_n_insns(tb);
    (void)id;
    if (n == 0) {
        return;
    }
    /* Blocks live as long as QEMU may run them: never freed (a run translates a few thousand). */
    struct block *b = calloc(1, sizeof *b);
    if (b == NULL) {
        fprintf(stderr, "insn_count: out of memory\n");
        abort();
    }
    b->n_insns = n;
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t at = qemu_plugin_insn_vaddr(insn) & ~(uint64_t)1;
        if (i == 0) {
            b->address = at;
        }
        b->fall_through = at + qemu_plugin_insn_size(insn);
        b->cycles += price(insn);
        if (at == start_address) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_start, QEMU_PLUGIN_CB_NO_REGS, NULL);
        } else if (at == stop_address) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_stop, QEMU_PLUGIN_CB_NO_REGS, NULL);
        }
    }
    if (profile && profiled_count < PROFILE_SLOTS) {
        profiled[profiled_count++] = b;
    }
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_block, QEMU_PLUGIN_CB_NO_REGS, b);
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
