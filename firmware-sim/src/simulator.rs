//! One simulated run: files in, QEMU under a time limit, files and counts out.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use defmt_decoder::Table;
use neurosurf_core::BlobError;
use neurosurf_core::scalar::{Q16, ScalarKind};
use neurosurf_sim_protocol::{
    MAX_ARITY, MODEL_FILE, Mode, Op, REQUEST_FILE, RESULT_FILE, RequestHeader, ResultTrailer,
    Status,
};

use crate::plugin::RegionCount;
use crate::{Firmware, SimError, Toolchain, log, plugin, qemu};

/// Environment variable naming a file that receives the instruction profile of each run
/// (the heaviest translation blocks by executed instructions; overwritten per run).
pub const PROFILE_VARIABLE: &str = "NEUROSURF_SIM_PROFILE";

/// What to run on the target.
#[derive(Copy, Clone, Debug)]
pub struct Job<'a> {
    /// The model blob, as the trainer wrote it.
    pub blob: &'a [u8],
    /// The scalar to evaluate in (any code is sent; the firmware rejects what it lacks).
    pub scalar: ScalarKind,
    /// What to compute.
    pub op: Op,
    /// Single points or lane batches.
    pub mode: Mode,
    /// Query points, `arity` coordinates each, one after the other (rounded to `f32` already,
    /// as the host core receives them).
    pub points: &'a [f32],
    /// Coordinates per point: 3 for implicit models, 1 (t) for curves, 2 (u, v) for spline
    /// surfaces, the source dimension for Cao En networks (at most [`MAX_ARITY`]).
    pub arity: usize,
    /// Wall-clock limit; `None` = 30 s plus 1 ms per point.
    pub time_limit: Option<Duration>,
}

impl<'a> Job<'a> {
    /// Φ and ∇Φ at `points` in lane batches, as `neurosurf eval` does on the host.
    pub fn field_gradient(blob: &'a [u8], scalar: ScalarKind, points: &'a [[f32; 3]]) -> Self {
        Job {
            blob,
            scalar,
            op: Op::FieldGradient,
            mode: Mode::Batch,
            points: points.as_flattened(),
            arity: 3,
            time_limit: None,
        }
    }

    /// The output vector and direction of a parametric model (see [`Op::PositionDirection`]) in
    /// lane batches, at `points` of `arity` coordinates each, one after the other.
    pub fn position_direction(
        blob: &'a [u8],
        scalar: ScalarKind,
        points: &'a [f32],
        arity: usize,
    ) -> Self {
        Job {
            op: Op::PositionDirection,
            points,
            arity,
            ..Self::field_gradient(blob, scalar, &[])
        }
    }

    /// Points in the request.
    pub fn count(&self) -> usize {
        self.points.len() / self.arity.max(1)
    }
}

/// A finished run.
#[derive(Clone, Debug)]
pub struct Run {
    /// The scalar evaluated in.
    pub scalar: ScalarKind,
    /// What was computed.
    pub op: Op,
    /// Single points or batches.
    pub mode: Mode,
    /// Raw result words, [`Run::words_per_point`] per point (`f32` or Q16.16 bits).
    pub words: Vec<u32>,
    /// Words per point: fixed by the op for fields, the model's output width (plus 3 with a
    /// direction) for parametric models.
    pub words_per_point: usize,
    /// Stack high-water mark of the run, in bytes.
    pub stack_bytes: u32,
    /// Instructions and estimated cycles in every timed region; region 0 is empty (the
    /// markers' own cost).
    pub regions: Vec<RegionCount>,
    /// The decoded defmt log.
    pub log: Vec<String>,
}

impl Run {
    /// Points evaluated.
    pub fn count(&self) -> usize {
        self.words.len() / self.words_per_point.max(1)
    }

    /// Result words decoded to `f64` (exact for `f32` and Q16.16).
    pub fn values(&self) -> Vec<f64> {
        self.words
            .iter()
            .map(|&w| match self.scalar {
                ScalarKind::Q16_16 => Q16::from_bits(w as i32).to_num::<f64>(),
                _ => f64::from(f32::from_bits(w)),
            })
            .collect()
    }

    /// (Φ, ∇Φ) per point, as the host's `evaluate` returns them; empty unless the op computed
    /// gradients.
    pub fn samples(&self) -> Vec<(f64, [f64; 3])> {
        if self.op != Op::FieldGradient {
            return Vec::new();
        }
        self.values()
            .chunks_exact(4)
            .map(|c| (c[0], [c[1], c[2], c[3]]))
            .collect()
    }

    /// (outputs, direction) per point of a parametric model — a curve's position and tangent,
    /// a surface's position and normal, a Cao En network's p outputs and normal; empty unless
    /// the op was [`Op::PositionDirection`].
    pub fn geometry(&self) -> Vec<(Vec<f64>, [f64; 3])> {
        if self.op != Op::PositionDirection || self.words_per_point < 3 {
            return Vec::new();
        }
        self.rows()
            .into_iter()
            .map(|mut row| {
                let direction = row.split_off(row.len() - 3);
                (row, [direction[0], direction[1], direction[2]])
            })
            .collect()
    }

    /// The result values of every point, `words_per_point` each, decoded to `f64`.
    pub fn rows(&self) -> Vec<Vec<f64>> {
        self.values()
            .chunks_exact(self.words_per_point.max(1))
            .map(<[f64]>::to_vec)
            .collect()
    }

    /// Guest instructions per evaluated point, the markers' own cost removed: the exact,
    /// deterministic cost of one evaluation (plus its share of the loop around it).
    pub fn instructions_per_point(&self) -> f64 {
        self.per_point(|r| r.instructions)
    }

    /// Estimated Cortex-M4 cycles per evaluated point, the markers' own cost removed: the
    /// instructions priced by the TRM's cycle table (see [`crate::plugin`]); deterministic,
    /// but an estimate, not a measurement of any chip.
    pub fn cycles_per_point(&self) -> f64 {
        self.per_point(|r| r.cycles)
    }

    /// `field` of the timed regions, less that of the empty region 0, per point.
    fn per_point(&self, field: impl Fn(&RegionCount) -> u64) -> f64 {
        let Some((empty, timed)) = self.regions.split_first() else {
            return f64::NAN;
        };
        let empty = field(empty);
        let total: u64 = timed.iter().map(|c| field(c).saturating_sub(empty)).sum();
        total as f64 / self.count().max(1) as f64
    }
}

/// The prepared simulator: toolchain located, firmware and plugin built, defmt table loaded.
#[derive(Clone)]
pub struct Simulator {
    toolchain: Toolchain,
    firmware: Firmware,
    plugin: PathBuf,
    table: Arc<Table>,
}

impl std::fmt::Debug for Simulator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulator")
            .field("toolchain", &self.toolchain)
            .field("firmware", &self.firmware.elf)
            .field("plugin", &self.plugin)
            .finish_non_exhaustive()
    }
}

impl Simulator {
    /// Gets everything ready (finding the toolchain, building the firmware and the plugin
    /// when their sources changed). Done once per process; later calls reuse it.
    ///
    /// # Errors
    /// [`SimError::Setup`], [`SimError::Build`], [`SimError::Elf`].
    pub fn prepare() -> Result<Self, SimError> {
        static PREPARED: Mutex<Option<Simulator>> = Mutex::new(None);
        let mut prepared = PREPARED.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(simulator) = prepared.as_ref() {
            return Ok(simulator.clone());
        }
        let simulator = Self::prepare_in(&crate::repository_root())?;
        *prepared = Some(simulator.clone());
        Ok(simulator)
    }

    /// As [`Simulator::prepare`], for the repository at `root`, without caching.
    ///
    /// # Errors
    /// As [`Simulator::prepare`].
    pub fn prepare_in(root: &Path) -> Result<Self, SimError> {
        let toolchain = Toolchain::find(root)?;
        let firmware = Firmware::build(&toolchain, root)?;
        Self::with_firmware(toolchain, root, firmware)
    }

    /// As [`Simulator::prepare_in`] for the repository this crate is in, with the firmware of
    /// [`Firmware::build_portable`]: the core's kernels named in `portable` turned off. Not
    /// cached: each call rebuilds that firmware, so finish the runs of one before the next.
    ///
    /// # Errors
    /// As [`Simulator::prepare`].
    pub fn prepare_portable(portable: &[&str]) -> Result<Self, SimError> {
        let root = crate::repository_root();
        let toolchain = Toolchain::find(&root)?;
        let firmware = Firmware::build_portable(&toolchain, &root, portable)?;
        Self::with_firmware(toolchain, &root, firmware)
    }

    fn with_firmware(
        toolchain: Toolchain,
        root: &Path,
        firmware: Firmware,
    ) -> Result<Self, SimError> {
        let plugin = plugin::build(&toolchain, root)?;
        let table = log::table(&firmware.elf, &firmware.bytes)?;
        Ok(Simulator {
            toolchain,
            firmware,
            plugin,
            table: Arc::new(table),
        })
    }

    /// The firmware being run.
    pub fn firmware(&self) -> &Firmware {
        &self.firmware
    }

    /// Runs `job` on the simulated Cortex-M4F.
    ///
    /// # Errors
    /// [`SimError::BlobRejected`] with the core's error when the target refuses the blob;
    /// [`SimError::Firmware`] for any other failure status (bad request, panic, HardFault);
    /// [`SimError::Timeout`] when the target hangs; [`SimError::Io`], [`SimError::Protocol`].
    pub fn run(&self, job: &Job<'_>) -> Result<Run, SimError> {
        let dir = tempfile::Builder::new()
            .prefix("neurosurf-sim-")
            .tempdir()
            .map_err(SimError::io(std::env::temp_dir()))?;
        let write = |name: &str, bytes: &[u8]| {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).map_err(SimError::io(path))
        };
        write(MODEL_FILE, job.blob)?;
        let arity = u8::try_from(job.arity)
            .ok()
            .filter(|&a| (1..=MAX_ARITY).contains(&usize::from(a)))
            .ok_or_else(|| {
                SimError::Protocol(format!(
                    "points have 1 to {MAX_ARITY} coordinates, not {}",
                    job.arity
                ))
            })?;
        if !job.points.len().is_multiple_of(job.arity) {
            return Err(SimError::Protocol(format!(
                "{} coordinates do not make points of {}",
                job.points.len(),
                job.arity
            )));
        }
        let count = u32::try_from(job.count()).map_err(|_| {
            SimError::Protocol(format!("{} points is too many for one run", job.count()))
        })?;
        let header = RequestHeader {
            scalar: job.scalar.code(),
            op: job.op,
            mode: job.mode,
            arity,
            count,
        };
        let mut request = header.encode().to_vec();
        for c in job.points {
            request.extend_from_slice(&c.to_le_bytes());
        }
        write(REQUEST_FILE, &request)?;

        let plugin_log = dir.path().join("plugin.log");
        // A development aid: with NEUROSURF_SIM_PROFILE=FILE the plugin also lists the
        // heaviest translation blocks, and its log is copied to FILE.
        let profile_copy = std::env::var_os(PROFILE_VARIABLE).map(PathBuf::from);
        let plugin = format!(
            "{},start={:#x},stop={:#x}{}",
            self.plugin.display(),
            self.firmware.region_start,
            self.firmware.region_stop,
            if profile_copy.is_some() {
                ",profile=1"
            } else {
                ""
            }
        );
        let extra: [OsString; 6] = [
            "-plugin".into(),
            plugin.into(),
            "-d".into(),
            "plugin".into(),
            "-D".into(),
            plugin_log.clone().into(),
        ];
        let limit = job
            .time_limit
            .unwrap_or(Duration::from_secs(30) + Duration::from_millis(job.count() as u64));
        let finished = qemu::run(
            &self.toolchain.qemu,
            &self.firmware.elf,
            dir.path(),
            &extra,
            limit,
        )?;
        let log = log::decode(&self.table, &finished.stdout);
        let Some(status) = finished.status else {
            return Err(SimError::Timeout {
                seconds: limit.as_secs(),
                log,
            });
        };
        let code = status.code().unwrap_or(-1);
        let firmware_failure = |message: String| SimError::Firmware {
            code,
            message,
            log: log.clone(),
        };
        match Status::from_code(code) {
            Some(Status::Ok) => {}
            Some(Status::BlobRejected) => {
                let (answer, _) = read_result(dir.path())?;
                let error = postcard::from_bytes::<BlobError>(&answer)
                    .map_err(|e| SimError::Protocol(format!("undecodable blob error: {e}")))?;
                return Err(SimError::BlobRejected { error });
            }
            Some(other) => return Err(firmware_failure(other.describe().to_string())),
            None => {
                return Err(firmware_failure(qemu::with_stderr(
                    "QEMU failed",
                    &finished.stderr,
                )));
            }
        }
        let (answer, trailer) = read_result(dir.path())?;
        let words_per_point = usize::from(trailer.words);
        let width_ok = job.op.words().is_none_or(|w| w == words_per_point);
        if !width_ok || trailer.count != count || answer.len() != job.count() * words_per_point * 4
        {
            return Err(SimError::Protocol(format!(
                "expected {count} points of {:?} words, got {trailer:?}",
                job.op.words()
            )));
        }
        let words = answer
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let plugin_text =
            std::fs::read_to_string(&plugin_log).map_err(SimError::io(&plugin_log))?;
        if let Some(copy) = profile_copy {
            std::fs::write(&copy, &plugin_text).map_err(SimError::io(&copy))?;
        }
        Ok(Run {
            scalar: job.scalar,
            op: job.op,
            mode: job.mode,
            words,
            words_per_point,
            stack_bytes: trailer.stack_bytes,
            regions: plugin::parse_regions(&plugin_text)?,
            log,
        })
    }
}

/// The answer bytes and the trailer of the result file.
fn read_result(dir: &Path) -> Result<(Vec<u8>, ResultTrailer), SimError> {
    let path = dir.join(RESULT_FILE);
    let mut bytes = std::fs::read(&path).map_err(SimError::io(&path))?;
    let trailer = ResultTrailer::decode(&bytes)
        .map_err(|e| SimError::Protocol(format!("result trailer: {e:?}")))?;
    bytes.truncate(bytes.len() - ResultTrailer::LEN);
    if bytes.len() != trailer.answer_bytes as usize {
        return Err(SimError::Protocol(format!(
            "result has {} answer bytes, trailer says {}",
            bytes.len(),
            trailer.answer_bytes
        )));
    }
    Ok((bytes, trailer))
}
