//! What can go wrong between the host and the simulated target.

use std::path::PathBuf;

use neurosurf_core::BlobError;

/// A failed simulation, naming what failed and showing what the firmware logged.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The toolchain or QEMU is missing (the message names it and the command that installs
    /// it).
    #[error("the Cortex-M toolchain is not ready: {0}")]
    Setup(String),
    /// Building the firmware or the plugin failed.
    #[error("cannot build {what}:\n{output}")]
    Build {
        /// The firmware or the plugin.
        what: &'static str,
        /// The compiler's output.
        output: String,
    },
    /// A file of the run could not be written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The firmware ELF is not what the runner expects.
    #[error("firmware {}: {reason}", path.display())]
    Elf {
        /// The ELF file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The firmware rejected the blob, with the core's own error.
    #[error("the target rejected the blob: {error}")]
    BlobRejected {
        /// The error the core reported on the target.
        error: BlobError,
    },
    /// The firmware ended with a failure status.
    #[error("{message} (exit code {code}){}", log_tail(.log))]
    Firmware {
        /// QEMU's exit status.
        code: i32,
        /// What the code means.
        message: String,
        /// The decoded defmt log.
        log: Vec<String>,
    },
    /// The firmware did not finish in time (a hang: the runner killed QEMU).
    #[error("the simulated target did not finish within {seconds} s and was stopped{}", log_tail(.log))]
    Timeout {
        /// The time limit.
        seconds: u64,
        /// The decoded defmt log so far.
        log: Vec<String>,
    },
    /// The result file or the plugin output does not follow the protocol.
    #[error("malformed answer from the target: {0}")]
    Protocol(String),
}

fn log_tail(log: &[String]) -> String {
    if log.is_empty() {
        String::new()
    } else {
        format!("; target log:\n  {}", log.join("\n  "))
    }
}

impl SimError {
    pub(crate) fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> SimError {
        let path = path.into();
        move |source| SimError::Io { path, source }
    }
}
