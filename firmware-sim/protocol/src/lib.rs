//! The protocol between the simulator runner (host) and the firmware (target).
//!
//! The runner writes two files into QEMU's working directory and the firmware reads them
//! through semihosting; the firmware answers with a third file and its exit code:
//!
//! | file | written by | content |
//! |---|---|---|
//! | [`MODEL_FILE`] | host | the model blob, unchanged |
//! | [`REQUEST_FILE`] | host | a [`RequestHeader`], then `count` points of `arity` little-endian `f32` |
//! | [`RESULT_FILE`] | target | the answer (see [`Status`]), then a [`ResultTrailer`] |
//!
//! On success the answer is `count × words` little-endian 32-bit words (`words` in the
//! [`ResultTrailer`]), the raw bits of the scalar (`f32` bits, or Q16.16 bits): for implicit
//! models Φ, then ∇Φ when the op asks for it; for the parametric kinds the output vector (a
//! curve's or surface's position, a Cao En network's p outputs), then the tangent (curves) or the
//! unit normal (surfaces, Cao En shapes). A request point has `arity` coordinates (1 to
//! [`MAX_ARITY`]): an implicit model reads x, y, z, a curve t, a surface (u, v), a Cao En network
//! its source point; missing coordinates count as 0, extra ones are ignored. When the blob
//! is rejected, the answer is the core's `BlobError` encoded with postcard, so the host can
//! show exactly what the target saw.
//!
//! Cost is measured outside the protocol: the firmware calls [`REGION_START_SYMBOL`] and
//! [`REGION_STOP_SYMBOL`] around every evaluation it times (the first region is empty: it
//! calibrates the markers' own cost), and an instruction-counting QEMU plugin reports the
//! instructions executed in each region.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

/// The blob file the firmware opens.
pub const MODEL_FILE: &str = "model.nsb";
/// The request file the firmware opens.
pub const REQUEST_FILE: &str = "request.bin";
/// The result file the firmware writes.
pub const RESULT_FILE: &str = "result.bin";

/// Symbol of the function the firmware calls when a timed region starts.
pub const REGION_START_SYMBOL: &str = "neurosurf_region_start";
/// Symbol of the function the firmware calls when a timed region stops.
pub const REGION_STOP_SYMBOL: &str = "neurosurf_region_stop";

/// Protocol version, checked by both sides.
pub const VERSION: u8 = 2;
/// Most coordinates a request point can have.
pub const MAX_ARITY: usize = 8;
/// Points the firmware evaluates per timed region (a multiple of the core's lane count).
pub const CHUNK_POINTS: usize = 64;
/// Largest blob the firmware accepts (its static blob buffer).
pub const MAX_BLOB_BYTES: usize = 48 * 1024;

/// How the firmware ended, as QEMU's exit status (semihosting `SYS_EXIT_EXTENDED`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
#[repr(u8)]
pub enum Status {
    /// Every point was evaluated; the results follow.
    Ok = 0,
    /// The request file is missing, malformed or asks for something this firmware cannot do.
    BadRequest = 2,
    /// The core rejected the blob; the postcard-encoded `BlobError` follows.
    BlobRejected = 3,
    /// A semihosting file operation failed (the host side of the files).
    HostIo = 4,
    /// A target kernel computed other bits than its portable loop (the log names it).
    KernelMismatch = 5,
    /// The firmware panicked (a bug: the core never panics).
    Panic = 101,
    /// The CPU took a HardFault (a bug).
    HardFault = 102,
}

impl Status {
    /// The exit code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The status with exit code `code`, if any.
    pub const fn from_code(code: i32) -> Option<Self> {
        Some(match code {
            0 => Status::Ok,
            2 => Status::BadRequest,
            3 => Status::BlobRejected,
            4 => Status::HostIo,
            5 => Status::KernelMismatch,
            101 => Status::Panic,
            102 => Status::HardFault,
            _ => return None,
        })
    }

    /// What the status means, for messages.
    pub const fn describe(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::BadRequest => "the firmware rejected the request",
            Status::BlobRejected => "the firmware rejected the blob",
            Status::HostIo => "a semihosting file operation failed",
            Status::KernelMismatch => {
                "a target kernel differs from its portable loop (the log names the kernel)"
            }
            Status::Panic => "the firmware panicked",
            Status::HardFault => "the firmware took a HardFault",
        }
    }
}

/// What to compute at every point.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
#[repr(u8)]
pub enum Op {
    /// Φ only: one word per point.
    Field = 1,
    /// Φ and ∇Φ: four words per point.
    FieldGradient = 2,
    /// Parametric models: the output vector — a curve's or surface's position (3 words, z = 0
    /// for a 2-D curve), a Cao En network's p outputs.
    Position = 3,
    /// The output vector, then three words of direction: a curve's tangent dC/dt, a surface's
    /// or Cao En shape's unit normal (0, 0, 0 where it does not exist).
    PositionDirection = 4,
    /// Self-test: panic on purpose (checks the runner's panic reporting).
    SelfTestPanic = 0xF0,
    /// Self-test: never finish (checks the runner's time limit).
    SelfTestHang = 0xF1,
}

impl Op {
    /// Whether the op evaluates curves and spline surfaces (rather than implicit fields).
    pub const fn is_parametric(self) -> bool {
        matches!(self, Op::Position | Op::PositionDirection)
    }

    /// Result words per point, when the op alone decides it (`None` for the parametric ops,
    /// whose width is the model's output dimension; the trailer says it).
    pub const fn words(self) -> Option<usize> {
        match self {
            Op::Field => Some(1),
            Op::FieldGradient => Some(4),
            Op::Position | Op::PositionDirection => None,
            Op::SelfTestPanic | Op::SelfTestHang => Some(0),
        }
    }

    fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            1 => Op::Field,
            2 => Op::FieldGradient,
            3 => Op::Position,
            4 => Op::PositionDirection,
            0xF0 => Op::SelfTestPanic,
            0xF1 => Op::SelfTestHang,
            _ => return None,
        })
    }
}

/// Whether points go through the core one at a time or in lane batches.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
#[repr(u8)]
pub enum Mode {
    /// `field` / `field_gradient`, one point per call.
    Single = 0,
    /// `field_batch` / `field_gradient_batch` over each chunk.
    Batch = 1,
}

impl Mode {
    fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0 => Mode::Single,
            1 => Mode::Batch,
            _ => return None,
        })
    }
}

/// Why a request header does not decode.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RequestError {
    /// Fewer bytes than a header.
    Truncated,
    /// Not a request file.
    BadMagic,
    /// Another protocol version.
    Version(u8),
    /// Unknown op code.
    Op(u8),
    /// Unknown mode code.
    Mode(u8),
    /// Coordinates per point outside 1 ..= [`MAX_ARITY`].
    Arity(u8),
}

/// The fixed-size start of [`REQUEST_FILE`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct RequestHeader {
    /// Scalar kind code to evaluate in (the core's `ScalarKind::code`).
    pub scalar: u8,
    /// What to compute.
    pub op: Op,
    /// Single points or batches.
    pub mode: Mode,
    /// Coordinates per point (1 ..= [`MAX_ARITY`]).
    pub arity: u8,
    /// Number of points that follow.
    pub count: u32,
}

impl RequestHeader {
    /// Encoded size.
    pub const LEN: usize = 16;
    const MAGIC: [u8; 4] = *b"NSRQ";

    /// Bytes per point after the header.
    pub const fn point_bytes(&self) -> usize {
        4 * self.arity as usize
    }

    /// Encodes the header.
    pub fn encode(&self) -> [u8; Self::LEN] {
        let mut out = [0; Self::LEN];
        out[..4].copy_from_slice(&Self::MAGIC);
        out[4] = VERSION;
        out[5] = self.scalar;
        out[6] = self.op as u8;
        out[7] = self.mode as u8;
        out[8..12].copy_from_slice(&self.count.to_le_bytes());
        out[12] = self.arity;
        out
    }

    /// Decodes a header from the start of `bytes`.
    ///
    /// # Errors
    /// [`RequestError`] naming the first problem.
    pub fn decode(bytes: &[u8]) -> Result<Self, RequestError> {
        let Some(header) = bytes.get(..Self::LEN) else {
            return Err(RequestError::Truncated);
        };
        if header[..4] != Self::MAGIC {
            return Err(RequestError::BadMagic);
        }
        if header[4] != VERSION {
            return Err(RequestError::Version(header[4]));
        }
        Ok(RequestHeader {
            scalar: header[5],
            op: Op::from_code(header[6]).ok_or(RequestError::Op(header[6]))?,
            mode: Mode::from_code(header[7]).ok_or(RequestError::Mode(header[7]))?,
            arity: match header[12] {
                a if a >= 1 && usize::from(a) <= MAX_ARITY => a,
                other => return Err(RequestError::Arity(other)),
            },
            count: u32::from_le_bytes([header[8], header[9], header[10], header[11]]),
        })
    }
}

/// The fixed-size end of [`RESULT_FILE`] (written last, once the stack high-water mark is
/// known; a run that dies early leaves no trailer and only its exit code).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ResultTrailer {
    /// How the run ended (also the exit code).
    pub status: u8,
    /// Words per point in the answer (0 unless `status` is ok).
    pub words: u8,
    /// Points answered.
    pub count: u32,
    /// Stack high-water mark in bytes (painted-stack measurement).
    pub stack_bytes: u32,
    /// Bytes of the answer before the trailer.
    pub answer_bytes: u32,
}

impl ResultTrailer {
    /// Encoded size.
    pub const LEN: usize = 20;
    const MAGIC: [u8; 4] = *b"NSRS";

    /// Encodes the trailer.
    pub fn encode(&self) -> [u8; Self::LEN] {
        let mut out = [0; Self::LEN];
        out[..4].copy_from_slice(&Self::MAGIC);
        out[4] = VERSION;
        out[5] = self.status;
        out[6] = self.words;
        out[8..12].copy_from_slice(&self.count.to_le_bytes());
        out[12..16].copy_from_slice(&self.stack_bytes.to_le_bytes());
        out[16..20].copy_from_slice(&self.answer_bytes.to_le_bytes());
        out
    }

    /// Decodes the trailer at the end of `bytes`.
    ///
    /// # Errors
    /// [`RequestError`] (the same framing problems as a request).
    pub fn decode(bytes: &[u8]) -> Result<Self, RequestError> {
        let start = bytes
            .len()
            .checked_sub(Self::LEN)
            .ok_or(RequestError::Truncated)?;
        let Some(h) = bytes.get(start..) else {
            return Err(RequestError::Truncated);
        };
        if h[..4] != Self::MAGIC {
            return Err(RequestError::BadMagic);
        }
        if h[4] != VERSION {
            return Err(RequestError::Version(h[4]));
        }
        let word = |at: usize| u32::from_le_bytes([h[at], h[at + 1], h[at + 2], h[at + 3]]);
        Ok(ResultTrailer {
            status: h[5],
            words: h[6],
            count: word(8),
            stack_bytes: word(12),
            answer_bytes: word(16),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_round_trip_and_reject_garbage() {
        let request = RequestHeader {
            scalar: 2,
            op: Op::FieldGradient,
            mode: Mode::Batch,
            arity: 3,
            count: 1234,
        };
        assert_eq!(RequestHeader::decode(&request.encode()), Ok(request));
        assert_eq!(request.point_bytes(), 12);
        let mut wide = request.encode();
        wide[12] = 9;
        assert_eq!(RequestHeader::decode(&wide), Err(RequestError::Arity(9)));
        let mut bad = request.encode();
        bad[6] = 9;
        assert_eq!(RequestHeader::decode(&bad), Err(RequestError::Op(9)));
        bad[4] = 7;
        assert_eq!(RequestHeader::decode(&bad), Err(RequestError::Version(7)));
        assert_eq!(RequestHeader::decode(b"NSRQ"), Err(RequestError::Truncated));
        assert_eq!(RequestHeader::decode(&[0; 16]), Err(RequestError::BadMagic));
        let result = ResultTrailer {
            status: 3,
            words: 0,
            count: 0,
            stack_bytes: 4096,
            answer_bytes: 7,
        };
        assert_eq!(ResultTrailer::decode(&result.encode()), Ok(result));
    }

    #[test]
    fn every_status_round_trips_through_its_code() {
        for status in [
            Status::Ok,
            Status::BadRequest,
            Status::BlobRejected,
            Status::HostIo,
            Status::KernelMismatch,
            Status::Panic,
            Status::HardFault,
        ] {
            assert_eq!(Status::from_code(i32::from(status.code())), Some(status));
        }
        assert_eq!(Status::from_code(1), None);
    }
}
