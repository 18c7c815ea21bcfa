//! The simulated Cortex-M4F (`neurosurf-firmware-sim`), for the commands that run models on it.

use std::path::Path;

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::caoen::CaoEnModel;
use neurosurf_core::curve::{BSplineCurve, BSplineSurface};
use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::parametric::SurfaceNetworkModel;
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
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
/// them: with the gradient or not (implicit models), with the tangent or not (curves), with
/// the normal or not (spline surfaces, Cao En networks, surface networks).
pub fn mac_count(
    bytes: &[u8],
    scalar: ScalarKind,
    derivative: bool,
    model: &Path,
) -> Result<usize> {
    let kind = blob::parse(bytes).map(|(header, _)| header.model);
    let count = match (kind, scalar) {
        (Ok(ModelKind::Curve), ScalarKind::Q16_16) => {
            BSplineCurve::<Q16>::from_blob(bytes).map(|c| c.mac_count(derivative))
        }
        (Ok(ModelKind::Curve), _) => {
            BSplineCurve::<f32>::from_blob(bytes).map(|c| c.mac_count(derivative))
        }
        (Ok(ModelKind::SplineSurface), ScalarKind::Q16_16) => {
            BSplineSurface::<Q16>::from_blob(bytes).map(|s| surface_macs(&s, derivative))
        }
        (Ok(ModelKind::SplineSurface), _) => {
            BSplineSurface::<f32>::from_blob(bytes).map(|s| surface_macs(&s, derivative))
        }
        (Ok(ModelKind::CaoEn), ScalarKind::Q16_16) => {
            CaoEnModel::<Q16>::from_blob(bytes).map(|m| m.mac_count(derivative))
        }
        (Ok(ModelKind::CaoEn), _) => {
            CaoEnModel::<f32>::from_blob(bytes).map(|m| m.mac_count(derivative))
        }
        (Ok(ModelKind::SurfaceNetwork), ScalarKind::Q16_16) => {
            SurfaceNetworkModel::<Q16>::from_blob(bytes).map(|m| m.mac_count(derivative))
        }
        (Ok(ModelKind::SurfaceNetwork), _) => {
            SurfaceNetworkModel::<f32>::from_blob(bytes).map(|m| m.mac_count(derivative))
        }
        (Ok(ModelKind::Implicit), ScalarKind::Q16_16) => {
            ImplicitModel::<Q16>::from_blob(bytes).map(|m| m.mac_count(derivative))
        }
        (Ok(ModelKind::Implicit), _) => {
            ImplicitModel::<f32>::from_blob(bytes).map(|m| m.mac_count(derivative))
        }
        (Ok(ModelKind::Rbf), _) => bail!(
            "{}: an RBF model runs on the host only (the core has no RBF evaluator)",
            model.display()
        ),
        (Err(e), _) => Err(e),
    };
    count.with_context(|| {
        format!(
            "{}: the core cannot load it in {}",
            model.display(),
            scalar.name()
        )
    })
}

/// A surface's position, plus its normal when asked (what the target's
/// position+direction op computes).
fn surface_macs<S: Scalar>(surface: &BSplineSurface<S>, normal: bool) -> usize {
    surface.mac_count(false)
        + if normal {
            surface.normal_mac_count()
        } else {
            0
        }
}
