//! The smallest firmware that embeds `neurosurf-core`: a Cortex-M4F program that loads a
//! trained implicit surface (a torus) from flash, evaluates Φ and ∇Φ at one point in `f32` and
//! in Q16.16 fixed point, logs the point, Φ and the outward unit normal with defmt, and exits.
//!
//! The README says how to build it, run it in QEMU and put your own blob in.
#![no_std]
#![no_main]

use core::mem::MaybeUninit;

use cortex_m_rt::entry;
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS, ExitStatus};
use defmt_semihosting as _; // the defmt transport: log frames go to the host by semihosting
use neurosurf_core::implicit::{FieldGradient, ImplicitModel};
use neurosurf_core::scalar::{Q16, Scalar};

/// The model, in flash: a torus of radii 1 and 0.4 (`core/examples/torus.nsb`), stored in
/// `f32`. Put your own blob's path here.
static TORUS: &[u8] = include_bytes!("../../../core/examples/torus.nsb");

/// Where to evaluate: a point on the torus's outer equator, whose outward normal is +x.
const POINT: [f32; 3] = [1.4, 0.0, 0.0];

#[entry]
fn main() -> ! {
    // A model reserves room for the largest blob it accepts (32 KiB of parameters by
    // default), too much for a stack, so each lives in a static. `#[entry]` turns these
    // `static mut`s into `&'static mut` references without `unsafe`, and `MaybeUninit` keeps
    // them in `.bss` instead of copying their initial value from flash.
    static mut FLOAT: MaybeUninit<ImplicitModel<f32>> = MaybeUninit::uninit();
    static mut FIXED: MaybeUninit<ImplicitModel<Q16>> = MaybeUninit::uninit();
    let float = FLOAT.write(ImplicitModel::new());
    let fixed = FIXED.write(ImplicitModel::new());

    // Every check of the blob happens here; after it, evaluation cannot fail or panic.
    if let Err(error) = float.load(TORUS).and_then(|()| fixed.load(TORUS)) {
        defmt::error!("the core refuses the blob: {}", error);
        exit(EXIT_FAILURE);
    }
    defmt::info!(
        "model: {=usize} modules of width {=usize}",
        float.module_count(),
        float.width()
    );
    log_normal("f32", float.field_gradient(POINT));
    log_normal(
        "Q16.16",
        fixed.field_gradient(POINT.map(Q16::from_f32_saturating)),
    );
    exit(EXIT_SUCCESS)
}

/// Logs Φ and the outward unit normal −∇Φ/|∇Φ| at [`POINT`], converted to `f32` for the log.
fn log_normal<S: Scalar>(scalar: &str, result: FieldGradient<S>) {
    let phi = result.value.to_f32();
    match result.normal() {
        Some(normal) => defmt::info!(
            "{=str}: Φ({}) = {=f32}, normal {}",
            scalar,
            POINT,
            phi,
            normal.map(S::to_f32)
        ),
        None => defmt::warn!(
            "{=str}: Φ({}) = {=f32}, no normal: ∇Φ = 0",
            scalar,
            POINT,
            phi
        ),
    }
}

/// Ends the program; under QEMU its exit status becomes 0 (success) or 1 (failure).
fn exit(status: ExitStatus) -> ! {
    debug::exit(status);
    // Without a host to stop it (no debugger attached), stay here.
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    exit(EXIT_FAILURE)
}
