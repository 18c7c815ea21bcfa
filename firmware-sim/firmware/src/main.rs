//! The simulator's firmware: a Cortex-M4F program that evaluates any neurosurf blob.
//!
//! At reset it reads `model.nsb` and `request.bin` from the host through semihosting, loads
//! the blob into a static model (no heap), evaluates the requested points with
//! `neurosurf-core` in the requested scalar, writes `result.bin`, and exits with a
//! [`Status`] code. Then it checks every target kernel against its portable loop
//! (`neurosurf_core::kernel_check`), so that a broken kernel fails every run by name. Logs go out as defmt frames over semihosting. The protocol lives in
//! `neurosurf-sim-protocol`, shared with the host runner.
#![no_std]
#![no_main]

mod regions;
mod semihosting;
mod serve;
mod slot;
mod stack;

// cortex-m provides the single-core critical section defmt needs.
use cortex_m as _;
use defmt_semihosting as _;
use neurosurf_sim_protocol::Status;

#[cortex_m_rt::entry]
fn main() -> ! {
    let served = serve::run();
    // After the answer, whose stack figure is then the evaluation's own.
    let status = check_kernels().err().unwrap_or(served);
    semihosting::exit(status.code())
}

/// Seed and number of cases of the kernel check: five edge cases, then seeded random inputs.
const KERNEL_CHECK: (u32, u32) = (0x6e73_6b63, 64);

/// Every kernel against its portable loop; logs how many calls matched, or names the kernel
/// and the case that did not.
fn check_kernels() -> Result<(), Status> {
    let (seed, cases) = KERNEL_CHECK;
    match neurosurf_core::kernel_check::check_kernels(seed, cases) {
        Ok(checked) => {
            defmt::info!(
                "kernel check: {=u32} kernel calls match the portable loops",
                checked
            );
            Ok(())
        }
        Err(mismatch) => {
            defmt::error!(
                "kernel check: {=str} differs from its portable loop in case {=u32}",
                mismatch.kernel,
                mismatch.case
            );
            Err(Status::KernelMismatch)
        }
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    semihosting::exit(Status::Panic.code())
}

#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    semihosting::exit(Status::HardFault.code())
}
