//! `neurosurf`: train neural freeform surfaces on a desktop, write blobs for microcontrollers,
//! evaluate them in f64, f32 and Q16.16. Run `neurosurf --help`.

mod cli;

fn main() -> std::process::ExitCode {
    restore_default_sigpipe();
    cli::main()
}

/// Rust ignores SIGPIPE, so `neurosurf eval … | head` would panic on the closed pipe; a
/// command-line tool should end quietly instead, as `cat` does.
#[cfg(unix)]
fn restore_default_sigpipe() {
    // SAFETY: called first thing in `main`, before any thread exists; setting a signal's
    // disposition to its default has no other effect on the program.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_default_sigpipe() {}
