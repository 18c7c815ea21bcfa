//! The simulated Cortex-M4F (`neurosurf-firmware-sim`), for the commands that run models on it.

use std::path::Path;

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::model::{self, Model, ModelVisitor};
use neurosurf_core::scalar::{Scalar, ScalarKind};
use neurosurf_firmware_sim::{Job, Mode, Op, Run, Simulator};
use neurosurf_trainer::evaluate::Precision;

/// Single points or lane batches, on the command line.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum ModeArg {
    /// `field_gradient_batch`: 8 points per pass.
    Batch,
    /// `field_gradient`: one point at a time.
    Single,
}

impl ModeArg {
    pub fn mode(self) -> Mode {
        match self {
            ModeArg::Batch => Mode::Batch,
            ModeArg::Single => Mode::Single,
        }
    }
}

/// `batch` or `single`.
pub fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Single => "single",
        _ => "batch",
    }
}

/// `field` or `field+gradient`.
pub fn op_name(op: Op) -> &'static str {
    match op {
        Op::Field => "field",
        Op::FieldGradient => "field+gradient",
        Op::Position => "position",
        Op::PositionDirection => "position+direction",
        _ => "self-test",
    }
}

/// The simulator, ready (the toolchain found and the firmware built on first use).
pub fn simulator() -> Result<Simulator> {
    Simulator::prepare().context("cannot prepare the simulated Cortex-M4F")
}

/// A simulator whose firmware runs the core's portable loops instead of the Cortex-M4F kernels
/// named in `kernels` (built anew on every call).
pub fn portable_simulator(kernels: &[&str]) -> Result<Simulator> {
    Simulator::prepare_portable(kernels).with_context(|| {
        format!(
            "cannot prepare the simulated Cortex-M4F without the kernels {}",
            kernels.join(", ")
        )
    })
}

/// The target scalar for `precision`; the target has no `f64`.
pub fn scalar(precision: Precision) -> Result<ScalarKind> {
    match precision {
        Precision::F32 => Ok(ScalarKind::F32),
        Precision::Q16 => Ok(ScalarKind::Q16_16),
        Precision::F64 => bail!(
            "the target has no f64: the Cortex-M4F evaluates in f32 or q16.16 (use `neurosurf \
             eval --scalar f64` for the trainer's f64 reference)"
        ),
    }
}

/// Reads a blob to send to the target. Host-only model kinds are refused here; a blob that
/// does not even parse is returned as it is, so the target reports what its core sees.
pub fn read_blob(path: &Path) -> Result<Vec<u8>> {
    let bytes =
        std::fs::read(path).with_context(|| format!("cannot read the model {}", path.display()))?;
    if let Ok((header, _)) = blob::parse(&bytes)
        && header.model == ModelKind::Rbf
    {
        bail!(
            "{}: {} is a host-only model kind: the target evaluates implicit models, curves, \
             spline surfaces, Cao En networks and surface networks (use `neurosurf eval`)",
            path.display(),
            header.model.name()
        );
    }
    Ok(bytes)
}

/// Runs `job` on the target; errors name the model file and carry the target's own report.
pub fn run(simulator: &Simulator, job: &Job<'_>, model: &Path) -> Result<Run> {
    simulator.run(job).with_context(|| {
        format!(
            "{} ({}, {}, {}) on the simulated Cortex-M4F",
            model.display(),
            job.scalar.name(),
            op_name(job.op),
            mode_name(job.mode)
        )
    })
}

/// Multiply–accumulates of one evaluation of the blob in `scalar`, as the host's core counts
/// them ([`Model::mac_count`]): the value alone, or with its derivative (gradient, tangent or
/// normal).
pub fn mac_count(
    bytes: &[u8],
    scalar: ScalarKind,
    derivative: bool,
    model: &Path,
) -> Result<usize> {
    let kind = blob::parse(bytes)
        .map(|(header, _)| header.model)
        .with_context(|| format!("{}: not a model blob", model.display()))?;
    let Some(count) = model::visit(kind, scalar, MacCount { bytes, derivative }) else {
        bail!(
            "{}: a {} model does not run on the target in {} (RBF models run on the host only)",
            model.display(),
            kind.name(),
            scalar.name()
        );
    };
    count.with_context(|| {
        format!(
            "{}: the core cannot load it in {}",
            model.display(),
            scalar.name()
        )
    })
}

/// [`mac_count`] for the model type the blob names.
struct MacCount<'a> {
    bytes: &'a [u8],
    derivative: bool,
}

impl ModelVisitor for MacCount<'_> {
    type Output = Result<usize, BlobError>;
    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
        let mut model = Box::<M>::default();
        model.load_blob(self.bytes)?;
        Ok(model.mac_count(self.derivative))
    }
}
