//! The Q16.16 transposed kernels (see the crate docs): `Wᵀ·g` column by column with the
//! nine (or one) values of g held in general registers, one `ldr` of a weight and one `smull` /
//! `smlal` per product, and the core's rounding to Q16.16 (add 2¹⁵, shift by 16, saturate) at
//! the end of each column, so that what comes back is exactly what the portable loop followed
//! by `Scalar::from_acc` gives.
//!
//! The columns are unrolled: the weights are read at constant offsets from one base, and the
//! only branch is to the out-of-line saturation of a column whose sum leaves the Q16.16 range.
//! The 9-row blocks save and restore r6, r7 and r11 themselves (`push` / `pop`, with lr to
//! keep the stack 8-byte aligned): Rust refuses r6 and the frame pointer (r7 in Thumb code, r11
//! in ARM code) as operands or clobbers, and the nine values of g and the output pointer need
//! them. Nothing inside reads memory through them. While a block runs, r7 holds a value of g,
//! so a debugger's backtrace taken inside a kernel (which follows the frame pointer) is wrong;
//! it is right again after the block. r9 is used as an ordinary register: targets that reserve
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
/// undefined behaviour) when |g| < 2.
///
/// For |g| < 2 (the caller's g is a slope a′, at most 1.144) each output is one `smmulr`:
/// with |wᵢ| ≤ 2²⁶ and |g| < 2¹⁷ in bits, (wᵢ·2⁴)·(g·2¹²) fits the multiplier's operands, the
/// rounded high word is (wᵢ·g + 2¹⁵) >> 16 exactly, and it cannot saturate (|wᵢ·g| < 2⁴³).
/// Other g take the 64-bit product with the full rounding and saturation.
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
            // |a| ≤ 2: (a + 2·2¹⁶) as u32 ≤ 4·2¹⁶.
            "add lr, r5, #0x20000\n",
            "cmp lr, #0x40000\n",
            "bhi 1",
            $i,
            "f\n",
            // |δ| < 2²⁹: (δ + 2²⁹) as u32 < 2³⁰.
            "add lr, r4, #0x20000000\n",
            "cmp lr, #0x40000000\n",
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

/// The out-of-line branch of [`slope9!`] for neuron `$i`: sets bit `$i` of r12, δ unchanged.
macro_rules! slope_slow {
    ($i:literal) => {
        concat!(
            "1",
            $i,
            ":\n",
            "orr r12, r12, #(1 << ",
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
/// `Scalar::times_slope` for Q16.16, which holds for |aᵢ| ≤ 2 and |δᵢ| < 2¹³. A neuron outside
/// that range keeps its δ, and its bit (1 << i) is set in the returned mask: the caller
/// finishes it on the portable (saturating) path. Fifteen instructions per neuron.
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
            slope_slow!("0"),
            slope_slow!("1"),
            slope_slow!("2"),
            slope_slow!("3"),
            slope_slow!("4"),
            slope_slow!("5"),
            slope_slow!("6"),
            slope_slow!("7"),
            slope_slow!("8"),
            "3:",
            in("r0") delta.as_mut_ptr(),
            in("r1") a.as_ptr(),
            in("r2") square.wrapping_shl(16),
            in("r3") offset.wrapping_shl(14),
            out("r4") _,
            out("r5") _,
            inout("r12") 0u32 => slow,
            out("lr") _,
        );
    }
    slow
}
