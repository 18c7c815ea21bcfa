//! The kernels themselves (see the crate docs). Register use: the inputs (forward) or the
//! gradient g (transposed) in s0–s8, the accumulators in s9–s17, the current weight row in
//! s18–s26. Rows are unrolled: the assembly has no loop, no branch and no counter.
//!
//! Operands are pointers only, and each kernel saves and restores the FPU registers it uses
//! (`vpush`/`vpop`, one instruction each, an even count of registers so the stack stays 8-byte
//! aligned): Rust 1.96 (Debian's, which builds the firmware) refuses FPU register operands and
//! clobbers on `thumbv7em-none-eabihf` ("register class `sreg` requires the `vfp2` target
//! feature", fixed upstream by rust-lang/rust#159988), so the compiler cannot be told which ones
//! are clobbered. Inputs are read from and results written to memory, where the caller's layers
//! live anyway. No block claims `preserves_flags`: `vmla` sets the FPSCR's sticky exception
//! flags.
#![allow(unsafe_code)]

use core::arch::asm;
use core::mem::MaybeUninit;

/// +0.0 for the transposed accumulators (one `vldmia` starts all of them).
static ZEROS: [f32; 9] = [0.0; 9];

/// One forward row of nine weights: loads them and adds `Wⱼᵢ·xᵢ` (x in s0–s8) to `$acc`, in
/// order i = 0…8.
macro_rules! forward_row9 {
    ($acc:literal) => {
        concat!(
            "vldmia {w}!, {{s18-s26}}\n",
            "vmla.f32 ",
            $acc,
            ", s18, s0\n",
            "vmla.f32 ",
            $acc,
            ", s19, s1\n",
            "vmla.f32 ",
            $acc,
            ", s20, s2\n",
            "vmla.f32 ",
            $acc,
            ", s21, s3\n",
            "vmla.f32 ",
            $acc,
            ", s22, s4\n",
            "vmla.f32 ",
            $acc,
            ", s23, s5\n",
            "vmla.f32 ",
            $acc,
            ", s24, s6\n",
            "vmla.f32 ",
            $acc,
            ", s25, s7\n",
            "vmla.f32 ",
            $acc,
            ", s26, s8\n",
        )
    };
}

/// One forward row of three weights (x in s0–s2).
macro_rules! forward_row3 {
    ($acc:literal) => {
        concat!(
            "vldmia {w}!, {{s18-s20}}\n",
            "vmla.f32 ",
            $acc,
            ", s18, s0\n",
            "vmla.f32 ",
            $acc,
            ", s19, s1\n",
            "vmla.f32 ",
            $acc,
            ", s20, s2\n",
        )
    };
}

/// One row j of the transposed product over nine columns: loads the row and adds `Wⱼᵢ·gⱼ`
/// (gⱼ in `$g`) to accumulator i (s9–s17) for every i.
macro_rules! transposed_row9 {
    ($g:literal) => {
        concat!(
            "vldmia {w}!, {{s18-s26}}\n",
            "vmla.f32 s9, s18, ",
            $g,
            "\n",
            "vmla.f32 s10, s19, ",
            $g,
            "\n",
            "vmla.f32 s11, s20, ",
            $g,
            "\n",
            "vmla.f32 s12, s21, ",
            $g,
            "\n",
            "vmla.f32 s13, s22, ",
            $g,
            "\n",
            "vmla.f32 s14, s23, ",
            $g,
            "\n",
            "vmla.f32 s15, s24, ",
            $g,
            "\n",
            "vmla.f32 s16, s25, ",
            $g,
            "\n",
            "vmla.f32 s17, s26, ",
            $g,
            "\n",
        )
    };
}

/// One row j of the transposed product over three columns (accumulators s9–s11).
macro_rules! transposed_row3 {
    ($g:literal) => {
        concat!(
            "vldmia {w}!, {{s18-s20}}\n",
            "vmla.f32 s9, s18, ",
            $g,
            "\n",
            "vmla.f32 s10, s19, ",
            $g,
            "\n",
            "vmla.f32 s11, s20, ",
            $g,
            "\n",
        )
    };
}

/// `b + W·x` for a 9×9 `W`: output j is bⱼ + Wⱼ₀x₀ + … + Wⱼ₈x₈, summed left to right.
#[inline(always)]
pub fn affine_9x9(w: &[[f32; 9]; 9], b: &[f32; 9], x: &[f32; 9]) -> [f32; 9] {
    let mut out = MaybeUninit::<[f32; 9]>::uninit();
    // SAFETY: reads the 81 weights behind `w`, the 9 biases behind `b` and the 9 inputs behind
    // `x`, writes the 9 words of `out` (lengths fixed by the array types), and restores every
    // FPU register it uses.
    unsafe {
        asm!(
            "vpush {{s0-s27}}",
            "vldmia {x}, {{s0-s8}}",
            "vldmia {b}, {{s9-s17}}",
            forward_row9!("s9"),
            forward_row9!("s10"),
            forward_row9!("s11"),
            forward_row9!("s12"),
            forward_row9!("s13"),
            forward_row9!("s14"),
            forward_row9!("s15"),
            forward_row9!("s16"),
            forward_row9!("s17"),
            "vstmia {out}, {{s9-s17}}",
            "vpop {{s0-s27}}",
            w = inout(reg) w.as_ptr() => _,
            b = in(reg) b.as_ptr(),
            x = in(reg) x.as_ptr(),
            out = in(reg) out.as_mut_ptr(),
        );
        out.assume_init()
    }
}

/// `b + W·x` for a 9×3 `W` (a leaf's first layer): output j is bⱼ + Wⱼ₀x₀ + Wⱼ₁x₁ + Wⱼ₂x₂.
#[inline(always)]
pub fn affine_9x3(w: &[[f32; 3]; 9], b: &[f32; 9], x: &[f32; 3]) -> [f32; 9] {
    let mut out = MaybeUninit::<[f32; 9]>::uninit();
    // SAFETY: reads the 27 weights behind `w`, the 9 biases behind `b` and the 3 inputs behind
    // `x`, writes the 9 words of `out` (lengths fixed by the array types), and restores every
    // FPU register it uses.
    unsafe {
        asm!(
            "vpush {{s0-s21}}",
            "vldmia {x}, {{s0-s2}}",
            "vldmia {b}, {{s9-s17}}",
            forward_row3!("s9"),
            forward_row3!("s10"),
            forward_row3!("s11"),
            forward_row3!("s12"),
            forward_row3!("s13"),
            forward_row3!("s14"),
            forward_row3!("s15"),
            forward_row3!("s16"),
            forward_row3!("s17"),
            "vstmia {out}, {{s9-s17}}",
            "vpop {{s0-s21}}",
            w = inout(reg) w.as_ptr() => _,
            b = in(reg) b.as_ptr(),
            x = in(reg) x.as_ptr(),
            out = in(reg) out.as_mut_ptr(),
        );
        out.assume_init()
    }
}

/// `b + w·x` for one row of nine weights (a module's output neuron): b + w₀x₀ + … + w₈x₈.
#[inline(always)]
pub fn affine_1x9(w: &[f32; 9], b: &f32, x: &[f32; 9]) -> f32 {
    let mut out = MaybeUninit::<f32>::uninit();
    // SAFETY: reads the 9 weights behind `w`, the bias `b` and the 9 inputs behind `x`, writes
    // `out` (lengths fixed by the types), and restores every FPU register it uses.
    unsafe {
        asm!(
            "vpush {{s0-s27}}",
            "vldmia {x}, {{s0-s8}}",
            "vldr s9, [{b}]",
            forward_row9!("s9"),
            "vstr s9, [{out}]",
            "vpop {{s0-s27}}",
            w = inout(reg) w.as_ptr() => _,
            b = in(reg) core::ptr::from_ref(b),
            x = in(reg) x.as_ptr(),
            out = in(reg) out.as_mut_ptr(),
        );
        out.assume_init()
    }
}

/// `Wᵀ·g` for a 9×9 `W`: output i is 0 + W₀ᵢg₀ + … + W₈ᵢg₈, summed left to right.
#[inline(always)]
pub fn transposed_9x9(w: &[[f32; 9]; 9], g: &[f32; 9]) -> [f32; 9] {
    let mut out = MaybeUninit::<[f32; 9]>::uninit();
    // SAFETY: reads the 81 weights behind `w`, the 9 values behind `g` and the 9 words of
    // `ZEROS`, writes the 9 words of `out` (lengths fixed by the array types), and restores
    // every FPU register it uses.
    unsafe {
        asm!(
            "vpush {{s0-s27}}",
            "vldmia {g}, {{s0-s8}}",
            "vldmia {z}, {{s9-s17}}",
            transposed_row9!("s0"),
            transposed_row9!("s1"),
            transposed_row9!("s2"),
            transposed_row9!("s3"),
            transposed_row9!("s4"),
            transposed_row9!("s5"),
            transposed_row9!("s6"),
            transposed_row9!("s7"),
            transposed_row9!("s8"),
            "vstmia {out}, {{s9-s17}}",
            "vpop {{s0-s27}}",
            w = inout(reg) w.as_ptr() => _,
            g = in(reg) g.as_ptr(),
            z = in(reg) ZEROS.as_ptr(),
            out = in(reg) out.as_mut_ptr(),
        );
        out.assume_init()
    }
}

/// `Wᵀ·g` for a 9×3 `W` (back through a leaf's first layer): output i is
/// 0 + W₀ᵢg₀ + … + W₈ᵢg₈, summed left to right.
#[inline(always)]
pub fn transposed_9x3(w: &[[f32; 3]; 9], g: &[f32; 9]) -> [f32; 3] {
    let mut out = MaybeUninit::<[f32; 3]>::uninit();
    // SAFETY: reads the 27 weights behind `w`, the 9 values behind `g` and 3 words of `ZEROS`,
    // writes the 3 words of `out` (lengths fixed by the array types), and restores every FPU
    // register it uses.
    unsafe {
        asm!(
            "vpush {{s0-s21}}",
            "vldmia {g}, {{s0-s8}}",
            "vldmia {z}, {{s9-s11}}",
            transposed_row3!("s0"),
            transposed_row3!("s1"),
            transposed_row3!("s2"),
            transposed_row3!("s3"),
            transposed_row3!("s4"),
            transposed_row3!("s5"),
            transposed_row3!("s6"),
            transposed_row3!("s7"),
            transposed_row3!("s8"),
            "vstmia {out}, {{s9-s11}}",
            "vpop {{s0-s21}}",
            w = inout(reg) w.as_ptr() => _,
            g = in(reg) g.as_ptr(),
            z = in(reg) ZEROS.as_ptr(),
            out = in(reg) out.as_mut_ptr(),
        );
        out.assume_init()
    }
}

/// `wᵀ·g` for one row of nine weights and one g: output i is 0 + wᵢ·g.
#[inline(always)]
pub fn transposed_1x9(w: &[f32; 9], g: &f32) -> [f32; 9] {
    let mut out = MaybeUninit::<[f32; 9]>::uninit();
    // SAFETY: reads the 9 weights behind `w`, `g` and the 9 words of `ZEROS`, writes the 9
    // words of `out` (lengths fixed by the types), and restores every FPU register it uses.
    unsafe {
        asm!(
            "vpush {{s0-s27}}",
            "vldr s0, [{g}]",
            "vldmia {z}, {{s9-s17}}",
            transposed_row9!("s0"),
            "vstmia {out}, {{s9-s17}}",
            "vpop {{s0-s27}}",
            w = inout(reg) w.as_ptr() => _,
            g = in(reg) core::ptr::from_ref(g),
            z = in(reg) ZEROS.as_ptr(),
            out = in(reg) out.as_mut_ptr(),
        );
        out.assume_init()
    }
}
