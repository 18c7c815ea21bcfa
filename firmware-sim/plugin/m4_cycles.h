/*
 * Estimated Cortex-M4 cycles of one Thumb or Thumb-2 instruction, after the Cortex-M4 Technical
 * Reference Manual (ARM DDI 0439B, r0p1): section 3.3.1, "Cortex-M4 instructions" (Table 3-1,
 * the processor's instruction timings), and section 7.2.3, "FPU instruction set" (Table 7-1,
 * the FPU's). Encoding classes as in the ARMv7-M Architecture Reference Manual (ARM DDI 0403E):
 * A5.2 (16-bit Thumb), A5.3 (32-bit Thumb-2), A6.4 and A6.5 (floating point).
 *
 * m4_cycles(hw1, hw2, size) prices an instruction of `size` bytes whose first halfword is hw1
 * and second (32-bit encodings only) hw2, WITHOUT the pipeline refill P of a taken branch: the
 * plugin adds M4_REFILL whenever the next executed translation block does not start where the
 * previous one's last instruction falls through, so a branch (B<c>, CBZ, B, BL, BX, POP {pc},
 * LDR pc, TBB, a write to the PC) costs its base when not taken and base + P when it is.
 *
 * Where the TRM gives a range or a condition, this model chooses:
 *  - loads and stores of one register cost 2 (the TRM lets neighbouring ones pipeline to 1:
 *    not modelled, so sequences of them are priced high);
 *  - SDIV and UDIV cost M4_DIVIDE = 7, the middle of the TRM's 2-12 (early termination
 *    depends on the operands);
 *  - P = M4_REFILL = 2, the middle of the TRM's 1-3 (target alignment, width, speculation);
 *  - IT costs 1 (never folded into the preceding instruction), an instruction an IT block
 *    skips costs what it would cost executed, and barriers and hints cost 1;
 *  - memory is zero-wait-state: no flash wait states, no bus contention, no FPU stalls on
 *    register dependencies (QEMU models no timing at all).
 */
#ifndef M4_CYCLES_H
#define M4_CYCLES_H

#include <stddef.h>
#include <stdint.h>

/* Pipeline refill after a taken branch (TRM: "P", 1 to 3). */
#define M4_REFILL 2
/* SDIV and UDIV (TRM: 2 to 12). */
#define M4_DIVIDE 7

/* How a table row prices its instructions. */
enum m4_price {
    M4_FIXED,     /* `cycles` */
    M4_LIST8,     /* 16-bit LDM/STM: 1 + N, N = registers in bits 7:0 */
    M4_LIST9,     /* 16-bit PUSH/POP: 1 + N, N = registers in bits 7:0 plus bit 8 (LR or PC) */
    M4_LIST16,    /* 32-bit LDM/STM/PUSH/POP: 1 + N, N = registers in the second halfword */
    M4_DUAL,      /* 32-bit load/store dual or exclusive, table branch */
    M4_LONG_MUL,  /* 32-bit long multiply (1) or divide (M4_DIVIDE) */
    M4_VFP_DATA,  /* floating-point data processing, by opc1 (and VSQRT by opc2/opc3) */
    M4_VFP_MEMORY /* VLDR/VSTR (2 single, 3 double) or VLDM/VSTM/VPUSH/VPOP (1 + words) */
};

struct m4_row {
    uint32_t mask, value; /* matched against (hw1 << 16) | hw2; 16-bit encodings: hw2 = 0 */
    enum m4_price price;
    unsigned cycles;
};

/* 16-bit encodings (A5.2), first match wins. Everything not listed is 1 cycle. */
static const struct m4_row m4_thumb16[] = {
    {0xF0000000, 0xC0000000, M4_LIST8, 0},  /* STM, LDM: 1 + N */
    {0xFE000000, 0xB4000000, M4_LIST9, 0},  /* PUSH: 1 + N */
    {0xFE000000, 0xBC000000, M4_LIST9, 0},  /* POP: 1 + N (+ P with the PC) */
    {0xF0000000, 0x90000000, M4_FIXED, 2},  /* LDR, STR SP-relative */
    {0xF0000000, 0x80000000, M4_FIXED, 2},  /* LDRH, STRH immediate */
    {0xE0000000, 0x60000000, M4_FIXED, 2},  /* LDR, STR, LDRB, STRB immediate */
    {0xF0000000, 0x50000000, M4_FIXED, 2},  /* loads and stores, register offset */
    {0xF8000000, 0x48000000, M4_FIXED, 2},  /* LDR literal */
    /* Data processing, MUL, ADD/MOV/CMP high registers, BX, BLX, ADR, ADD SP, CBZ, CBNZ,
       extends, REV, IT, hints, B<c>, B: 1 (+ P when they branch). */
};

/* 32-bit encodings (A5.3), first match wins. Everything not listed is 1 cycle: data
   processing (immediate, shifted or register operands), bit fields, saturation, MUL, MLA, MLS,
   the DSP multiplies, B<c>.W, B.W, BL (+ P when they branch), MSR, MRS, barriers, hints. */
static const struct m4_row m4_thumb32[] = {
    /* Floating point (coprocessor 10 and 11), A6.4 and A6.5 */
    {0xFFE00E00, 0xEC400A00, M4_FIXED, 2},     /* VMOV two core registers <-> two S or one D */
    {0xFF000E10, 0xEE000A10, M4_FIXED, 1},     /* VMOV core <-> S, VMRS, VMSR */
    {0xFF000E10, 0xEE000A00, M4_VFP_DATA, 0},  /* VADD, VMUL, VMLA, VFMA, VDIV, VSQRT, VCVT… */
    {0xFE000E00, 0xEC000A00, M4_VFP_MEMORY, 0}, /* VLDR, VSTR, VLDM, VSTM, VPUSH, VPOP */
    /* Integer */
    {0xFE400000, 0xE8000000, M4_LIST16, 0},    /* LDM, STM, PUSH.W, POP.W: 1 + N (+ P) */
    {0xFE400000, 0xE8400000, M4_DUAL, 0},      /* LDRD, STRD, LDREX, STREX, TBB, TBH */
    {0xFE000000, 0xF8000000, M4_FIXED, 2},     /* LDR, STR (byte, halfword, word) */
    {0xFF800000, 0xFB800000, M4_LONG_MUL, 0},  /* SMULL, UMULL, SMLAL, UMLAL, SDIV, UDIV */
};

static unsigned m4_bits(uint32_t x) {
    unsigned n = 0;
    for (; x != 0; x &= x - 1) {
        n++;
    }
    return n;
}

static unsigned m4_apply(const struct m4_row *row, uint16_t hw1, uint16_t hw2) {
    switch (row->price) {
    case M4_FIXED:
        return row->cycles;
    case M4_LIST8:
        return 1 + m4_bits(hw1 & 0xFF);
    case M4_LIST9:
        return 1 + m4_bits(hw1 & 0x1FF);
    case M4_LIST16:
        return 1 + m4_bits(hw2);
    case M4_DUAL: {
        /* A5.3.8: op1 = hw1[8:7], op2 = hw1[5:4]; op1 = 0x with op2 = 0x is an exclusive
           access or TBB/TBH (2; TBB/TBH + P), anything else LDRD/STRD (TRM: 1 + N, N = 2). */
        unsigned op1 = (hw1 >> 7) & 3, op2 = (hw1 >> 4) & 3;
        return (op1 & 2) == 0 && (op2 & 2) == 0 ? 2 : 3;
    }
    case M4_LONG_MUL:
        /* A5.3.17: op1 = hw1[6:4]; 001 SDIV, 011 UDIV; the rest are 1-cycle long multiplies. */
        return (hw1 & 0x50) == 0x10 ? M4_DIVIDE : 1;
    case M4_VFP_DATA:
        /* A6.4, opc1 = hw1 bits 7, 5, 4 (bit 6 is the register bit D). */
        switch (hw1 & 0xB0) {
        case 0x00: /* VMLA, VMLS */
        case 0x10: /* VNMLA, VNMLS */
        case 0x90: /* VFNMA, VFNMS */
        case 0xA0: /* VFMA, VFMS */
            return 3;
        case 0x80: /* VDIV */
            return 14;
        case 0xB0: /* VSQRT is opc2 = 0001, opc3 = 11; VMOV, VABS, VNEG, VCMP, VCVT are 1 */
            return (hw1 & 0xF) == 1 && (hw2 & 0xC0) == 0xC0 ? 14 : 1;
        default: /* VMUL, VNMUL, VADD, VSUB */
            return 1;
        }
    case M4_VFP_MEMORY:
        /* A6.5: P = 1, W = 0 is VLDR/VSTR (2 for a word, 3 for a double word, hw2 bit 8);
           the other forms move imm8 words: 1 + N. */
        if ((hw1 & 0x120) == 0x100) {
            return hw2 & 0x100 ? 3 : 2;
        }
        return 1 + (hw2 & 0xFF);
    }
    return 1;
}

static unsigned m4_lookup(const struct m4_row *rows, size_t n, uint16_t hw1, uint16_t hw2) {
    uint32_t word = (uint32_t)hw1 << 16 | hw2;
    for (size_t i = 0; i < n; i++) {
        if ((word & rows[i].mask) == rows[i].value) {
            return m4_apply(&rows[i], hw1, hw2);
        }
    }
    return 1;
}

/* The estimated cycles of one instruction, without the refill of a taken branch (see above). */
static unsigned m4_cycles(uint16_t hw1, uint16_t hw2, size_t size) {
    if (size == 4) {
        return m4_lookup(m4_thumb32, sizeof m4_thumb32 / sizeof m4_thumb32[0], hw1, hw2);
    }
    return m4_lookup(m4_thumb16, sizeof m4_thumb16 / sizeof m4_thumb16[0], hw1, 0);
}

#endif
