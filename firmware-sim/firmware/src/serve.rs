//! One run: read the request and the blob from the host, evaluate, write the answer.

use core::mem::{MaybeUninit, align_of, size_of};

use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::model::{self, MAX_INPUTS, MAX_OUTPUTS, Model, ModelVisitor};
use neurosurf_core::scalar::{Scalar, ScalarKind};
use neurosurf_sim_protocol::{
    CHUNK_POINTS, MAX_ARITY, MAX_BLOB_BYTES, MODEL_FILE, Mode, Op, REQUEST_FILE, RESULT_FILE,
    RequestHeader, ResultTrailer, Status,
};

use crate::regions::timed;
use crate::semihosting::HostFile;
use crate::slot::Slot;
use crate::stack;

// A request point is a model's input at its widest.
const _: () = assert!(MAX_ARITY == MAX_INPUTS);

static BLOB: Slot<[u8; MAX_BLOB_BYTES]> = Slot::new([0; MAX_BLOB_BYTES]);

/// NUL-terminated copies of the protocol's file names, for SYS_OPEN.
macro_rules! c_name {
    ($name:expr) => {{
        const N: usize = $name.len() + 1;
        const BYTES: [u8; N] = {
            let mut out = [0_u8; N];
            let src = $name.as_bytes();
            let mut i = 0;
            while i < src.len() {
                out[i] = src[i];
                i += 1;
            }
            out
        };
        &BYTES
    }};
}

/// What the run wrote before its trailer.
struct Answer {
    status: Status,
    words: u8,
    count: u32,
    bytes: u32,
}

impl Answer {
    fn failed(status: Status) -> Self {
        Answer {
            status,
            words: 0,
            count: 0,
            bytes: 0,
        }
    }
}

/// Serves the request in the working directory and returns the exit status.
pub fn run() -> Status {
    // The first timed region is empty: the runner subtracts its cost from every other one.
    timed(|| ());
    let Ok(mut out) = HostFile::create(c_name!(RESULT_FILE)) else {
        defmt::error!("cannot create {}", RESULT_FILE);
        return Status::HostIo;
    };
    let answer = serve(&mut out);
    let trailer = ResultTrailer {
        status: answer.status.code(),
        words: answer.words,
        count: answer.count,
        stack_bytes: stack::high_water_bytes(),
        answer_bytes: answer.bytes,
    };
    defmt::info!("stack high-water mark: {=u32} bytes", trailer.stack_bytes);
    if out.write_all(&trailer.encode()).is_err() {
        return Status::HostIo;
    }
    answer.status
}

fn serve(out: &mut HostFile) -> Answer {
    let Ok(mut request) = HostFile::open_read(c_name!(REQUEST_FILE)) else {
        defmt::error!("cannot open {}", REQUEST_FILE);
        return Answer::failed(Status::BadRequest);
    };
    let mut header = [0_u8; RequestHeader::LEN];
    if request.read_exact(&mut header).is_err() {
        defmt::error!("request shorter than its header");
        return Answer::failed(Status::BadRequest);
    }
    let header = match RequestHeader::decode(&header) {
        Ok(header) => header,
        Err(e) => {
            defmt::error!("bad request header: {}", defmt::Debug2Format(&e));
            return Answer::failed(Status::BadRequest);
        }
    };
    let expected =
        RequestHeader::LEN as u64 + u64::from(header.count) * header.point_bytes() as u64;
    if request.len().map(|len| len as u64) != Ok(expected) {
        defmt::error!(
            "request length disagrees with its {=u32} points",
            header.count
        );
        return Answer::failed(Status::BadRequest);
    }
    match header.op {
        Op::SelfTestPanic => panic!("self-test: panic requested"),
        Op::SelfTestHang => {
            defmt::info!("self-test: hanging on purpose");
            loop {
                core::hint::spin_loop();
            }
        }
        _ => {}
    }

    let Some(buffer) = BLOB.take() else {
        return Answer::failed(Status::HostIo);
    };
    let blob = match read_blob(buffer) {
        Ok(blob) => blob,
        Err(status) => return Answer::failed(status),
    };
    let kind = match blob::parse(blob) {
        Ok((blob_header, _)) => blob_header.model,
        Err(e) => return reject(out, e),
    };
    defmt::info!(
        "request: {=u32} points, op {}, scalar code {=u8}, blob {=usize} bytes",
        header.count,
        header.op as u8,
        header.scalar,
        blob.len()
    );
    let Some(scalar) = ScalarKind::from_code(header.scalar) else {
        defmt::error!("unknown scalar code {=u8}", header.scalar);
        return Answer::failed(Status::BadRequest);
    };
    let io = Io {
        header: &header,
        request: &mut request,
        out: &mut *out,
    };
    model::visit(kind, scalar, Serve { blob, io }).unwrap_or_else(|| {
        // The kind or the scalar is not evaluated on the target: the RBF baseline runs on
        // the host only, f64 is not a target scalar.
        if kind == ModelKind::Rbf {
            reject(
                out,
                BlobError::WrongModelKind {
                    expected: ModelKind::Implicit,
                    found: kind,
                },
            )
        } else {
            defmt::error!(
                "scalar {=str} is not evaluated on the target",
                scalar.name()
            );
            Answer::failed(Status::BadRequest)
        }
    })
}

/// The request being served: its header, the rest of its file, and the result file.
struct Io<'a> {
    header: &'a RequestHeader,
    request: &'a mut HostFile,
    out: &'a mut HostFile,
}

/// Reads the whole blob file into `buffer`.
fn read_blob(buffer: &'static mut [u8; MAX_BLOB_BYTES]) -> Result<&'static [u8], Status> {
    let Ok(mut file) = HostFile::open_read(c_name!(MODEL_FILE)) else {
        defmt::error!("cannot open {}", MODEL_FILE);
        return Err(Status::BadRequest);
    };
    let len = file.len().map_err(|_| Status::HostIo)?;
    let Some(slice) = buffer.get_mut(..len) else {
        defmt::error!(
            "blob of {=usize} bytes exceeds the {=usize}-byte buffer",
            len,
            MAX_BLOB_BYTES
        );
        return Err(Status::BadRequest);
    };
    file.read_exact(slice).map_err(|_| Status::HostIo)?;
    Ok(slice)
}

/// Reports a rejected blob: the core's error, postcard-encoded, is the answer.
fn reject(out: &mut HostFile, error: BlobError) -> Answer {
    defmt::warn!("blob rejected: {}", error);
    let mut encoded = [0_u8; 64];
    let bytes = match postcard::to_slice(&error, &mut encoded) {
        Ok(bytes) => &*bytes,
        Err(_) => &[][..],
    };
    if out.write_all(bytes).is_err() {
        return Answer::failed(Status::HostIo);
    }
    Answer {
        status: Status::BlobRejected,
        words: 0,
        count: 0,
        bytes: bytes.len() as u32,
    }
}

/// One request for whatever model type the blob names ([`model::visit`]): the model is
/// loaded in place in the static [`MODEL`] slot (no stack copy of up to 32 KiB of parameters),
/// then the points stream through it.
struct Serve<'a> {
    blob: &'static [u8],
    io: Io<'a>,
}

impl ModelVisitor for Serve<'_> {
    type Output = Answer;

    fn visit<S: Scalar, M: Model<S>>(self) -> Answer {
        let Serve { blob, io } = self;
        let op = io.header.op;
        // Field ops ask implicit models, position ops parametric ones.
        if op.is_parametric() == (M::KIND == ModelKind::Implicit) {
            defmt::error!(
                "op {=u8} does not apply to {=str} models",
                op as u8,
                M::KIND.name()
            );
            return Answer::failed(Status::BadRequest);
        }
        let Some(storage) = MODEL.take() else {
            return Answer::failed(Status::HostIo);
        };
        let model = place::<S, M>(storage);
        if let Err(e) = model.load_blob(blob) {
            return reject(io.out, e);
        }
        let full = matches!(op, Op::FieldGradient | Op::PositionDirection);
        defmt::info!(
            "{=str} model: {=usize} inputs, {=usize} outputs, {=usize} MACs per evaluation",
            M::KIND.name(),
            model.input_len(),
            model.output_len(full),
            model.mac_count(full)
        );
        let model = &*model;
        let words = model.output_len(full);
        if io.header.mode == Mode::Batch {
            stream(io, words, |inputs, out| {
                model.evaluate_batch(inputs, full, out)
            })
        } else {
            stream(io, words, |inputs, out| {
                for (input, out) in inputs.iter().zip(out.iter_mut()) {
                    model.evaluate(input, full, out);
                }
            })
        }
    }
}

/// Storage for any model type [`model::visit`] hands out.
#[repr(C, align(8))]
struct ModelStorage(MaybeUninit<[u8; model::MAX_MODEL_BYTES]>);

const _: () = assert!(model::MAX_MODEL_ALIGN <= 8);

static MODEL: Slot<ModelStorage> = Slot::new(ModelStorage(MaybeUninit::uninit()));

/// A fresh `M` in `storage` (the [`MODEL`] slot).
fn place<S: Scalar, M: Model<S>>(storage: &mut ModelStorage) -> &mut M {
    const {
        assert!(size_of::<M>() <= model::MAX_MODEL_BYTES);
        assert!(align_of::<M>() <= 8);
    }
    let slot: *mut M = (storage as *mut ModelStorage).cast();
    // SAFETY: the storage is large and aligned enough for an `M` (checked above, at compile
    // time), the exclusive borrow of it is moved into the returned one, so nothing else
    // refers to it, and it is written before the reference is made.
    unsafe {
        slot.write(M::default());
        &mut *slot
    }
}

/// Results encoded and written to the host at a time.
const WRITE_POINTS: usize = 16;

/// Streams the request's points through `evaluate`, chunk by chunk: each point is decoded to
/// `S` (missing coordinates 0) outside the timed region, the chunk is evaluated inside a timed
/// region, and each result is written as its first `words` words.
fn stream<S: Scalar>(
    io: Io<'_>,
    words: usize,
    mut evaluate: impl FnMut(&[[S; MAX_INPUTS]], &mut [[S; MAX_OUTPUTS]]),
) -> Answer {
    let header = io.header;
    let words = words.min(MAX_OUTPUTS);
    let point_bytes = header.point_bytes();
    let mut raw = [0_u8; CHUNK_POINTS * 4 * MAX_INPUTS];
    let mut inputs = [[S::ZERO; MAX_INPUTS]; CHUNK_POINTS];
    let mut results = [[S::ZERO; MAX_OUTPUTS]; CHUNK_POINTS];
    let mut encoded = [0_u8; WRITE_POINTS * 4 * MAX_OUTPUTS];
    let mut remaining = header.count as usize;
    let mut written = 0_u32;
    while remaining > 0 {
        let n = remaining.min(CHUNK_POINTS);
        let (raw, inputs) = (&mut raw[..n * point_bytes], &mut inputs[..n]);
        if io.request.read_exact(raw).is_err() {
            return Answer::failed(Status::HostIo);
        }
        for (point, bytes) in inputs.iter_mut().zip(raw.chunks_exact(point_bytes)) {
            *point = [S::ZERO; MAX_INPUTS];
            for (c, b) in point.iter_mut().zip(bytes.chunks_exact(4)) {
                *c = S::from_f32_saturating(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            }
        }
        let results = &mut results[..n];
        timed(|| evaluate(inputs, results));
        for results in results.chunks(WRITE_POINTS) {
            let mut len = 0;
            for result in results {
                for v in &result[..words] {
                    encoded[len..len + 4].copy_from_slice(&v.to_le_bytes());
                    len += 4;
                }
            }
            if io.out.write_all(&encoded[..len]).is_err() {
                return Answer::failed(Status::HostIo);
            }
            written += len as u32;
        }
        remaining -= n;
    }
    defmt::info!("evaluated {=u32} points", header.count);
    Answer {
        status: Status::Ok,
        words: words as u8,
        count: header.count,
        bytes: written,
    }
}
