//! Running a firmware ELF in QEMU: the board, semihosting, a time limit, the output kept.

use std::ffi::OsString;
use std::io::Read;
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::time::Duration;

use wait_timeout::ChildExt;

use crate::{SimError, TARGET_MACHINE, Toolchain, log};

/// How a QEMU run ended and what it printed.
#[derive(Debug)]
pub(crate) struct Finished {
    /// QEMU's exit status (the firmware's semihosting exit code); `None` when the time limit
    /// stopped it.
    pub(crate) status: Option<ExitStatus>,
    /// The firmware's semihosting output: its defmt frames.
    pub(crate) stdout: Vec<u8>,
    /// QEMU's own messages.
    pub(crate) stderr: String,
}

/// Runs `elf` on the simulated board, in folder `dir` (where its semihosting file operations
/// land), with `extra` QEMU arguments, until it exits or `limit` has passed (then QEMU is
/// killed).
///
/// # Errors
/// [`SimError::Io`] when QEMU cannot be started or waited for.
pub(crate) fn run(
    qemu: &Path,
    elf: &Path,
    dir: &Path,
    extra: &[OsString],
    limit: Duration,
) -> Result<Finished, SimError> {
    let mut child = Command::new(qemu)
        .args(["-M", TARGET_MACHINE, "-cpu", "cortex-m4"])
        .args(["-display", "none", "-serial", "null", "-monitor", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(extra)
        .arg("-kernel")
        .arg(elf)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(SimError::io(qemu))?;
    // Drain the pipes while QEMU runs so a chatty target cannot block on them.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let stderr = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let status = child.wait_timeout(limit).map_err(SimError::io(qemu))?;
    if status.is_none() {
        let _ = child.kill();
        let _ = child.wait();
    }
    Ok(Finished {
        status,
        stdout: stdout.join().unwrap_or_default(),
        stderr: String::from_utf8_lossy(&stderr.join().unwrap_or_default()).into_owned(),
    })
}

/// Runs a firmware that needs no request from the host — an example, a self-test — and
/// returns its defmt log, decoded with the ELF's own tables.
///
/// ```no_run
/// # fn main() -> Result<(), neurosurf_firmware_sim::SimError> {
/// use neurosurf_firmware_sim::{Toolchain, build_elf, repository_root, run_program};
/// let root = repository_root();
/// let toolchain = Toolchain::find(&root)?;
/// let source = root.join("examples/cortex-m");
/// let target_dir = root.join("target/examples/cortex-m");
/// let elf = build_elf(&toolchain, &root, &source, &target_dir, "neurosurf-example-cortex-m")?;
/// for line in run_program(&toolchain, &elf, std::time::Duration::from_secs(60))? {
///     println!("{line}");
/// }
/// # Ok(()) }
/// ```
///
/// # Errors
/// [`SimError::Elf`] when the ELF has no defmt table; [`SimError::Firmware`] with the log when
/// the firmware exits with a failure status (a panic, a refused blob, a QEMU error);
/// [`SimError::Timeout`] when it runs longer than `limit`; [`SimError::Io`].
pub fn run_program(
    toolchain: &Toolchain,
    elf: &Path,
    limit: Duration,
) -> Result<Vec<String>, SimError> {
    let bytes = std::fs::read(elf).map_err(SimError::io(elf))?;
    let table = log::table(elf, &bytes)?;
    let dir = tempfile::Builder::new()
        .prefix("neurosurf-program-")
        .tempdir()
        .map_err(SimError::io(std::env::temp_dir()))?;
    let finished = run(&toolchain.qemu, elf, dir.path(), &[], limit)?;
    let log = log::decode(&table, &finished.stdout);
    match finished.status {
        None => Err(SimError::Timeout {
            seconds: limit.as_secs(),
            log,
        }),
        Some(status) if status.success() => Ok(log),
        Some(status) => Err(SimError::Firmware {
            code: status.code().unwrap_or(-1),
            message: with_stderr("the firmware reported a failure", &finished.stderr),
            log,
        }),
    }
}

/// `what` went wrong, followed by QEMU's own message if it printed one.
pub(crate) fn with_stderr(what: &str, stderr: &str) -> String {
    match stderr.trim() {
        "" => what.to_string(),
        message => format!("{what}: {message}"),
    }
}
