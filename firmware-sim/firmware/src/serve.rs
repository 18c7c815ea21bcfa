//! One run: read the request and the blob from the host, evaluate, write the answer.

use core::mem::MaybeUninit;

use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::caoen::{CaoEnModel, CaoEnPoint, MAX_TARGET_DIMENSION};
use neurosurf_core::curve::{BSplineCurve, BSplineSurface, CurvePoint};
use neurosurf_core::implicit::{FieldGradient, ImplicitModel};
use neurosurf_core::parametric::{SurfaceNetworkModel, SurfaceNetworkPoint};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use neurosurf_sim_protocol::{
    CHUNK_POINTS, MAX_ARITY, MAX_BLOB_BYTES, MODEL_FILE, Mode, Op, REQUEST_FILE, RESULT_FILE,
    RequestHeader, ResultTrailer, Status,
};

use crate::regions::timed;
use crate::semihosting::HostFile;
use crate::slot::Slot;
use crate::stack;

// A request point is a Cao En source point at its widest, and a result fits `stream`'s buffer.
const _: () = assert!(MAX_ARITY == neurosurf_core::caoen::MAX_SOURCE_DIMENSION);

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
    let scalar = ScalarKind::from_code(header.scalar);
    if !matches!(scalar, Some(ScalarKind::F32 | ScalarKind::Q16_16)) {
        defmt::error!(
            "scalar code {=u8} is not evaluated on the target",
            header.scalar
        );
        return Answer::failed(Status::BadRequest);
    }
    let q16 = scalar == Some(ScalarKind::Q16_16);
    let parametric = matches!(
        model,
        ModelKind::Curve | ModelKind::SplineSurface | ModelKind::CaoEn | ModelKind::SurfaceNetwork
    );
    let served = parametric || model == ModelKind::Implicit;
    if served && header.op.is_parametric() != parametric {
        defmt::error!(
            "op {=u8} does not apply to {=str} models",
            header.op as u8,
            model.name()
        );
        return Answer::failed(Status::BadRequest);
    }
    let io = Io {
        header: &header,
        request: &mut request,
        out,
    };
    match (model, q16) {
        (ModelKind::Implicit, false) => serve_implicit(&IMPLICIT_F32, blob, io),
        (ModelKind::Implicit, true) => serve_implicit(&IMPLICIT_Q16, blob, io),
        (ModelKind::Curve, false) => serve_curve::<f32>(blob, io),
        (ModelKind::Curve, true) => serve_curve::<Q16>(blob, io),
        (ModelKind::SplineSurface, false) => serve_surface::<f32>(blob, io),
        (ModelKind::SplineSurface, true) => serve_surface::<Q16>(blob, io),
        (ModelKind::CaoEn, false) => serve_caoen::<f32>(blob, io),
        (ModelKind::CaoEn, true) => serve_caoen::<Q16>(blob, io),
        (ModelKind::SurfaceNetwork, false) => serve_network::<f32>(blob, io),
        (ModelKind::SurfaceNetwork, true) => serve_network::<Q16>(blob, io),
        // The RBF baseline is evaluated by the host trainer only.
        (ModelKind::Rbf, _) => reject(
            io.out,
            BlobError::WrongModelKind {
                expected: ModelKind::Implicit,
                found: ModelKind::Rbf,
            },
        ),
    }
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

/// Loads an implicit model in place (in its static slot: no stack copy of the 32 KiB
/// parameters) and streams the points through it.
fn serve_implicit<S: Scalar>(
    slot: &'static Slot<MaybeUninit<ImplicitModel<S>>>,
    blob: &[u8],
    io: Io<'_>,
) -> Answer {
    let Some(slot) = slot.take() else {
        return Answer::failed(Status::HostIo);
    };
    let model = slot.write(ImplicitModel::new());
    if let Err(e) = model.load(blob) {
        return reject(io.out, e);
    }
    defmt::info!(
        "implicit model: {=usize} modules, width {=usize}, {=usize} parameters, {=usize} MACs per field+gradient",
        model.module_count(),
        model.width(),
        model.parameter_count(),
        model.mac_count(true)
    );
    let model = &*model;
    let point = |p: [S; MAX_ARITY]| [p[0], p[1], p[2]];
    match (io.header.op, io.header.mode) {
        (Op::Field, Mode::Batch) => stream(
            io,
            1,
            point,
            |p, out| model.field_batch(p, out).is_ok(),
            |v: &S| [*v],
        ),
        (Op::Field, _) => stream(
            io,
            1,
            point,
            |p, out| each(p, out, |&p| model.field(p)),
            |v: &S| [*v],
        ),
        (_, Mode::Batch) => stream(
            io,
            4,
            point,
            |p, out| model.field_gradient_batch(p, out).is_ok(),
            field_gradient_words,
        ),
        _ => stream(
            io,
            4,
            point,
            |p, out| each(p, out, |&p| model.field_gradient(p)),
            field_gradient_words,
        ),
    }
}

/// Loads a curve (on the stack: at most 6 KiB) and streams the parameters t through it.
#[inline(never)]
fn serve_curve<S: Scalar>(blob: &[u8], io: Io<'_>) -> Answer {
    let mut curve = BSplineCurve::<S>::new();
    if let Err(e) = curve.load(blob) {
        return reject(io.out, e);
    }
    defmt::info!(
        "curve: dimension {=usize}, {=usize} control points, {=usize} segments",
        curve.dimension(),
        curve.control_count(),
        curve.segments()
    );
    let curve = &curve;
    let t = |p: [S; MAX_ARITY]| p[0];
    match (io.header.op, io.header.mode) {
        (Op::Position, Mode::Batch) => stream(
            io,
            3,
            t,
            |t, out| curve.position_batch(t, out).is_ok(),
            |p: &[S; 3]| *p,
        ),
        (Op::Position, _) => stream(
            io,
            3,
            t,
            |t, out| each(t, out, |&t| curve.position(t)),
            |p: &[S; 3]| *p,
        ),
        (_, Mode::Batch) => stream(
            io,
            6,
            t,
            |t, out| curve.eval_batch(t, out).is_ok(),
            curve_words,
        ),
        _ => stream(
            io,
            6,
            t,
            |t, out| each(t, out, |&t| curve.eval(t)),
            curve_words,
        ),
    }
}

/// Loads a spline surface (on the stack: at most 12 KiB) and streams the parameters (u, v)
/// through it.
#[inline(never)]
fn serve_surface<S: Scalar>(blob: &[u8], io: Io<'_>) -> Answer {
    let mut surface = BSplineSurface::<S>::new();
    if let Err(e) = surface.load(blob) {
        return reject(io.out, e);
    }
    let [count_u, count_v] = surface.counts();
    defmt::info!(
        "spline surface: {=usize} × {=usize} control points",
        count_u,
        count_v
    );
    let surface = &surface;
    let uv = |p: [S; MAX_ARITY]| [p[0], p[1]];
    match (io.header.op, io.header.mode) {
        (Op::Position, Mode::Batch) => stream(
            io,
            3,
            uv,
            |uv, out| surface.position_batch(uv, out).is_ok(),
            |p: &[S; 3]| *p,
        ),
        (Op::Position, _) => stream(
            io,
            3,
            uv,
            |uv, out| each(uv, out, |&uv| surface.position(uv)),
            |p: &[S; 3]| *p,
        ),
        (_, Mode::Batch) => stream(
            io,
            6,
            uv,
            |uv, out| surface_batch(surface, uv, out),
            surface_words,
        ),
        _ => stream(
            io,
            6,
            uv,
            |uv, out| each(uv, out, |&uv| (surface.position(uv), surface.normal(uv))),
            surface_words,
        ),
    }
}

/// Loads a surface network (on the stack: at most 5 KiB) and streams the parameters (u, v)
/// through it: the position, then (for `PositionDirection`) the unit normal.
#[inline(never)]
fn serve_network<S: Scalar>(blob: &[u8], io: Io<'_>) -> Answer {
    let mut network = SurfaceNetworkModel::<S>::new();
    if let Err(e) = network.load(blob) {
        return reject(io.out, e);
    }
    defmt::info!(
        "surface network: hidden layers {=[u8]}, {=usize} MACs per position+normal",
        network.hidden_sizes(),
        network.mac_count(true)
    );
    let network = &network;
    let uv = |p: [S; MAX_ARITY]| [p[0], p[1]];
    let words = |p: &SurfaceNetworkPoint<S>| surface_words(&(p.position, p.normal));
    match (io.header.op, io.header.mode) {
        (Op::Position, Mode::Batch) => stream(
            io,
            3,
            uv,
            |uv, out| network.position_batch(uv, out).is_ok(),
            |p: &[S; 3]| *p,
        ),
        (Op::Position, _) => stream(
            io,
            3,
            uv,
            |uv, out| each(uv, out, |&uv| network.position(uv)),
            |p: &[S; 3]| *p,
        ),
        (_, Mode::Batch) => stream(
            io,
            6,
            uv,
            |uv, out| network.eval_batch(uv, out).is_ok(),
            words,
        ),
        _ => stream(
            io,
            6,
            uv,
            |uv, out| each(uv, out, |&uv| network.eval(uv)),
            words,
        ),
    }
}

/// Loads a Cao En network (on the stack: at most 19 KiB) and streams the source points
/// through it: every output, then (for `PositionDirection`) the unit normal.
#[inline(never)]
fn serve_caoen<S: Scalar>(blob: &[u8], io: Io<'_>) -> Answer {
    let mut network = CaoEnModel::<S>::new();
    if let Err(e) = network.load(blob) {
        return reject(io.out, e);
    }
    let p = network.target_dimension();
    defmt::info!(
        "Cao En network: {=usize} key points, {=usize} → {=usize} dimensions",
        network.key_count(),
        network.source_dimension(),
        p
    );
    let network = &network;
    let x = |x: [S; MAX_ARITY]| x;
    let outputs = |y: &[S; MAX_TARGET_DIMENSION]| *y;
    match (io.header.op, io.header.mode) {
        (Op::Position, Mode::Batch) => stream(
            io,
            p,
            x,
            |x, out| network.eval_batch(x, out).is_ok(),
            outputs,
        ),
        (Op::Position, _) => stream(
            io,
            p,
            x,
            |x, out| each(x, out, |x| network.eval(x)),
            outputs,
        ),
        (_, Mode::Batch) => stream(
            io,
            p + 3,
            x,
            |x, out| caoen_batch(network, x, out),
            caoen_words(p),
        ),
        _ => stream(
            io,
            p + 3,
            x,
            |x, out| each(x, out, |x| caoen_single(network, x)),
            caoen_words(p),
        ),
    }
}

/// Every output and the unit normal of every source point, through the network's batch calls:
/// one pass with the Jacobian for a shape (p = 3, whose position comes with the normal), one
/// without for other networks (which have no normal).
fn caoen_batch<S: Scalar>(
    network: &CaoEnModel<S>,
    x: &[[S; MAX_ARITY]],
    out: &mut [CaoEnResult<S>],
) -> bool {
    if network.target_dimension() == 3 {
        let mut points = [CaoEnPoint::default(); CHUNK_POINTS];
        let Some(points) = points.get_mut(..x.len()) else {
            return false;
        };
        if network.eval_normal_batch(x, points).is_err() {
            return false;
        }
        for (slot, point) in out.iter_mut().zip(points.iter()) {
            *slot = caoen_result(point);
        }
    } else {
        let mut outputs = [[S::ZERO; MAX_TARGET_DIMENSION]; CHUNK_POINTS];
        let Some(outputs) = outputs.get_mut(..x.len()) else {
            return false;
        };
        if network.eval_batch(x, outputs).is_err() {
            return false;
        }
        for (slot, &y) in out.iter_mut().zip(outputs.iter()) {
            *slot = (y, None);
        }
    }
    true
}

/// One source point, as [`caoen_batch`] computes it.
fn caoen_single<S: Scalar>(network: &CaoEnModel<S>, x: &[S; MAX_ARITY]) -> CaoEnResult<S> {
    if network.target_dimension() == 3 {
        caoen_result(&network.eval_normal(x))
    } else {
        (network.eval(x), None)
    }
}

/// A shape's position and normal as the eight-output result.
fn caoen_result<S: Scalar>(point: &CaoEnPoint<S>) -> CaoEnResult<S> {
    let mut y = [S::ZERO; MAX_TARGET_DIMENSION];
    for (slot, &v) in y.iter_mut().zip(&point.position) {
        *slot = v;
    }
    (y, point.normal)
}

/// A Cao En network's outputs and unit normal at one source point.
type CaoEnResult<S> = ([S; MAX_TARGET_DIMENSION], Option<[S; 3]>);

/// The p outputs, then the normal (0, 0, 0 where it does not exist).
fn caoen_words<S: Scalar>(p: usize) -> impl Fn(&CaoEnResult<S>) -> [S; MAX_TARGET_DIMENSION + 3] {
    move |(y, normal)| {
        let mut words = [S::ZERO; MAX_TARGET_DIMENSION + 3];
        let normal = normal.unwrap_or([S::ZERO; 3]);
        for (word, &v) in words.iter_mut().zip(y.iter().take(p).chain(&normal)) {
            *word = v;
        }
        words
    }
}

/// Position and normal of every `uv`, through the surface's batch calls.
fn surface_batch<S: Scalar>(
    surface: &BSplineSurface<S>,
    uv: &[[S; 2]],
    out: &mut [([S; 3], Option<[S; 3]>)],
) -> bool {
    let mut positions = [[S::ZERO; 3]; CHUNK_POINTS];
    let mut normals = [None; CHUNK_POINTS];
    let (Some(positions), Some(normals)) =
        (positions.get_mut(..uv.len()), normals.get_mut(..uv.len()))
    else {
        return false;
    };
    if surface.position_batch(uv, positions).is_err() || surface.normal_batch(uv, normals).is_err()
    {
        return false;
    }
    for ((slot, &p), &n) in out.iter_mut().zip(positions.iter()).zip(normals.iter()) {
        *slot = (p, n);
    }
    true
}

fn field_gradient_words<S: Scalar>(fg: &FieldGradient<S>) -> [S; 4] {
    [fg.value, fg.gradient[0], fg.gradient[1], fg.gradient[2]]
}

fn curve_words<S: Scalar>(point: &CurvePoint<S>) -> [S; 6] {
    let ([x, y, z], [tx, ty, tz]) = (point.position, point.tangent);
    [x, y, z, tx, ty, tz]
}

fn surface_words<S: Scalar>(&(position, normal): &([S; 3], Option<[S; 3]>)) -> [S; 6] {
    let ([x, y, z], [nx, ny, nz]) = (position, normal.unwrap_or([S::ZERO; 3]));
    [x, y, z, nx, ny, nz]
}

/// The single-point path: `f` at every input, in order.
fn each<I, R>(inputs: &[I], out: &mut [R], f: impl Fn(&I) -> R) -> bool {
    for (slot, input) in out.iter_mut().zip(inputs) {
        *slot = f(input);
    }
    true
}

/// Streams the request's points through `evaluate`, chunk by chunk: each point is decoded to
/// `S` (missing coordinates 0) and turned into the model's input by `input` (outside the timed
/// region), the chunk is evaluated inside a timed region, and each result is written as the
/// first `words` (≤ `W`) words of `encode`.
fn stream<S: Scalar, I: Copy + Default, R: Copy + Default, const W: usize>(
    io: Io<'_>,
    words: usize,
    input: impl Fn([S; MAX_ARITY]) -> I,
    mut evaluate: impl FnMut(&[I], &mut [R]) -> bool,
    encode: impl Fn(&R) -> [S; W],
) -> Answer {
    let header = io.header;
    let words = words.min(W);
    let point_bytes = header.point_bytes();
    let mut raw = [0_u8; CHUNK_POINTS * 4 * MAX_ARITY];
    let mut inputs = [I::default(); CHUNK_POINTS];
    let mut results = [R::default(); CHUNK_POINTS];
    let mut encoded = [0_u8; CHUNK_POINTS * 4 * (MAX_TARGET_DIMENSION + 3)];
    let mut remaining = header.count as usize;
    let mut written = 0_u32;
    while remaining > 0 {
        let n = remaining.min(CHUNK_POINTS);
        let (raw, inputs) = (&mut raw[..n * point_bytes], &mut inputs[..n]);
        if io.request.read_exact(raw).is_err() {
            return Answer::failed(Status::HostIo);
        }
        for (slot, bytes) in inputs.iter_mut().zip(raw.chunks_exact(point_bytes)) {
            let mut point = [S::ZERO; MAX_ARITY];
            for (c, b) in point.iter_mut().zip(bytes.chunks_exact(4)) {
                *c = S::from_f32_saturating(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            }
            *slot = input(point);
        }
        let results = &mut results[..n];
        if !timed(|| evaluate(inputs, results)) {
            return Answer::failed(Status::BadRequest);
        }
        let mut len = 0;
        for result in results.iter() {
            for v in encode(result).into_iter().take(words) {
                encoded[len..len + 4].copy_from_slice(&v.to_le_bytes());
                len += 4;
            }
        }
        if io.out.write_all(&encoded[..len]).is_err() {
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
