//! `neurosurf info`: what a blob holds.

use std::path::PathBuf;

use anyhow::Result;
use neurosurf_core::blob::ModelKind;
use serde::Serialize;

use neurosurf_trainer::curve::FitSummary;
use neurosurf_trainer::evaluate::LoadedModel;
use neurosurf_trainer::implicit::TrainingSummary;
use neurosurf_trainer::parametric::NetworkSummary;
use neurosurf_trainer::rbf::RbfModel;

use super::output;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob.
    model: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Default, Serialize)]
struct Info<'a> {
    kind: &'static str,
    stored_as: &'static str,
    blob_bytes: usize,
    parameters: usize,
    width: Option<usize>,
    tree: Option<String>,
    modules: Option<usize>,
    leaves: Option<usize>,
    /// Implicit models: sign guards added to the root's output.
    guards: Option<usize>,
    /// Implicit models: where the model's coordinates sit among the user's,
    /// `model = (x − origin) · 2^shift`.
    frame: Option<FrameInfo>,
    /// Multiply–accumulates of one field evaluation and of one field+gradient evaluation.
    macs: Option<(usize, usize)>,
    centers: Option<usize>,
    training: Option<&'a TrainingSummary>,
    /// Curves and surfaces: the control net, e.g. `12, closed` or `8 × 6, open × open`.
    control: Option<String>,
    fit: Option<&'a FitSummary>,
    /// Surface networks: how the network was fitted.
    network_fit: Option<&'a NetworkSummary>,
}

#[derive(Serialize)]
struct FrameInfo {
    origin: [f32; 3],
    shift: i8,
}

pub fn run(args: &Args) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    let info = match &model {
        LoadedModel::Implicit { bytes, decoded } => {
            let net = &decoded.network;
            let core = neurosurf_core::implicit::ImplicitModel::<f32>::from_blob(bytes).ok();
            let macs = core
                .as_ref()
                .map(|m| (m.mac_count(false), m.mac_count(true)));
            let frame = core.as_ref().map(|m| FrameInfo {
                origin: m.frame().origin(),
                shift: m.frame().shift(),
            });
            Info {
                kind: "implicit",
                stored_as: decoded.stored_as.name(),
                blob_bytes: bytes.len(),
                parameters: net.params().len(),
                width: Some(net.width()),
                tree: Some(net.tree().to_string()),
                modules: Some(net.module_count()),
                leaves: Some(net.subtree_leaves(net.root()).len()),
                guards: Some(net.guards().len()),
                frame,
                macs,
                training: decoded.metadata.as_ref().and_then(|m| m.summary.as_ref()),
                ..Info::default()
            }
        }
        LoadedModel::Rbf(rbf) => Info {
            kind: "rbf",
            stored_as: "f64",
            blob_bytes: std::fs::metadata(&args.model).map_or(0, |m| m.len() as usize),
            parameters: rbf.parameter_count(),
            centers: Some(RbfModel::centers(rbf).len()),
            ..Info::default()
        },
        LoadedModel::Curve { bytes, decoded } => {
            let curve = &decoded.curve;
            let core = neurosurf_core::curve::BSplineCurve::<f32>::from_blob(bytes).ok();
            Info {
                kind: ModelKind::Curve.name(),
                stored_as: decoded.stored_as.name(),
                blob_bytes: bytes.len(),
                parameters: curve.control.len() * 3,
                macs: core.map(|c| (c.mac_count(false), c.mac_count(true))),
                control: Some(format!(
                    "{} points, {}-D, {}, {} segments",
                    curve.control.len(),
                    curve.dimension,
                    open_or_closed(curve.closed),
                    curve.segments()
                )),
                fit: decoded.summary.as_ref(),
                ..Info::default()
            }
        }
        LoadedModel::SplineSurface { bytes, decoded } => {
            let surface = &decoded.surface;
            let core = neurosurf_core::curve::BSplineSurface::<f32>::from_blob(bytes).ok();
            Info {
                kind: ModelKind::SplineSurface.name(),
                stored_as: decoded.stored_as.name(),
                blob_bytes: bytes.len(),
                parameters: surface.control.len() * 3,
                macs: core.map(|c| {
                    (
                        c.mac_count(false),
                        c.mac_count(false) + c.normal_mac_count(),
                    )
                }),
                control: Some(format!(
                    "{} × {} points, {} × {}",
                    surface.count_u,
                    surface.count_v,
                    open_or_closed(surface.closed_u),
                    open_or_closed(surface.closed_v)
                )),
                fit: decoded.summary.as_ref(),
                ..Info::default()
            }
        }
        LoadedModel::SurfaceNetwork { bytes, decoded } => {
            let network = &decoded.network;
            let core =
                neurosurf_core::parametric::SurfaceNetworkModel::<f32>::from_blob(bytes).ok();
            let hidden: Vec<String> = network
                .hidden_sizes()
                .iter()
                .map(usize::to_string)
                .collect();
            Info {
                kind: ModelKind::SurfaceNetwork.name(),
                stored_as: decoded.stored_as.name(),
                blob_bytes: bytes.len(),
                parameters: network.parameter_count(),
                macs: core.map(|c| (c.mac_count(false), c.mac_count(true))),
                control: Some(format!(
                    "hidden layers {} ({}), (u, v) in [{:.4}, {:.4}] × [{:.4}, {:.4}]",
                    hidden.join(" × "),
                    network.activation.name(),
                    network.input_center[0] - network.input_scale[0],
                    network.input_center[0] + network.input_scale[0],
                    network.input_center[1] - network.input_scale[1],
                    network.input_center[1] + network.input_scale[1],
                )),
                network_fit: decoded.summary.as_ref(),
                ..Info::default()
            }
        }
        LoadedModel::CaoEn { bytes, decoded } => {
            let network = &decoded.network;
            let core = neurosurf_core::caoen::CaoEnModel::<f32>::from_blob(bytes).ok();
            Info {
                kind: ModelKind::CaoEn.name(),
                stored_as: decoded.stored_as.name(),
                blob_bytes: bytes.len(),
                parameters: network.key_count()
                    * (network.source_dimension() + network.target_dimension() + 1),
                macs: core
                    .as_ref()
                    .map(|c| (c.mac_count(false), c.mac_count(true))),
                control: core.map(|c| {
                    format!(
                        "{} key points, {:?} {}-D → {}-D, {:?} blending{}",
                        c.key_count(),
                        c.domain(),
                        c.source_dimension(),
                        c.target_dimension(),
                        c.blending(),
                        if c.is_normalized() {
                            ", normalized"
                        } else {
                            ""
                        }
                    )
                }),
                ..Info::default()
            }
        }
    };
    if args.json {
        return output::json(&info);
    }
    println!("{}: {} model", args.model.display(), info.kind);
    println!("  stored as    {}", info.stored_as);
    println!("  blob         {} bytes", info.blob_bytes);
    println!("  parameters   {}", info.parameters);
    if let (Some(width), Some(tree)) = (info.width, &info.tree) {
        println!(
            "  tree         {tree} ({} modules, {} leaves, width {width})",
            info.modules.unwrap_or(0),
            info.leaves.unwrap_or(0)
        );
    }
    if let Some(guards) = info.guards.filter(|&g| g > 0) {
        println!("  sign guards  {guards}");
    }
    if let Some(FrameInfo { origin, shift }) = &info.frame {
        println!(
            "  frame        model = (x − ({}, {}, {})) · 2^{shift}",
            origin[0], origin[1], origin[2]
        );
    }
    if let Some(control) = &info.control {
        println!("  control      {control}");
    }
    if let Some((value, derivative)) = info.macs {
        match model.kind() {
            ModelKind::Curve => {
                println!("  MACs         {value} per position, {derivative} per position+tangent")
            }
            ModelKind::SplineSurface | ModelKind::CaoEn | ModelKind::SurfaceNetwork => {
                println!("  MACs         {value} per position, {derivative} per position+normal")
            }
            ModelKind::Implicit | ModelKind::Rbf => {
                println!("  MACs         {value} per field, {derivative} per field+gradient")
            }
        }
    }
    if let Some(fit) = info.fit {
        println!(
            "  fit          {} of {} points ({} neurons, seed {}), residual RMS {:.3e} max {:.3e}",
            fit.method, fit.points, fit.neurons, fit.seed, fit.rms_residual, fit.max_residual,
        );
    }
    if let Some(fit) = info.network_fit {
        println!(
            "  fit          {} points, {} configurations tried, RMS error {:.3e} ({:.2e} of the diagonal)",
            fit.points, fit.candidates, fit.rms_error, fit.relative_rms_error
        );
    }
    if let Some(centers) = info.centers {
        println!("  centers      {centers}");
    }
    if let Some(t) = info.training {
        println!(
            "  training     {} iterations, {}",
            t.iterations(),
            t.outcome()
        );
        for m in &t.modules {
            println!(
                "    module {:>2} {:<4} feature {:<4} {:>5} points {:>4} iterations  E {:.2e}",
                m.module,
                if m.node { "node" } else { "leaf" },
                m.feature.map_or("-".to_string(), |f| f.to_string()),
                m.points,
                m.lm.iterations,
                m.lm.error
            );
        }
    }
    Ok(())
}

fn open_or_closed(closed: bool) -> &'static str {
    if closed { "closed" } else { "open" }
}
