//! `neurosurf`: train neural freeform surfaces on a desktop, write blobs for microcontrollers,
//! evaluate them in f64, f32 and Q16.16. Run `neurosurf --help`.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
