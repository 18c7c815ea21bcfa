//! The simulator's firmware: a Cortex-M4F program that evaluates any neurosurf blob.
//!
//! At reset it reads `model.nsb` and `request.bin` from the host through semihosting, loads
//! the blob into a static model (no heap), evaluates the requested points with
//! `neurosurf-core` in the requested scalar, writes `result.bin`, and exits with a
//! [`Status`] code. Logs go out as defmt frames over semihosting. The protocol lives in
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
    let status = serve::run();
    semihosting::exit(status.code())
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
