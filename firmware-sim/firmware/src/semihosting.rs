//! Host file I/O and exit codes through ARM semihosting (what QEMU gives a bare-metal guest).

use cortex_m_semihosting::{nr, syscall};

/// An open host file.
pub struct HostFile(usize);

/// A failed semihosting file operation.
#[derive(Copy, Clone, Debug, PartialEq, Eq, defmt::Format)]
pub struct HostIoError;

impl HostFile {
    /// Opens `name` (NUL-terminated) for reading (binary).
    pub fn open_read(name: &[u8]) -> Result<Self, HostIoError> {
        Self::open(name, nr::open::R_BINARY)
    }

    /// Creates or truncates `name` (NUL-terminated) for writing (binary).
    pub fn create(name: &[u8]) -> Result<Self, HostIoError> {
        Self::open(name, nr::open::W_TRUNC_BINARY)
    }

    fn open(name: &[u8], mode: usize) -> Result<Self, HostIoError> {
        if name.last() != Some(&0) {
            return Err(HostIoError);
        }
        // SAFETY: SYS_OPEN reads `len` bytes of the NUL-terminated name we pass.
        let fd = unsafe { syscall!(OPEN, name.as_ptr(), mode, name.len() - 1) };
        if fd as isize == -1 {
            Err(HostIoError)
        } else {
            Ok(HostFile(fd))
        }
    }

    /// Length of the file in bytes.
    pub fn len(&self) -> Result<usize, HostIoError> {
        // SAFETY: SYS_FLEN takes the handle only.
        let len = unsafe { syscall!(FLEN, self.0) };
        if len as isize == -1 {
            Err(HostIoError)
        } else {
            Ok(len)
        }
    }

    /// Fills `buffer` completely, or fails.
    pub fn read_exact(&mut self, buffer: &mut [u8]) -> Result<(), HostIoError> {
        if buffer.is_empty() {
            return Ok(());
        }
        // SAFETY: SYS_READ writes at most `len` bytes into the buffer we own.
        let not_read = unsafe { syscall!(READ, self.0, buffer.as_mut_ptr(), buffer.len()) };
        if not_read == 0 {
            Ok(())
        } else {
            Err(HostIoError)
        }
    }

    /// Writes all of `bytes`.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<(), HostIoError> {
        if bytes.is_empty() {
            return Ok(());
        }
        // SAFETY: SYS_WRITE reads `len` bytes from the slice.
        let not_written = unsafe { syscall!(WRITE, self.0, bytes.as_ptr(), bytes.len()) };
        if not_written == 0 {
            Ok(())
        } else {
            Err(HostIoError)
        }
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: SYS_CLOSE takes the handle only; it is not used afterwards.
        unsafe {
            syscall!(CLOSE, self.0);
        }
    }
}

/// Ends the simulation with `code` as QEMU's exit status (SYS_EXIT_EXTENDED: unlike
/// SYS_EXIT, any code reaches the host on 32-bit ARM).
pub fn exit(code: u8) -> ! {
    const APPLICATION_EXIT: usize = 0x20026;
    const SYS_EXIT_EXTENDED: usize = 0x20;
    let block = [APPLICATION_EXIT, usize::from(code)];
    loop {
        // SAFETY: SYS_EXIT_EXTENDED reads the two-word block; QEMU exits and never returns.
        unsafe {
            cortex_m_semihosting::syscall(SYS_EXIT_EXTENDED, &block);
        }
    }
}
