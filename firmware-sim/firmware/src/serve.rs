//! One run: read the request and the blob from the host, evaluate, write the answer.

use core::mem::MaybeUninit;

use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::implicit::{FieldGradient, ImplicitModel};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use neurosurf_sim_protocol::{
    CHUNK_POINTS, MAX_BLOB_BYTES, MODEL_FILE, Mode, Op, REQUEST_FILE, RESULT_FILE, RequestHeader,
    ResultTrailer, Status,
};

use crate::regions::timed;
use crate::semihosting::HostFile;
use crate::slot::Slot;
use crate::stack;

static BLOB: Slot<[u8; MAX_BLOB_BYTES]> = Slot::new([0; MAX_BLOB_BYTES]);
static IMPLICIT_F32: Slot<MaybeUninit<ImplicitModel<f32>>> = Slot::new(MaybeUninit::uninit());
static IMPLICIT_Q16: Slot<MaybeUninit<ImplicitModel<Q16>>> = Slot::new(MaybeUninit::uninit());

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
        RequestHeader::LEN as u64 + u64::from(header.count) * RequestHeader::POINT_BYTES as u64;
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
    let model = match blob::parse(blob) {
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
    match (model, ScalarKind::from_code(header.scalar)) {
        (ModelKind::Implicit, Some(ScalarKind::F32)) => {
            serve_implicit(&IMPLICIT_F32, blob, &header, &mut request, out)
        }
        (ModelKind::Implicit, Some(ScalarKind::Q16_16)) => {
            serve_implicit(&IMPLICIT_Q16, blob, &header, &mut request, out)
        }
        (ModelKind::Implicit, _) => {
            defmt::error!(
                "scalar code {=u8} is not evaluated on the target",
                header.scalar
            );
            Answer::failed(Status::BadRequest)
        }
        (other, _) => reject(
            out,
            BlobError::WrongModelKind {
                expected: ModelKind::Implicit,
                found: other,
            },
        ),
    }
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

/// Loads an implicit model in place (in its static slot: no stack copy of the 32 KiB
/// parameters) and streams the points through it, chunk by chunk.
fn serve_implicit<S: Scalar>(
    slot: &'static Slot<MaybeUninit<ImplicitModel<S>>>,
    blob: &[u8],
    header: &RequestHeader,
    request: &mut HostFile,
    out: &mut HostFile,
) -> Answer {
    let Some(slot) = slot.take() else {
        return Answer::failed(Status::HostIo);
    };
    let model = slot.write(ImplicitModel::new());
    if let Err(e) = model.load(blob) {
        return reject(out, e);
    }
    defmt::info!(
        "implicit model: {=usize} modules, width {=usize}, {=usize} parameters, {=usize} MACs per field+gradient",
        model.module_count(),
        model.width(),
        model.parameter_count(),
        model.mac_count(true)
    );
    let words = header.op.words();
    let mut raw = [0_u8; CHUNK_POINTS * RequestHeader::POINT_BYTES];
    let mut points = [[S::ZERO; 3]; CHUNK_POINTS];
    let mut results = [FieldGradient::<S>::default(); CHUNK_POINTS];
    let mut fields = [S::ZERO; CHUNK_POINTS];
    let mut encoded = [0_u8; CHUNK_POINTS * 16];
    let mut remaining = header.count as usize;
    let mut written = 0_u32;
    while remaining > 0 {
        let n = remaining.min(CHUNK_POINTS);
        let (raw, points) = (&mut raw[..n * RequestHeader::POINT_BYTES], &mut points[..n]);
        if request.read_exact(raw).is_err() {
            return Answer::failed(Status::HostIo);
        }
        for (point, bytes) in points.iter_mut().zip(raw.chunks_exact(4 * 3)) {
            for (c, b) in point.iter_mut().zip(bytes.chunks_exact(4)) {
                let word = [b[0], b[1], b[2], b[3]];
                *c = S::from_f32_saturating(f32::from_le_bytes(word));
            }
        }
        let (results, fields) = (&mut results[..n], &mut fields[..n]);
        let evaluated = match (header.op, header.mode) {
            (Op::Field, Mode::Batch) => timed(|| model.field_batch(points, fields)).is_ok(),
            (Op::Field, _) => {
                timed(|| {
                    for (slot, &p) in fields.iter_mut().zip(points.iter()) {
                        *slot = model.field(p);
                    }
                });
                true
            }
            (_, Mode::Batch) => timed(|| model.field_gradient_batch(points, results)).is_ok(),
            _ => {
                timed(|| {
                    for (slot, &p) in results.iter_mut().zip(points.iter()) {
                        *slot = model.field_gradient(p);
                    }
                });
                true
            }
        };
        if !evaluated {
            return Answer::failed(Status::BadRequest);
        }
        let mut len = 0;
        for i in 0..n {
            let values: &[S] = if words == 1 {
                core::slice::from_ref(&fields[i])
            } else {
                let fg = &results[i];
                &[fg.value, fg.gradient[0], fg.gradient[1], fg.gradient[2]]
            };
            for v in values {
                encoded[len..len + 4].copy_from_slice(&v.to_le_bytes());
                len += 4;
            }
        }
        if out.write_all(&encoded[..len]).is_err() {
            return Answer::failed(Status::HostIo);
        }
        written += len as u32;
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
