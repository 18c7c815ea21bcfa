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

/// The one-row transpose, one `single9!` per listed output, the saturations out of line: g
/// in r0, the weights at `$w`, the outputs written at `$out`.
macro_rules! transposed_row1 {
    ($w:expr, $g:expr, $out:expr, $($i:literal),+) => {
        asm!(
            "push {{r11, lr}}",
            "mov r11, r1",
            $(single9!($i),)+
            "b 3f",
            $(saturate!($i),)+
            "3:",
            "pop {{r11, lr}}",
            in("r0") $g,
            in("r1") $out,
            out("r9") _,
            out("r10") _,
            in("r12") $w,
            out("lr") _,
        )
    };
}

/// `wᵀ·g` for one row of nine weights and one g in Q16.16, rounded: output i is
/// `from_acc(0 + wᵢ·g)`.
#[inline(always)]
pub fn q16_transposed_1x9(w: &[I16F16; 9], g: I16F16) -> [I16F16; 9] {
    let mut out = MaybeUninit::<[I16F16; 9]>::uninit();
    // SAFETY: reads the 9 words behind `w`, writes the 9 words of `out` (lengths fixed by the
    // array types), saves and restores r11 and lr (8 bytes) and declares every other register
    // it changes.
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
