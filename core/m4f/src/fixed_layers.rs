//! The Q16.16 kernels (see the crate docs), each exactly the core's portable code for its
//! shape:
//!
//! - the transposes `Wᵀ·g`, column by column with the nine (or one) values of g held in general
//!   registers, one `ldr` of a weight and one `smull` / `smlal` per product, and the core's
//!   rounding to Q16.16 (add 2¹⁵, shift by 16, saturate) at the end of each column — what the
//!   portable loop followed by `Scalar::from_acc` gives;
//! - the chain rule δ·a′ through nine neurons (`Scalar::times_slope`'s fast path, `smmulr`);
//! - the two hidden forward layers: the inputs in registers, the weights read two (or three) at
//!   a time by `ldm`, each row rounded once and clamped for the activation table, then the
//!   table interpolation (`Scalar::activation_from_acc`).
//!
//! Everything is unrolled; the branches go to out-of-line code (a saturated column, a
//! saturated pre-activation, a neuron outside the chain rule's fast range) and straight back.
//! The 9-row blocks save and restore r6, r7 and r11 themselves (`push` / `pop`, with lr to
//! keep the stack 8-byte aligned): Rust refuses r6 and the frame pointer (r7 in Thumb code, r11
//! in ARM code) as operands or clobbers, and the nine values of g (or x) and a pointer or a
//! weight need them. Nothing inside reads memory through r7 or r11 as a frame pointer. While a
//! block runs, r7 holds a value of g or x, so a debugger's backtrace taken inside a kernel
//! (which follows the frame pointer) is wrong; it is right again after the block. r9 is used as an ordinary register: targets that reserve
//! it (the RWPI relocation model) do not build this crate.
#![allow(unsafe_code)]

use core::arch::asm;
use core::mem::MaybeUninit;

use fixed::types::I16F16;

/// One column of a transposed product: output `$i` = Σⱼ W[j][`$i`]·gⱼ over the rows j = 0…8
/// (row stride `$stride` bytes), g in r0–r8, the weights at r12, rounded to Q16.16 in r9 and
/// stored at r11 + 4·`$i`. Accumulator r10:r9 (high:low), weight and scratch lr.
macro_rules! column9 {
    ($i:literal, $stride:literal) => {
        concat!(
            "ldr lr, [r12, #(4*",
            $i,
            ")]\n",
            "smull r9, r10, lr, r0\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 1*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r1\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 2*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r2\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 3*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r3\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 4*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r4\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 5*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r5\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 6*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r6\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 7*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r7\n",
            "ldr lr, [r12, #(4*",
            $i,
            " + 8*",
            $stride,
            ")]\n",
            "smlal r9, r10, lr, r8\n",
            round_and_store!($i),
        )
    };
}

/// Rounds the accumulator r10:r9 to Q16.16 like `Scalar::from_acc`: r9 ← ((r10:r9) + 2¹⁵) >> 16
/// when that fits 32 bits, else the end of the range on r10's side (label 1`$i` does that
/// out of line, then comes back to 2`$i`); stores it at r11 + 4·`$i`.
macro_rules! round_and_store {
    ($i:literal) => {
        concat!(
            "adds r9, r9, #32768\n",
            "adc r10, r10, #0\n",
            "lsr r9, r9, #16\n",
            "orr r9, r9, r10, lsl #16\n",
            // Exact when bits 15… of the high word all equal the result's sign bit.
            "asr lr, r10, #15\n",
            "cmp lr, r9, asr #31\n",
            "bne 1",
            $i,
            "f\n",
            "2",
            $i,
            ":\n",
            "str r9, [r11, #(4*",
            $i,
            ")]\n",
        )
    };
}

/// The out-of-line saturation of column `$i`: i32::MAX, or i32::MIN when the sum is negative.
macro_rules! saturate {
    ($i:literal) => {
        concat!(
            "1",
            $i,
            ":\n",
            "mvn r9, #0x80000000\n",
            "eor r9, r9, r10, asr #31\n",
            "b 2",
            $i,
            "b\n",
        )
    };
}

/// The whole transposed product over nine rows of `$stride` bytes, one `column9!` per listed
/// output column, their saturations out of line after the last: g at `$g` (loaded into r0–r8),
/// the weights at `$w`, the outputs written at `$out` (moved to r11 once it is saved).
macro_rules! transposed_rows9 {
    ($w:expr, $g:expr, $out:expr, $stride:literal, $($i:literal),+) => {
        asm!(
            "push {{r6, r7, r11, lr}}",
            "mov r11, r1",
            "ldm r0, {{r0-r8}}",
            $(column9!($i, $stride),)+
            "b 3f",
            $(saturate!($i),)+
            "3:",
            "pop {{r6, r7, r11, lr}}",
            inout("r0") $g => _,
            inout("r1") $out => _,
            out("r2") _,
            out("r3") _,
            out("r4") _,
            out("r5") _,
            out("r8") _,
            out("r9") _,
            out("r10") _,
            in("r12") $w,
            out("lr") _,
        )
    };
}

/// `Wᵀ·g` for a 9×9 `W` in Q16.16, rounded: output i is
/// `from_acc(0 + W₀ᵢg₀ + … + W₈ᵢg₈)`, the products exact in 64 bits.
#[inline(always)]
pub fn q16_transposed_9x9(w: &[[I16F16; 9]; 9], g: &[I16F16; 9]) -> [I16F16; 9] {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    // SAFETY: reads the 81 words behind `w` and the 9 behind `g`, writes the 9 words of `out`
    // (lengths fixed by the array types; `I16F16` is a transparent `i32`); saves and restores
    // r6, r7, r11 and lr on the stack (16 bytes, keeping its 8-byte alignment) and declares
    // every other register it changes.
    unsafe {
        transposed_rows9!(
            w.as_ptr(),
            g.as_ptr(),
            out.as_mut_ptr(),
            "36",
            "0",
            "1",
            "2",
            "3",
            "4",
            "5",
            "6",
            "7",
            "8"
        );
        out.assume_init()
    }
}

/// `Wᵀ·g` for a 9×3 `W` (back through a leaf's first layer) in Q16.16, rounded: output
/// i is `from_acc(0 + W₀ᵢg₀ + … + W₈ᵢg₈)`.
#[inline(always)]
pub fn q16_transposed_9x3(w: &[[I16F16; 3]; 9], g: &[I16F16; 9]) -> [I16F16; 3] {
    let mut out = MaybeUninit::<[I16F16; 3]>::uninit();
    // SAFETY: as `q16_transposed_9x9`, over the 27 words behind `w` and the 3 of `out`.
    unsafe {
        transposed_rows9!(
            w.as_ptr(),
            g.as_ptr(),
            out.as_mut_ptr(),
            "12",
            "0",
            "1",
            "2"
        );
        out.assume_init()
    }
}

/// One product of the one-row transpose: output `$i` = `from_acc(0 + wᵢ·g)`, g in r0 (the
/// output pointer in r11, as for the other kernels).
macro_rules! single9 {
    ($i:literal) => {
        concat!(
            "ldr lr, [r12, #(4*",
            $i,
            ")]\n",
            "smull r9, r10, lr, r0\n",
            round_and_store!($i),
        )
    };
}

/// One product of the one-row transpose for a small g: output `$i` = round(wᵢ·g/2¹⁶) as the
/// rounded high word of (wᵢ·2⁴)·(g·2¹²), g·2¹² in r0.
macro_rules! single9_small {
    ($i:literal) => {
        concat!(
            "ldr lr, [r12, #(4*",
            $i,
            ")]\n",
            "lsl lr, lr, #4\n",
            "smmulr r9, lr, r0\n",
            "str r9, [r11, #(4*",
            $i,
            ")]\n",
        )
    };
}

/// The one-row transpose: for |g| < 2 (2¹⁷ in bits) one `single9_small!` per listed output,
/// else one `single9!` each with the saturations out of line: g in r0, the weights at `$w`,
/// the outputs written at `$out`.
macro_rules! transposed_row1 {
    ($w:expr, $g:expr, $out:expr, $($i:literal),+) => {
        asm!(
            "push {{r11, lr}}",
            "mov r11, r1",
            // |g| < 2¹⁷: (g + 2¹⁷) as u32 < 2¹⁸.
            "add r9, r0, #0x20000",
            "cmp r9, #0x40000",
            "bhs 4f",
            "lsl r0, r0, #12",
            $(single9_small!($i),)+
            "b 3f",
            "4:",
            $(single9!($i),)+
            "b 3f",
            $(saturate!($i),)+
            "3:",
            "pop {{r11, lr}}",
            inout("r0") $g => _,
            in("r1") $out,
            out("r9") _,
            out("r10") _,
            in("r12") $w,
            out("lr") _,
        )
    };
}

/// `wᵀ·g` for one row of nine weights and one g in Q16.16, rounded: output i is
/// `from_acc(0 + wᵢ·g)`, for weights within the core's parameter bound |wᵢ| ≤ 1024 (2²⁶ in
/// bits; the model loader rejects larger ones). Larger weights give an unspecified value (no
/// undefined behaviour) when −2 ≤ g < 2.
///
/// For −2 ≤ g < 2 (the caller's g is a slope a′, between −3·10⁻⁵ and 1.144) each output is
/// one `smmulr`: with |wᵢ| ≤ 2²⁶ and −2¹⁷ ≤ g < 2¹⁷ in bits, (wᵢ·2⁴)·(g·2¹²) fits the
/// multiplier's operands, the rounded high word is (wᵢ·g + 2¹⁵) >> 16 exactly, and it cannot
/// saturate (|wᵢ·g| ≤ 2⁴³). Other g take the 64-bit product with the full rounding and
/// saturation; the core never passes one, so no test reaches that branch (it is the previous
/// kernel's code, which the simulator tests held to the host's bits).
#[inline(always)]
pub fn q16_transposed_1x9(w: &[I16F16; 9], g: I16F16) -> [I16F16; 9] {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    // SAFETY: reads the 9 words behind `w`, writes the 9 words of `out` on either path
    // (lengths fixed by the array types), saves and restores r11 and lr (8 bytes) and declares
    // every other register it changes.
    unsafe {
        transposed_row1!(
            w.as_ptr(),
            g.to_bits(),
            out.as_mut_ptr(),
            "0",
            "1",
            "2",
            "3",
            "4",
            "5",
            "6",
            "7",
            "8"
        );
        out.assume_init()
    }
}

/// The chain rule through neuron `$i` (see [`q16_times_slope_9`]): δ at r0 + 4·`$i`, a at
/// r1 + 4·`$i`, the constants in r2 (square·2¹⁶) and r3 (offset·2¹⁴); a value outside the fast
/// range branches to label 1`$i` (out of line), which marks it in r12 and comes back to 2`$i`.
macro_rules! slope9 {
    ($i:literal) => {
        concat!(
            "ldr r4, [r0, #(4*",
            $i,
            ")]\n",
            "ldr r5, [r1, #(4*",
            $i,
            ")]\n",
            // −2 ≤ a < 2 and |δ| < 2²⁹ bits at once: (a + 2¹⁷) as u32 < 2¹⁸ and
            // (δ + 2²⁹) as u32 < 2³⁰ exactly when their OR, the second shifted right by 12,
            // is below 2¹⁸. (a = 2 exactly goes out of line: the fallback gives the same
            // bits, conservatively.)
            "add lr, r5, #0x20000\n",
            "add r8, r4, #0x20000000\n",
            "orr lr, lr, r8, lsr #12\n",
            "cmp lr, #0x40000\n",
            "bhs 1",
            $i,
            "f\n",
            // a′·2¹⁴ = offset·2¹⁴ − round(square·2¹⁶ · round((a·2⁸)²/2³²)/2³²)·2¹⁴
            "lsl r5, r5, #8\n",
            "smmulr r5, r5, r5\n",
            "smmulr r5, r5, r2\n",
            "sub r5, r3, r5, lsl #14\n",
            // round((δ·2²)·(a′·2¹⁴)/2³²)
            "lsl r4, r4, #2\n",
            "smmulr r4, r4, r5\n",
            "str r4, [r0, #(4*",
            $i,
            ")]\n",
            "2",
            $i,
            ":\n",
        )
    };
}

/// The out-of-line branch of [`slope9!`] (mask in r12) and [`single_slope!`] (mask in r5) for
/// neuron `$i`: sets bit `$i` of the mask register `$mask`, the value unchanged.
macro_rules! slope_slow {
    ($mask:literal, $i:literal) => {
        concat!(
            "1",
            $i,
            ":\n",
            "orr ",
            $mask,
            ", ",
            $mask,
            ", #(1 << ",
            $i,
            ")\n",
            "b 2",
            $i,
            "b\n",
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

/// Row `$j` of a forward layer over nine inputs (x in r0–r8, the row's bias at sp + 4·`$j`,
/// the weights read in order from r12, two at a time): H = bias + Σᵢ W[j][i]·xᵢ in r10:r9
/// (Q32.32, in order), then [`pre_activation!`].
macro_rules! layer_row9 {
    ($j:literal) => {
        concat!(
            "ldr r10, [sp, #(4*",
            $j,
            ")]\n",
            "lsl r9, r10, #16\n",
            "asr r10, r10, #16\n",
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
            pre_activation!($j),
        )
    };
}

/// Row `$j` of a forward layer over three inputs, activation included (x in r0–r2, the
/// row's bias at r8 + 4·`$j`, its three weights read from r12 by one `ldm`): H = bias +
/// Σᵢ W[j][i]·xᵢ in r10:r9, rounded and clamped as [`pre_activation!`] into r9 (label 1`$j`
/// is [`saturated_pre_activation!`]), then a(H) by [`table_activation!`] (2⁹ in r7), stored at
/// r11 + 4·`$j`. With three inputs there are registers to spare, so the row needs no second
/// pass.
macro_rules! layer_row3 {
    ($j:literal) => {
        concat!(
            "ldr r10, [r8, #(4*",
            $j,
            ")]\n",
            "lsl r9, r10, #16\n",
            "asr r10, r10, #16\n",
            "ldm r12!, {{r4, r5, r6}}\n",
            "smlal r9, r10, r4, r0\n",
            "smlal r9, r10, r5, r1\n",
            "smlal r9, r10, r6, r2\n",
            "adds r9, r9, #0x8000\n",
            "adc r10, r10, #0\n",
            "add lr, r10, #10\n",
            "cmp lr, #20\n",
            "bhs 1",
            $j,
            "f\n",
            "lsr r9, r9, #16\n",
            "orr r9, r9, r10, lsl #16\n",
            "2",
            $j,
            ":\n",
            table_activation!("r9", "r4", "r5", "r6", "r7"),
            "str r5, [r11, #(4*",
            $j,
            ")]\n",
        )
    };
}

/// Rounds row `$j`'s accumulator r10:r9 for the activation and stores it at sp + 4·`$j`: H in
/// Q16.16 bits when the rounded high word lies in [−10, 10) (then H fits 32 bits and |H| < 16),
/// else ±10 (label 1`$j`, out of line), where the table has saturated: both give
/// `activation_from_acc`'s value in the second pass ([`activation!`]).
macro_rules! pre_activation {
    ($j:literal) => {
        concat!(
            "adds r9, r9, #0x8000\n",
            "adc r10, r10, #0\n",
            "add lr, r10, #10\n",
            "cmp lr, #20\n",
            "bhs 1",
            $j,
            "f\n",
            "lsr r9, r9, #16\n",
            "orr r9, r9, r10, lsl #16\n",
            "2",
            $j,
            ":\n",
            "str r9, [sp, #(4*",
            $j,
            ")]\n",
        )
    };
}

/// The out-of-line branch of [`pre_activation!`] for row `$j`: ±10 in Q16.16 bits, the sign
/// of the high word r10.
macro_rules! saturated_pre_activation {
    ($j:literal) => {
        concat!(
            "1",
            $j,
            ":\n",
            "mov r9, #0xa0000\n",
            "cmp r10, #0\n",
            "it lt\n",
            "rsblt r9, r9, #0\n",
            "b 2",
            $j,
            "b\n",
        )
    };
}

/// a(H) for the H in `$h` into `$lo`, by the table's segments (at r3) with 2⁹ in `$half`: the
/// segment below |H| (index |H| >> 10) interpolated by the fraction |H| & 1023, rounded, the
/// sign restored — the core's `interpolate` and odd symmetry. `$abs` and `$rise` are scratch.
macro_rules! table_activation {
    ($h:literal, $abs:literal, $lo:literal, $rise:literal, $half:literal) => {
        concat!(
            "eor ",
            $abs,
            ", ",
            $h,
            ", ",
            $h,
            ", asr #31\n",
            "sub ",
            $abs,
            ", ",
            $abs,
            ", ",
            $h,
            ", asr #31\n",
            "ubfx ",
            $lo,
            ", ",
            $abs,
            ", #10, #10\n",
            "add ",
            $lo,
            ", r3, ",
            $lo,
            ", lsl #3\n",
            "ldrd ",
            $lo,
            ", ",
            $rise,
            ", [",
            $lo,
            "]\n",
            "ubfx ",
            $abs,
            ", ",
            $abs,
            ", #0, #10\n",
            "mla ",
            $rise,
            ", ",
            $rise,
            ", ",
            $abs,
            ", ",
            $half,
            "\n",
            "add ",
            $lo,
            ", ",
            $lo,
            ", ",
            $rise,
            ", asr #10\n",
            "eor ",
            $lo,
            ", ",
            $lo,
            ", ",
            $h,
            ", asr #31\n",
            "sub ",
            $lo,
            ", ",
            $lo,
            ", ",
            $h,
            ", asr #31\n",
        )
    };
}

/// Output `$j` = a(H) for the H at sp + 4·`$j` ([`table_activation!`], 2⁹ in r6), stored at
/// r2 + 4·`$j`.
macro_rules! activation {
    ($j:literal) => {
        concat!(
            "ldr r0, [sp, #(4*",
            $j,
            ")]\n",
            table_activation!("r0", "r1", "r4", "r5", "r6"),
            "str r4, [r2, #(4*",
            $j,
            ")]\n",
        )
    };
}

/// A whole forward layer of nine outputs: the rows (`$row!`, inputs loaded by `$load`) into
/// the nine pre-activations on the stack, then their activations through the table.
macro_rules! layer9 {
    ($row:ident, $load:literal, $w:expr, $b:expr, $x:expr, $out:expr, $table:expr) => {
        asm!(
            // r2 (out) and r3 (table) are saved for the second pass; 24 + 40 bytes keep sp
            // 8-byte aligned.
            "push {{r2, r3, r6, r7, r11, lr}}",
            "sub sp, sp, #40",
            // The biases go where the rows' pre-activations will be: row j reads slot j,
            // then overwrites it.
            "ldm r1, {{r2-r10}}",
            "stm sp, {{r2-r10}}",
            $load,
            $row!("0"),
            $row!("1"),
            $row!("2"),
            $row!("3"),
            $row!("4"),
            $row!("5"),
            $row!("6"),
            $row!("7"),
            $row!("8"),
            "ldr r2, [sp, #40]",
            "ldr r3, [sp, #44]",
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
            "add sp, sp, #40",
            "pop {{r2, r3, r6, r7, r11, lr}}",
            inout("r0") $x => _,
            inout("r1") $b => _,
            inout("r2") $out => _,
            inout("r3") $table => _,
            out("r4") _,
            out("r5") _,
            out("r8") _,
            out("r9") _,
            out("r10") _,
            inout("r12") $w => _,
            out("lr") _,
        )
    };
}

/// The activation table's layout that [`q16_layer_9x9`] and [`q16_layer_9x3`] read: for
/// k = 0 … 1023, a(H) in Q16.16 bits at H = k/64 and its rise to the entry at (k + 1)/64
/// (a(10) from k = 640 on, rise 0).
pub type ActivationTable = [[i32; 2]; 1024];

/// A forward layer of nine outputs on nine inputs in Q16.16: output j is the core's
/// `activation_from_acc(to_acc(bⱼ) + Σᵢ W[j][i]·xᵢ)` with `table` the core's activation
/// table — the accumulation exact in 64 bits, rounded once, then the table entry below |H|
/// interpolated towards the next; |H| ≥ 10 gives the saturated entry.
#[inline(always)]
pub fn q16_layer_9x9(
    w: &[[I16F16; 9]; 9],
    b: &[I16F16; 9],
    x: &[I16F16; 9],
    table: &ActivationTable,
) -> [I16F16; 9] {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    // SAFETY: reads the 81 words behind `w`, the 9 behind `b` and `x` and, at indices below
    // 1 024 + 1 (the index is masked to 10 bits), the table; writes the 9 words of `out`
    // (lengths fixed by the array types; `I16F16` is a transparent `i32`); uses 64 bytes of
    // stack (saving r2, r3, r6, r7, r11 and lr there, the nine pre-activations below them),
    // keeps it 8-byte aligned, and declares every other register it changes.
    unsafe {
        layer9!(
            layer_row9,
            "ldm r0, {{r0-r8}}",
            w.as_ptr(),
            b.as_ptr(),
            x.as_ptr(),
            out.as_mut_ptr(),
            table.as_ptr()
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
    // SAFETY: reads the 27 words behind `w`, the 9 behind `b`, the 3 behind `x` and, at
    // indices below 1 024 (the index is masked to 10 bits), the table; writes the 9 words of
    // `out` (lengths fixed by the array types; `I16F16` is a transparent `i32`); pushes r6,
    // r7, r11 and lr (16 bytes, keeping sp 8-byte aligned) and restores them, and declares
    // every other register it changes.
    unsafe {
        asm!(
            "push {{r6, r7, r11, lr}}",
            "mov r11, r2",
            "mov r7, #512",
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
            in("r3") table.as_ptr(),
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

/// The chain rule's tail for column `$c` of a fused transpose, its rounded accumulator
/// `$lo`/`$hi` = Σⱼ W[j][`$c`]·gⱼ + 2¹⁵ (Q32.32, high word `$hi`): with a = `a[$c]` (r2 points
/// at a, r0 = square·2¹⁶, r1 = offset·2¹⁴), t = the sum rounded to Q16.16 and, when
/// −2 ≤ a < 2 and |t| < 2¹³ (so t needs no saturation), δ = round(t·a′/2¹⁶) with
/// a′ = offset − round(square·round(a²/2¹⁶)/2¹⁶), as [`slope9!`]; stores δ at lr + 4·`$c`.
/// Outside that range label 1`$c` (out of line, [`slope_tail_slow!`]) stores t instead and
/// marks the column. Uses r3, r4 and r9.
macro_rules! slope_tail {
    ($c:literal, $lo:literal, $hi:literal) => {
        concat!(
            "ldr r3, [r2, #(4*",
            $c,
            ")]\n",
            // −2 ≤ a < 2 and −2¹³ ≤ high word < 2¹³ (t in [−2²⁹, 2²⁹) bits) at once:
            // (a + 2¹⁷) as u32 < 2¹⁸ and (high + 2¹³) as u32 < 2¹⁴ exactly when the first
            // shifted right by 4, ORed with the second, is below 2¹⁴.
            "add r4, r3, #0x20000\n",
            "add r9, ",
            $hi,
            ", #0x2000\n",
            "orr r4, r9, r4, lsr #4\n",
            "cmp r4, #0x4000\n",
            "bhs 1",
            $c,
            "f\n",
            // t·2² = (sum >> 16) << 2, in range by the test above.
            "bfc ",
            $lo,
            ", #0, #16\n",
            "lsr ",
            $lo,
            ", ",
            $lo,
            ", #14\n",
            "orr ",
            $lo,
            ", ",
            $lo,
            ", ",
            $hi,
            ", lsl #18\n",
            // a′·2¹⁴, then round((t·2²)·(a′·2¹⁴)/2³²), as slope9!.
            "lsl r3, r3, #8\n",
            "smmulr r3, r3, r3\n",
            "smmulr r3, r3, r0\n",
            "sub r3, r1, r3, lsl #14\n",
            "smmulr ",
            $lo,
            ", ",
            $lo,
            ", r3\n",
            "2",
            $c,
            ":\n",
            "str ",
            $lo,
            ", [lr, #(4*",
            $c,
            ")]\n",
        )
    };
}

/// The out-of-line branch of [`slope_tail!`] for column `$c`: t = the rounded sum saturated to
/// Q16.16 (as `Scalar::from_acc`) into `$lo`, bit `$c` set in the mask at sp + 12; back to
/// 2`$c`.
macro_rules! slope_tail_slow {
    ($c:literal, $lo:literal, $hi:literal) => {
        concat!(
            "1",
            $c,
            ":\n",
            "lsr ",
            $lo,
            ", ",
            $lo,
            ", #16\n",
            "orr ",
            $lo,
            ", ",
            $lo,
            ", ",
            $hi,
            ", lsl #16\n",
            // Exact when bits 15… of the high word all equal the result's sign bit.
            "asr r3, ",
            $hi,
            ", #15\n",
            "cmp r3, ",
            $lo,
            ", asr #31\n",
            "beq 4",
            $c,
            "f\n",
            "mvn ",
            $lo,
            ", #0x80000000\n",
            "eor ",
            $lo,
            ", ",
            $lo,
            ", ",
            $hi,
            ", asr #31\n",
            "4",
            $c,
            ":\n",
            "ldr r3, [sp, #12]\n",
            "orr r3, r3, #(1 << ",
            $c,
            ")\n",
            "str r3, [sp, #12]\n",
            "b 2",
            $c,
            "b\n",
        )
    };
}

/// Row `$j` of a column pair: W[`$j`][`$c`] and W[`$j`][`$c` + 1] by one `ldrd` (row stride 36
/// bytes, W at r12) into r9/r10, times g (in `$g`) into the accumulators r6:r5 and r8:r7;
/// `$op` is `smull` for the first row, else `smlal`.
macro_rules! pair_row {
    ($op:literal, $c:literal, $j:literal, $g:literal) => {
        concat!(
            "ldrd r9, r10, [r12, #(4*",
            $c,
            " + 36*",
            $j,
            ")]\n",
            $op,
            " r5, r6, r9, ",
            $g,
            "\n",
            $op,
            " r7, r8, r10, ",
            $g,
            "\n",
        )
    };
}

/// Columns `$c` and `$c1` = `$c` + 1 of a fused 9×9 transpose: g₀…g₄ then g₅…g₈ (at r11) into
/// r0–r4, one `ldrd` of two weights per row, then [`slope_tail!`] on each column with the
/// constants and the pointer to a (sp + 0…8) in r0–r2.
macro_rules! slope_pair {
    ($c:literal, $c1:literal) => {
        concat!(
            "ldm r11, {{r0-r4}}\n",
            pair_row!("smull", $c, "0", "r0"),
            pair_row!("smlal", $c, "1", "r1"),
            pair_row!("smlal", $c, "2", "r2"),
            pair_row!("smlal", $c, "3", "r3"),
            pair_row!("smlal", $c, "4", "r4"),
            "add r9, r11, #20\n",
            "ldm r9, {{r0-r3}}\n",
            pair_row!("smlal", $c, "5", "r0"),
            pair_row!("smlal", $c, "6", "r1"),
            pair_row!("smlal", $c, "7", "r2"),
            pair_row!("smlal", $c, "8", "r3"),
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

/// Row `$j` of the last, single column 8: W[`$j`][8] by `ldr` into r9, times g (in `$g`) into
/// r6:r5.
macro_rules! last_row {
    ($op:literal, $j:literal, $g:literal) => {
        concat!(
            "ldr r9, [r12, #(32 + 36*",
            $j,
            ")]\n",
            $op,
            " r5, r6, r9, ",
            $g,
            "\n",
        )
    };
}

/// δᵢ = `times_slope(from_acc(Σⱼ W[j][i]·gⱼ), aᵢ)` for the nine columns of a 9×9 `W` in Q16.16:
/// [`q16_transposed_9x9`] followed by [`q16_times_slope_9`] in one pass, with the same bits.
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
/// 1.7 instructions per product against the two of [`q16_transposed_9x9`], and the chain rule
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
            "ldm r11, {{r0-r4}}",
            last_row!("smull", "0", "r0"),
            last_row!("smlal", "1", "r1"),
            last_row!("smlal", "2", "r2"),
            last_row!("smlal", "3", "r3"),
            last_row!("smlal", "4", "r4"),
            "add r9, r11, #20",
            "ldm r9, {{r0-r3}}",
            last_row!("smlal", "5", "r0"),
            last_row!("smlal", "6", "r1"),
            last_row!("smlal", "7", "r2"),
            last_row!("smlal", "8", "r3"),
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

/// Output `$i` of the fused one-row transpose: t = round(wᵢ·g/2¹⁶) as [`single9_small!`] (g·2¹²
/// in r0, w at r12), then with a = `a[$i]` (at r1; r3 = square·2¹⁶, r4 = offset·2¹⁴) the
/// chain rule's fast path when −2 ≤ a < 2 (t is small enough by the weight bound), else t
/// and bit `$i` of r5 (label 1`$i`, out of line); stored at r2 + 4·`$i`.
macro_rules! single_slope {
    ($i:literal) => {
        concat!(
            "ldr r9, [r12, #(4*",
            $i,
            ")]\n",
            "lsl r9, r9, #4\n",
            "smmulr r9, r9, r0\n",
            "ldr r10, [r1, #(4*",
            $i,
            ")]\n",
            "add lr, r10, #0x20000\n",
            "cmp lr, #0x40000\n",
            "bhs 1",
            $i,
            "f\n",
            "lsl r9, r9, #2\n",
            "lsl r10, r10, #8\n",
            "smmulr r10, r10, r10\n",
            "smmulr r10, r10, r3\n",
            "sub r10, r4, r10, lsl #14\n",
            "smmulr r9, r9, r10\n",
            "2",
            $i,
            ":\n",
            "str r9, [r2, #(4*",
            $i,
            ")]\n",
        )
    };
}

/// δᵢ = `times_slope(from_acc(wᵢ·g), aᵢ)` for one row of nine weights and one g in Q16.16:
/// [`q16_transposed_1x9`] followed by [`q16_times_slope_9`] in one pass, with the same bits,
/// for −2 ≤ g < 2 and weights within the core's bound |wᵢ| ≤ 1024 (as `q16_transposed_1x9`'s
/// fast path; then |t| ≤ 2¹¹, inside the chain rule's fast range). `None` for any other g (the
/// core's g, the output's slope, is at most 1.144): the caller then takes the two steps
/// separately. A neuron with aᵢ outside [−2, 2) keeps t and its bit is set in the mask, as
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
    // |g| < 2¹⁷ bits, as the 1×9 kernel's test.
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
