//! The Q16.16 kernels (see the crate docs), each exactly the core's portable code for its
//! shape:
//!
//! - the forward layers: each row's products summed exactly in 64 bits, rounded once and
//!   clamped for the activation table, then the table interpolation
//!   (`Scalar::activation_from_acc`);
//! - the transposes `Wᵀ·g`, rounded to Q16.16 at the end of each column (what the portable loop
//!   followed by `Scalar::from_acc` gives), the 9×9 and 1×9 ones followed by the chain rule δ·a′
//!   on the column sums (`Scalar::times_slope`'s fast path, `smmulr`);
//! - the chain rule alone through nine neurons, and a leaf's input normalization.
//!
//! Everything is unrolled; the branches go to out-of-line code (a saturated column, a
//! saturated pre-activation, a neuron outside the chain rule's fast range) and straight back.
//! The blocks that need r6, r7 or r11 save and restore them themselves (`push` / `pop`, keeping
//! the stack 8-byte aligned): Rust refuses r6 and the frame pointer (r7 in Thumb code, r11 in
//! ARM code) as operands or clobbers, and the inputs held in registers, the accumulators and the
//! pointers need them. Nothing inside reads memory through r7 or r11 as a frame pointer. While
//! such a block runs, r7 holds data, so a debugger's backtrace taken inside a kernel (which
//! follows the frame pointer) is wrong; it is right again after the block. r9 is used as an
//! ordinary register: targets that reserve it (the RWPI relocation model) do not build this
//! crate.
//!
//! The macros that build the assembly text are `#[rustfmt::skip]`, so that each source line is
//! one line of assembly (`"ldr r4, [r0, #(4*", $i, ")]\n",`) rather than one fragment.
#![allow(unsafe_code)]

use core::arch::asm;
use core::mem::MaybeUninit;

use fixed::types::I16F16;

/// Row `$j` of a column pair: W[`$j`][`$c`] and W[`$j`][`$c` + 1] by one `ldrd` (row stride
/// `$stride` bytes, W at r12) into r9/r10, times g (in `$g`) into the accumulators r6:r5 and
/// r8:r7; `$op` is `smull` for the first row, else `smlal`.
#[rustfmt::skip]
macro_rules! pair_row {
    ($op:literal, $c:literal, $j:literal, $g:literal, $stride:literal) => {
        concat!(
            "ldrd r9, r10, [r12, #(4*", $c, " + ", $stride, "*", $j, ")]\n",
            $op, " r5, r6, r9, ", $g, "\n",
            $op, " r7, r8, r10, ", $g, "\n",
        )
    };
}

/// Row `$j` of a single column: W[`$j`][`$c`] by `ldr` into r9 (row stride `$stride` bytes, W
/// at r12), times g (in `$g`) into r6:r5.
#[rustfmt::skip]
macro_rules! single_row {
    ($op:literal, $c:literal, $j:literal, $g:literal, $stride:literal) => {
        concat!(
            "ldr r9, [r12, #(4*", $c, " + ", $stride, "*", $j, ")]\n",
            $op, " r5, r6, r9, ", $g, "\n",
        )
    };
}

/// Σⱼ W[j][`$c`]·gⱼ over nine rows (of `$stride` bytes, W at r12) into r6:r5, by `$row!`
/// ([`pair_row!`] also sums column `$c` + 1 into r8:r7): g₀…g₄ and then g₅…g₈ (at r11) in
/// r0–r4, since nine values of g and two 64-bit accumulators do not fit the registers
/// together. Uses r9 and r10.
#[rustfmt::skip]
macro_rules! column_sums {
    ($row:ident, $c:literal, $stride:literal) => {
        concat!(
            "ldm r11, {{r0-r4}}\n",
            $row!("smull", $c, "0", "r0", $stride), $row!("smlal", $c, "1", "r1", $stride), $row!("smlal", $c, "2", "r2", $stride), $row!("smlal", $c, "3", "r3", $stride), $row!("smlal", $c, "4", "r4", $stride), "add r9, r11, #20\n",
            "ldm r9, {{r0-r3}}\n",
            $row!("smlal", $c, "5", "r0", $stride), $row!("smlal", $c, "6", "r1", $stride), $row!("smlal", $c, "7", "r2", $stride), $row!("smlal", $c, "8", "r3", $stride),
        )
    };
}

/// `$lo` ← the rounded sum `$hi`:`$lo` (2¹⁵ already added) shifted to Q16.16, and the flags
/// "equal" exactly when that fits 32 bits: when bits 15… of the high word all equal the
/// result's sign bit. `$scratch` is scratch.
#[rustfmt::skip]
macro_rules! shift_and_check {
    ($lo:literal, $hi:literal, $scratch:literal) => {
        concat!(
            "lsr ", $lo, ", ", $lo, ", #16\n",
            "orr ", $lo, ", ", $lo, ", ", $hi, ", lsl #16\n",
            "asr ", $scratch, ", ", $hi, ", #15\n",
            "cmp ", $scratch, ", ", $lo, ", asr #31\n",
        )
    };
}

/// `$lo` ← i32::MAX, or i32::MIN when the sum (high word `$hi`) is negative: the saturation of
/// a sum that does not fit.
#[rustfmt::skip]
macro_rules! saturated_word {
    ($lo:literal, $hi:literal) => {
        concat!(
            "mvn ", $lo, ", #0x80000000\n",
            "eor ", $lo, ", ", $lo, ", ", $hi, ", asr #31\n",
        )
    };
}

/// Rounds the sum `$hi`:`$lo` to Q16.16 like `Scalar::from_acc` — ((`$hi`:`$lo`) + 2¹⁵) >> 16
/// when that fits 32 bits, else the end of the range on `$hi`'s side (label 1`$c`, out of
/// line: [`saturate!`], back at 2`$c`) — and stores it at lr + 4·`$c`. Uses r9.
#[rustfmt::skip]
macro_rules! round_and_store {
    ($c:literal, $lo:literal, $hi:literal) => {
        concat!(
            "adds ", $lo, ", ", $lo, ", #32768\n",
            "adc ", $hi, ", ", $hi, ", #0\n",
            shift_and_check!($lo, $hi, "r9"),
            "bne 1", $c, "f\n",
            "2", $c, ":\n",
            "str ", $lo, ", [lr, #(4*", $c, ")]\n",
        )
    };
}

/// The out-of-line saturation of column `$c` (see [`round_and_store!`]).
macro_rules! saturate {
    ($c:literal, $lo:literal, $hi:literal) => {
        concat!("1", $c, ":\n", saturated_word!($lo, $hi), "b 2", $c, "b\n",)
    };
}

/// `Wᵀ·g` for a 9×3 `W` (back through a leaf's first layer) in Q16.16, rounded: output i is
/// `from_acc(0 + W₀ᵢg₀ + … + W₈ᵢg₈)`, the products exact in 64 bits. Columns 0 and 1 as a pair
/// (one `ldrd` of two weights per row), then column 2.
#[inline(always)]
pub fn q16_transposed_9x3(w: &[[I16F16; 3]; 9], g: &[I16F16; 9]) -> [I16F16; 3] {
    let mut out = MaybeUninit::<[I16F16; 3]>::uninit();
    // SAFETY: reads the 27 words behind `w` and the 9 behind `g`, writes the 3 words of `out`
    // (lengths fixed by the array types; `I16F16` is a transparent `i32`); saves and restores
    // r6, r7, r11 and lr on the stack (16 bytes, keeping its 8-byte alignment) and declares
    // every other register it changes.
    unsafe {
        asm!(
            "push {{r6, r7, r11, lr}}",
            "mov r11, r5",
            "mov lr, r4",
            column_sums!(pair_row, "0", "12"),
            round_and_store!("0", "r5", "r6"),
            round_and_store!("1", "r7", "r8"),
            column_sums!(single_row, "2", "12"),
            round_and_store!("2", "r5", "r6"),
            "b 3f",
            saturate!("0", "r5", "r6"),
            saturate!("1", "r7", "r8"),
            saturate!("2", "r5", "r6"),
            "3:",
            "pop {{r6, r7, r11, lr}}",
            out("r0") _,
            out("r1") _,
            out("r2") _,
            out("r3") _,
            inout("r4") out.as_mut_ptr() => _,
            inout("r5") g.as_ptr() => _,
            out("r8") _,
            out("r9") _,
            out("r10") _,
            in("r12") w.as_ptr(),
        );
        out.assume_init()
    }
}

/// The chain rule through neuron `$i` (see [`q16_times_slope_9`]): δ at r0 + 4·`$i`, a at
/// r1 + 4·`$i`, the constants in r2 (square·2¹⁶) and r3 (offset·2¹⁴); a value outside the fast
/// range branches to label 1`$i` (out of line), which marks it in r12 and comes back to 2`$i`.
#[rustfmt::skip]
macro_rules! slope9 {
    ($i:literal) => {
        concat!(
            "ldr r4, [r0, #(4*", $i, ")]\n",
            "ldr r5, [r1, #(4*", $i, ")]\n",
            // −2 ≤ a < 2 and |δ| < 2²⁹ bits at once: (a + 2¹⁷) as u32 < 2¹⁸ and
            // (δ + 2²⁹) as u32 < 2³⁰ exactly when their OR, the second shifted right by 12,
            // is below 2¹⁸. (a = 2 exactly goes out of line: the fallback gives the same
            // bits, conservatively.)
            "add lr, r5, #0x20000\n",
            "add r8, r4, #0x20000000\n",
            "orr lr, lr, r8, lsr #12\n",
            "cmp lr, #0x40000\n",
            "bhs 1", $i, "f\n",
            // a′·2¹⁴ = offset·2¹⁴ − round(square·2¹⁶ · round((a·2⁸)²/2³²)/2³²)·2¹⁴
            "lsl r5, r5, #8\n",
            "smmulr r5, r5, r5\n",
            "smmulr r5, r5, r2\n",
            "sub r5, r3, r5, lsl #14\n",
            // round((δ·2²)·(a′·2¹⁴)/2³²)
            "lsl r4, r4, #2\n",
            "smmulr r4, r4, r5\n",
            "str r4, [r0, #(4*", $i, ")]\n",
            "2", $i, ":\n",
        )
    };
}

/// The out-of-line branch of [`slope9!`] (mask in r12) and [`single_slope!`] (mask in r5) for
/// neuron `$i`: sets bit `$i` of the mask register `$mask`, the value unchanged.
#[rustfmt::skip]
macro_rules! slope_slow {
    ($mask:literal, $i:literal) => {
        concat!(
            "1", $i, ":\n",
            "orr ", $mask, ", ", $mask, ", #(1 << ", $i, ")\n",
            "b 2", $i, "b\n",
        )
    };
}

/// δᵢ ← round(δᵢ·a′ᵢ/2¹⁶) for the nine neurons of a layer, the slope a′ᵢ computed from the
/// neuron's output aᵢ as `offset − round(square·round(aᵢ²/2¹⁶)/2¹⁶)` (all in Q16.16 bits,
/// each round(x·y/2ⁿ) the rounded high word of a `smmulr`) — exactly the core's fast path of
/// `Scalar::times_slope` for Q16.16, which holds for −2 ≤ aᵢ ≤ 2 and −2¹³ ≤ δᵢ < 2¹³; the
/// kernel takes it for −2 ≤ aᵢ < 2 and the same δᵢ. A neuron outside that range keeps its δ, and its bit
/// (1 << i) is set in the returned mask: the caller finishes it on the portable (saturating)
/// path, which gives the fast path's bits wherever that holds. Fourteen instructions per
/// neuron.
///
/// `offset` and `square` are the core's constants (a′ = offset − square·a²); with them below
/// 2¹⁷ and 2¹⁵ in bits, offset·2¹⁴ and square·2¹⁶ fit an `i32` (the caller's are 1.144 and
/// 0.389).
#[inline(always)]
pub fn q16_times_slope_9(
    delta: &mut [I16F16; 9],
    a: &[I16F16; 9],
    offset: i32,
    square: i32,
) -> u32 {
    let slow: u32;
    // SAFETY: reads the 9 words behind `a` and reads and writes the 9 words behind `delta`
    // (lengths fixed by the array types; `I16F16` is a transparent `i32`); uses no stack and
    // declares every register it changes.
    unsafe {
        asm!(
            slope9!("0"),
            slope9!("1"),
            slope9!("2"),
            slope9!("3"),
            slope9!("4"),
            slope9!("5"),
            slope9!("6"),
            slope9!("7"),
            slope9!("8"),
            "b 3f",
            slope_slow!("r12", "0"),
            slope_slow!("r12", "1"),
            slope_slow!("r12", "2"),
            slope_slow!("r12", "3"),
            slope_slow!("r12", "4"),
            slope_slow!("r12", "5"),
            slope_slow!("r12", "6"),
            slope_slow!("r12", "7"),
            slope_slow!("r12", "8"),
            "3:",
            in("r0") delta.as_mut_ptr(),
            in("r1") a.as_ptr(),
            in("r2") square.wrapping_shl(16),
            in("r3") offset.wrapping_shl(14),
            out("r4") _,
            out("r5") _,
            out("r8") _,
            inout("r12") 0u32 => slow,
            out("lr") _,
            options(nostack),
        );
    }
    slow
}

/// Row `$j` of a forward layer over nine inputs (x in r0–r8, the row's bias·2¹⁶ + 2¹⁵ as a
/// Q32.32 pair at sp + 8·`$j`, the weights read in order from r12, two at a time): H = bias +
/// Σᵢ W[j][i]·xᵢ in r10:r9 (Q32.32, in order, the rounding's half included), clamped by
/// [`clamp_pre_activation!`] and stored at sp + 4·`$j` (a pair row j has read already).
#[rustfmt::skip]
macro_rules! layer_row9 {
    ($j:literal) => {
        concat!(
            "ldrd r9, r10, [sp, #(8*", $j, ")]\n",
            "ldm r12!, {{r11, lr}}\n",
            "smlal r9, r10, r11, r0\n",
            "smlal r9, r10, lr, r1\n",
            "ldm r12!, {{r11, lr}}\n",
            "smlal r9, r10, r11, r2\n",
            "smlal r9, r10, lr, r3\n",
            "ldm r12!, {{r11, lr}}\n",
            "smlal r9, r10, r11, r4\n",
            "smlal r9, r10, lr, r5\n",
            "ldm r12!, {{r11, lr}}\n",
            "smlal r9, r10, r11, r6\n",
            "smlal r9, r10, lr, r7\n",
            "ldr lr, [r12], #4\n",
            "smlal r9, r10, lr, r8\n",
            clamp_pre_activation!($j, "lr"),
            "str r9, [sp, #(4*", $j, ")]\n",
        )
    };
}

/// Row `$j` of a forward layer over three inputs, activation included (x in r0–r2, the
/// row's bias at r8 + 4·`$j`, its three weights read from r12 by one `ldm`): H = bias + 2⁻¹⁷ +
/// Σᵢ W[j][i]·xᵢ in r10:r9 (the rounding's half added with the bias, from lr = 2¹⁵), clamped
/// by [`clamp_pre_activation!`] into r9, then a(H) by [`table_activation!`] (2⁹ in r7), stored at
/// r11 + 4·`$j`. With three inputs there are registers to spare, so the row needs no second
/// pass.
#[rustfmt::skip]
macro_rules! layer_row3 {
    ($j:literal) => {
        concat!(
            "ldr r10, [r8, #(4*", $j, ")]\n",
            // bias·2¹⁶ + 2¹⁵: the rounding's half folded into the bias's low word.
            "orr r9, lr, r10, lsl #16\n",
            "asr r10, r10, #16\n",
            "ldm r12!, {{r4, r5, r6}}\n",
            "smlal r9, r10, r4, r0\n",
            "smlal r9, r10, r5, r1\n",
            "smlal r9, r10, r6, r2\n",
            clamp_pre_activation!($j, "r4"),
            table_activation!("r9", "r4", "r5", "r6", "r7", "r10"),
            "str r5, [r11, #(4*", $j, ")]\n",
        )
    };
}

/// Row `$j`'s accumulator r10:r9, already holding the rounding's 2¹⁵, as H for the activation
/// into r9: H in Q16.16 bits when the rounded high word lies in [−10, 10) (then H fits 32
/// bits), else ±10 (label 1`$j`, out of line: [`saturated_pre_activation!`], back at label
/// 2`$j`), where the table has saturated: both give `activation_from_acc`'s value. `$scratch`
/// is scratch.
#[rustfmt::skip]
macro_rules! clamp_pre_activation {
    ($j:literal, $scratch:literal) => {
        concat!(
            "add ", $scratch, ", r10, #10\n",
            "cmp ", $scratch, ", #20\n",
            "bhs 1", $j, "f\n",
            "lsr r9, r9, #16\n",
            "orr r9, r9, r10, lsl #16\n",
            "2", $j, ":\n",
        )
    };
}

/// The out-of-line branch of [`clamp_pre_activation!`] for row `$j`: ±10 in Q16.16 bits, the sign
/// of the high word r10.
#[rustfmt::skip]
macro_rules! saturated_pre_activation {
    ($j:literal) => {
        concat!(
            "1", $j, ":\n",
            "mov r9, #0xa0000\n",
            "cmp r10, #0\n",
            "it lt\n",
            "rsblt r9, r9, #0\n",
            "b 2", $j, "b\n",
        )
    };
}

/// a(H) for the H in `$h` (within [−10, 10]) into `$lo`, by the table's segments over both
/// signs (r3 points at the one for H = 0; see `ActivationTable`): the segment below H, index
/// H >> 10, interpolated by the fraction H & 1023 and rounded with 2⁹ (in `$half`) less one
/// when H < 0 — the core's symmetric interpolation, bit for bit (the core's `SEGMENTS` docs
/// show why). `$index`, `$rise` and `$round` are scratch.
#[rustfmt::skip]
macro_rules! table_activation {
    ($h:literal, $index:literal, $lo:literal, $rise:literal, $half:literal, $round:literal) => {
        concat!(
            "asr ", $index, ", ", $h, ", #10\n",
            "add ", $index, ", r3, ", $index, ", lsl #3\n",
            "ldrd ", $lo, ", ", $rise, ", [", $index, "]\n",
            "ubfx ", $index, ", ", $h, ", #0, #10\n",
            "add ", $round, ", ", $half, ", ", $h, ", asr #31\n",
            "mla ", $rise, ", ", $rise, ", ", $index, ", ", $round, "\n",
            "add ", $lo, ", ", $lo, ", ", $rise, ", asr #10\n",
        )
    };
}

/// Output `$j` = a(H) for the H at sp + 4·`$j` ([`table_activation!`], 2⁹ in r6), stored at
/// r2 + 4·`$j`.
#[rustfmt::skip]
macro_rules! activation {
    ($j:literal) => {
        concat!(
            "ldr r0, [sp, #(4*", $j, ")]\n",
            table_activation!("r0", "r1", "r4", "r5", "r6", "r9"),
            "str r4, [r2, #(4*", $j, ")]\n",
        )
    };
}

/// Bias `$j` (in `$b`) as the Q32.32 pair (bias·2¹⁶ + 2¹⁵, bias >> 16) at sp + 8·`$j`, with
/// 2¹⁵ in lr: the accumulator a row starts from. Uses r11.
#[rustfmt::skip]
macro_rules! bias_pair {
    ($b:literal, $j:literal) => {
        concat!(
            "orr r11, lr, ", $b, ", lsl #16\n",
            "asr ", $b, ", ", $b, ", #16\n",
            "strd r11, ", $b, ", [sp, #(8*", $j, ")]\n",
        )
    };
}

/// The activation table's layout that [`q16_layer_9x9`] and [`q16_layer_9x3`] read: at index
/// 640 + k for k = −640 … 640, a(H) in Q16.16 bits at H = k/64 and its rise to the entry at
/// (k + 1)/64 (rise 0 at k = 640, where a has saturated).
pub type ActivationTable = [[i32; 2]; 1281];

/// The index of H = 0 in an [`ActivationTable`].
const TABLE_ZERO: usize = 640;

/// A forward layer of nine outputs on nine inputs in Q16.16: output j is the core's
/// `activation_from_acc(to_acc(bⱼ) + Σᵢ W[j][i]·xᵢ)` with `table` the core's activation
/// table — the accumulation exact in 64 bits, rounded once and clamped to ±10, then the table's
/// segment below H interpolated ([`table_activation!`]). The rows go first, each into its
/// pre-activation on the stack (the nine inputs hold r0–r8), then the nine activations.
#[inline(always)]
pub fn q16_layer_9x9(
    w: &[[I16F16; 9]; 9],
    b: &[I16F16; 9],
    x: &[I16F16; 9],
    table: &ActivationTable,
) -> [I16F16; 9] {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    // SAFETY: reads the 81 words behind `w`, the 9 behind `b` and `x` and the table at
    // indices 640 + (H >> 10) for H clamped to [−10, 10] (0 … 1 280); writes the 9 words of `out`
    // (lengths fixed by the array types; `I16F16` is a transparent `i32`); uses 96 bytes of
    // stack (saving r2, r3, r6, r7, r11 and lr there, below them the nine biases as Q32.32
    // pairs, overwritten by the nine pre-activations), keeps it 8-byte aligned, and declares
    // every other register it changes.
    unsafe {
        asm!(
            // r2 (out) and r3 (table) are saved for the second pass; 24 + 72 bytes keep sp
            // 8-byte aligned.
            "push {{r2, r3, r6, r7, r11, lr}}",
            "sub sp, sp, #72",
            // Each bias as the Q32.32 pair (bias·2¹⁶ + 2¹⁵, bias >> 16) at sp + 8j: the row's
            // accumulator starts with one `ldrd`, its rounding's half included.
            "mov lr, #0x8000",
            "ldm r1, {{r2-r10}}",
            bias_pair!("r2", "0"),
            bias_pair!("r3", "1"),
            bias_pair!("r4", "2"),
            bias_pair!("r5", "3"),
            bias_pair!("r6", "4"),
            bias_pair!("r7", "5"),
            bias_pair!("r8", "6"),
            bias_pair!("r9", "7"),
            bias_pair!("r10", "8"),
            "ldm r0, {{r0-r8}}",
            layer_row9!("0"),
            layer_row9!("1"),
            layer_row9!("2"),
            layer_row9!("3"),
            layer_row9!("4"),
            layer_row9!("5"),
            layer_row9!("6"),
            layer_row9!("7"),
            layer_row9!("8"),
            "ldr r2, [sp, #72]",
            "ldr r3, [sp, #76]",
            "mov r6, #512",
            activation!("0"),
            activation!("1"),
            activation!("2"),
            activation!("3"),
            activation!("4"),
            activation!("5"),
            activation!("6"),
            activation!("7"),
            activation!("8"),
            "b 3f",
            saturated_pre_activation!("0"),
            saturated_pre_activation!("1"),
            saturated_pre_activation!("2"),
            saturated_pre_activation!("3"),
            saturated_pre_activation!("4"),
            saturated_pre_activation!("5"),
            saturated_pre_activation!("6"),
            saturated_pre_activation!("7"),
            saturated_pre_activation!("8"),
            "3:",
            "add sp, sp, #72",
            "pop {{r2, r3, r6, r7, r11, lr}}",
            inout("r0") x.as_ptr() => _,
            inout("r1") b.as_ptr() => _,
            inout("r2") out.as_mut_ptr() => _,
            inout("r3") table.as_ptr().wrapping_add(TABLE_ZERO) => _,
            out("r4") _,
            out("r5") _,
            out("r8") _,
            out("r9") _,
            out("r10") _,
            inout("r12") w.as_ptr() => _,
            out("lr") _,
        );
        out.assume_init()
    }
}

/// A forward layer of nine outputs on three inputs (a leaf's first layer), as
/// [`q16_layer_9x9`].
#[inline(always)]
pub fn q16_layer_9x3(
    w: &[[I16F16; 3]; 9],
    b: &[I16F16; 9],
    x: &[I16F16; 3],
    table: &ActivationTable,
) -> [I16F16; 9] {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    // SAFETY: reads the 27 words behind `w`, the 9 behind `b`, the 3 behind `x` and the
    // table at indices 640 + (H >> 10) for H clamped to [−10, 10] (0 … 1 280); writes the 9 words of
    // `out` (lengths fixed by the array types; `I16F16` is a transparent `i32`); pushes r6,
    // r7, r11 and lr (16 bytes, keeping sp 8-byte aligned) and restores them, and declares
    // every other register it changes.
    unsafe {
        asm!(
            "push {{r6, r7, r11, lr}}",
            "mov r11, r2",
            "mov r7, #512",
            "mov lr, #0x8000",
            "ldm r0, {{r0-r2}}",
            layer_row3!("0"),
            layer_row3!("1"),
            layer_row3!("2"),
            layer_row3!("3"),
            layer_row3!("4"),
            layer_row3!("5"),
            layer_row3!("6"),
            layer_row3!("7"),
            layer_row3!("8"),
            "b 3f",
            saturated_pre_activation!("0"),
            saturated_pre_activation!("1"),
            saturated_pre_activation!("2"),
            saturated_pre_activation!("3"),
            saturated_pre_activation!("4"),
            saturated_pre_activation!("5"),
            saturated_pre_activation!("6"),
            saturated_pre_activation!("7"),
            saturated_pre_activation!("8"),
            "3:",
            "pop {{r6, r7, r11, lr}}",
            inout("r0") x.as_ptr() => _,
            out("r1") _,
            inout("r2") out.as_mut_ptr() => _,
            in("r3") table.as_ptr().wrapping_add(TABLE_ZERO),
            out("r4") _,
            out("r5") _,
            inout("r8") b.as_ptr() => _,
            out("r9") _,
            out("r10") _,
            inout("r12") w.as_ptr() => _,
            out("lr") _,
        );
        out.assume_init()
    }
}

/// The output neuron: a(b + Σᵢ wᵢ·xᵢ) for one row of nine weights in Q16.16 — the core's
/// `activation_from_acc(to_acc(b) + Σᵢ wᵢ·xᵢ)`, as [`q16_layer_9x9`] for one row. With one row
/// the inputs need not stay in registers: once a product has used its input's register,
/// that register takes a later weight, so the nine weights come in three `ldm`.
#[inline(always)]
pub fn q16_layer_1x9(
    w: &[I16F16; 9],
    b: I16F16,
    x: &[I16F16; 9],
    table: &ActivationTable,
) -> I16F16 {
    let a: i32;
    // SAFETY: reads the 9 words behind `w` and `x` and the table at index 640 + (H >> 10) for
    // H clamped to [−10, 10] (0 … 1 280); pushes the table pointer, r6, r7 and r11 (16 bytes,
    // keeping sp 8-byte aligned) and restores them, and declares every other register it
    // changes.
    unsafe {
        asm!(
            "push {{r3, r6, r7, r11}}",
            // bias·2¹⁶ + 2¹⁵: the rounding's half folded into the bias's low word.
            "mov r9, #0x8000",
            "orr r9, r9, r10, lsl #16",
            "asr r10, r10, #16",
            "ldm r0, {{r0-r8}}",
            "ldm r12!, {{r11, lr}}",
            "smlal r9, r10, r11, r0",
            "smlal r9, r10, lr, r1",
            "ldm r12!, {{r0, r1, r11, lr}}",
            "smlal r9, r10, r0, r2",
            "smlal r9, r10, r1, r3",
            "smlal r9, r10, r11, r4",
            "smlal r9, r10, lr, r5",
            "ldm r12, {{r0-r2}}",
            "smlal r9, r10, r0, r6",
            "smlal r9, r10, r1, r7",
            "smlal r9, r10, r2, r8",
            clamp_pre_activation!("0", "lr"),
            "ldr r3, [sp]",
            "mov r7, #512",
            table_activation!("r9", "r4", "r5", "r6", "r7", "lr"),
            "b 3f",
            saturated_pre_activation!("0"),
            "3:",
            "pop {{r3, r6, r7, r11}}",
            inout("r0") x.as_ptr() => _,
            out("r1") _,
            out("r2") _,
            in("r3") table.as_ptr().wrapping_add(TABLE_ZERO),
            out("r4") _,
            out("r5") a,
            out("r8") _,
            out("r9") _,
            inout("r10") b.to_bits() => _,
            inout("r12") w.as_ptr() => _,
            out("lr") _,
        );
    }
    I16F16::from_bits(a)
}

/// The chain rule's tail for column `$c` of a fused transpose, its rounded accumulator
/// `$lo`/`$hi` = Σⱼ W[j][`$c`]·gⱼ + 2¹⁵ (Q32.32, high word `$hi`): with a = `a[$c]` (r2 points
/// at a, r0 = square·2¹⁶, r1 = offset·2¹⁴), t = the sum rounded to Q16.16 and, when
/// −2 ≤ a < 2 and −2¹³ ≤ t < 2¹³ (so t needs no saturation), δ = round(t·a′/2¹⁶) with
/// a′ = offset − round(square·round(a²/2¹⁶)/2¹⁶), as [`slope9!`]; stores δ at lr + 4·`$c`.
/// Outside that range label 1`$c` (out of line, [`slope_tail_slow!`]) stores t instead and
/// marks the column. Uses r3, r4 and r9.
#[rustfmt::skip]
macro_rules! slope_tail {
    ($c:literal, $lo:literal, $hi:literal) => {
        concat!(
            "ldr r3, [r2, #(4*", $c, ")]\n",
            // −2 ≤ a < 2 and −2¹³ ≤ high word < 2¹³ (t in [−2²⁹, 2²⁹) bits) at once:
            // (a + 2¹⁷) as u32 < 2¹⁸ and (high + 2¹³) as u32 < 2¹⁴ exactly when the first
            // shifted right by 4, ORed with the second, is below 2¹⁴.
            "add r4, r3, #0x20000\n",
            "add r9, ", $hi, ", #0x2000\n",
            "orr r4, r9, r4, lsr #4\n",
            "cmp r4, #0x4000\n",
            "bhs 1", $c, "f\n",
            // t·2² = (sum >> 16) << 2, in range by the test above.
            "bfc ", $lo, ", #0, #16\n",
            "lsr ", $lo, ", ", $lo, ", #14\n",
            "orr ", $lo, ", ", $lo, ", ", $hi, ", lsl #18\n",
            // a′·2¹⁴, then round((t·2²)·(a′·2¹⁴)/2³²), as slope9!.
            "lsl r3, r3, #8\n",
            "smmulr r3, r3, r3\n",
            "smmulr r3, r3, r0\n",
            "sub r3, r1, r3, lsl #14\n",
            "smmulr ", $lo, ", ", $lo, ", r3\n",
            "2", $c, ":\n",
            "str ", $lo, ", [lr, #(4*", $c, ")]\n",
        )
    };
}

/// The out-of-line branch of [`slope_tail!`] for column `$c`: t = the rounded sum saturated to
/// Q16.16 (as `Scalar::from_acc`) into `$lo`, bit `$c` set in the mask at sp + 12; back to
/// 2`$c`.
#[rustfmt::skip]
macro_rules! slope_tail_slow {
    ($c:literal, $lo:literal, $hi:literal) => {
        concat!(
            "1", $c, ":\n",
            shift_and_check!($lo, $hi, "r3"),
            "beq 4", $c, "f\n",
            saturated_word!($lo, $hi),
            "4", $c, ":\n",
            "ldr r3, [sp, #12]\n",
            "orr r3, r3, #(1 << ", $c, ")\n",
            "str r3, [sp, #12]\n",
            "b 2", $c, "b\n",
        )
    };
}

/// Columns `$c` and `$c1` = `$c` + 1 of a fused 9×9 transpose ([`column_sums!`] by
/// [`pair_row!`]), then [`slope_tail!`] on each column with the constants and the pointer to a
/// (sp + 0…8) in r0–r2.
#[rustfmt::skip]
macro_rules! slope_pair {
    ($c:literal, $c1:literal) => {
        concat!(
            column_sums!(pair_row, $c, "36"),
            "ldm sp, {{r0-r2}}\n",
            "adds r5, r5, #0x8000\n",
            "adc r6, r6, #0\n",
            slope_tail!($c, "r5", "r6"),
            "adds r7, r7, #0x8000\n",
            "adc r8, r8, #0\n",
            slope_tail!($c1, "r7", "r8"),
        )
    };
}

/// δᵢ = `times_slope(from_acc(Σⱼ W[j][i]·gⱼ), aᵢ)` for the nine columns of a 9×9 `W` in Q16.16:
/// the transpose, rounded, followed by [`q16_times_slope_9`] in one pass, with the same bits.
///
/// Each column's sum is exact in 64 bits; when −2 ≤ aᵢ < 2 and its rounded value t lies in
/// [−2¹³, 2¹³) (where no saturation happens), δᵢ is the chain rule's fast path, as
/// `q16_times_slope_9` with `offset` and `square` (a′ = offset − square·a², in Q16.16 bits,
/// below 2¹⁷ and 2¹⁵). Otherwise output i is t, saturated like `from_acc`, and bit i of the
/// returned mask is set: the caller finishes it on the portable path, which gives the fast
/// path's bits wherever that holds.
///
/// The weights come in column pairs, two per `ldrd` from the same row, with g₀…g₄ and then
/// g₅…g₈ in registers (the nine values and two 64-bit accumulators do not fit together): about
/// 1.7 instructions per product against the two of one `ldr` per weight, and the chain rule
/// runs on the sum still in registers.
#[inline(always)]
pub fn q16_transposed_slope_9x9(
    w: &[[I16F16; 9]; 9],
    g: &[I16F16; 9],
    a: &[I16F16; 9],
    offset: i32,
    square: i32,
) -> ([I16F16; 9], u32) {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    let slow: u32;
    // SAFETY: reads the 81 words behind `w` and the 9 behind `g` and `a`, writes the 9 words
    // of `out` (lengths fixed by the array types; `I16F16` is a transparent `i32`); pushes 32
    // bytes (the constants, the pointer to `a`, the mask, and r6, r7, r11 and lr, which it
    // restores), keeping sp 8-byte aligned, and declares every other register it changes.
    unsafe {
        asm!(
            "push {{r0-r3, r6, r7, r11, lr}}",
            "mov r11, r5",
            "mov lr, r4",
            slope_pair!("0", "1"),
            slope_pair!("2", "3"),
            slope_pair!("4", "5"),
            slope_pair!("6", "7"),
            column_sums!(single_row, "8", "36"),
            "ldm sp, {{r0-r2}}",
            "adds r5, r5, #0x8000",
            "adc r6, r6, #0",
            slope_tail!("8", "r5", "r6"),
            "b 3f",
            slope_tail_slow!("0", "r5", "r6"),
            slope_tail_slow!("1", "r7", "r8"),
            slope_tail_slow!("2", "r5", "r6"),
            slope_tail_slow!("3", "r7", "r8"),
            slope_tail_slow!("4", "r5", "r6"),
            slope_tail_slow!("5", "r7", "r8"),
            slope_tail_slow!("6", "r5", "r6"),
            slope_tail_slow!("7", "r7", "r8"),
            slope_tail_slow!("8", "r5", "r6"),
            "3:",
            "ldr r0, [sp, #12]",
            "add sp, sp, #16",
            "pop {{r6, r7, r11, lr}}",
            inout("r0") square.wrapping_shl(16) => slow,
            inout("r1") offset.wrapping_shl(14) => _,
            inout("r2") a.as_ptr() => _,
            inout("r3") 0u32 => _,
            inout("r4") out.as_mut_ptr() => _,
            inout("r5") g.as_ptr() => _,
            out("r8") _,
            out("r9") _,
            out("r10") _,
            in("r12") w.as_ptr(),
            out("lr") _,
        );
        (out.assume_init(), slow)
    }
}

/// Output `$i` of the fused one-row transpose: t = round(wᵢ·g/2¹⁶) as the rounded high word
/// of (wᵢ·2⁴)·(g·2¹²) (g·2¹² in r0, w at r12), then with a = `a[$i]` (at r1; r3 = square·2¹⁶, r4 = offset·2¹⁴) the
/// chain rule's fast path when −2 ≤ a < 2 (t is small enough by the weight bound), else t
/// and bit `$i` of r5 (label 1`$i`, out of line); stored at r2 + 4·`$i`.
#[rustfmt::skip]
macro_rules! single_slope {
    ($i:literal) => {
        concat!(
            "ldr r9, [r12, #(4*", $i, ")]\n",
            "lsl r9, r9, #4\n",
            "smmulr r9, r9, r0\n",
            "ldr r10, [r1, #(4*", $i, ")]\n",
            "add lr, r10, #0x20000\n",
            "cmp lr, #0x40000\n",
            "bhs 1", $i, "f\n",
            "lsl r9, r9, #2\n",
            "lsl r10, r10, #8\n",
            "smmulr r10, r10, r10\n",
            "smmulr r10, r10, r3\n",
            "sub r10, r4, r10, lsl #14\n",
            "smmulr r9, r9, r10\n",
            "2", $i, ":\n",
            "str r9, [r2, #(4*", $i, ")]\n",
        )
    };
}

/// δᵢ = `times_slope(from_acc(wᵢ·g), aᵢ)` for one row of nine weights and one g in Q16.16:
/// the one-row transpose followed by [`q16_times_slope_9`] in one pass, with the same bits,
/// for −2 ≤ g < 2 and weights within the core's bound |wᵢ| ≤ 1024 (2²⁶ in bits; the model
/// loader rejects larger ones).
///
/// Each t = round(wᵢ·g/2¹⁶) is one `smmulr`: with |wᵢ| ≤ 2²⁶ and −2¹⁷ ≤ g < 2¹⁷ in bits,
/// (wᵢ·2⁴)·(g·2¹²) fits the multiplier's operands, its rounded high word is
/// (wᵢ·g + 2¹⁵) >> 16 exactly, and it cannot saturate (|wᵢ·g| ≤ 2⁴³); |t| ≤ 2¹¹, inside the
/// chain rule's fast range. Larger weights give an unspecified value (no undefined
/// behaviour). `None` for any other g (the core's g, the output's slope, is at most 1.144):
/// the caller then takes the portable path. A neuron with aᵢ outside [−2, 2) keeps t and its bit is set in the mask, as
/// [`q16_transposed_slope_9x9`].
#[inline(always)]
pub fn q16_transposed_slope_1x9(
    w: &[I16F16; 9],
    g: I16F16,
    a: &[I16F16; 9],
    offset: i32,
    square: i32,
) -> Option<([I16F16; 9], u32)> {
    let g = g.to_bits();
    // −2¹⁷ ≤ g < 2¹⁷ in bits: (g + 2¹⁷) as u32 < 2¹⁸.
    if (g.wrapping_add(0x2_0000) as u32) >= 0x4_0000 {
        return None;
    }
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    let slow: u32;
    // SAFETY: reads the 9 words behind `w` and `a`, writes the 9 words of `out` (lengths fixed
    // by the array types); uses no stack and declares every register it changes.
    unsafe {
        asm!(
            single_slope!("0"),
            single_slope!("1"),
            single_slope!("2"),
            single_slope!("3"),
            single_slope!("4"),
            single_slope!("5"),
            single_slope!("6"),
            single_slope!("7"),
            single_slope!("8"),
            "b 3f",
            slope_slow!("r5", "0"),
            slope_slow!("r5", "1"),
            slope_slow!("r5", "2"),
            slope_slow!("r5", "3"),
            slope_slow!("r5", "4"),
            slope_slow!("r5", "5"),
            slope_slow!("r5", "6"),
            slope_slow!("r5", "7"),
            slope_slow!("r5", "8"),
            "3:",
            in("r0") g << 12,
            in("r1") a.as_ptr(),
            in("r2") out.as_mut_ptr(),
            in("r3") square.wrapping_shl(16),
            in("r4") offset.wrapping_shl(14),
            inout("r5") 0u32 => slow,
            out("r9") _,
            out("r10") _,
            in("r12") w.as_ptr(),
            out("lr") _,
            options(nostack),
        );
        Some((out.assume_init(), slow))
    }
}
