//! `neurosurf info`: what a blob holds. The core describes every kind it evaluates the same
//! way ([`Model`]: inputs, outputs, multiply–accumulates, structure); the trainer adds what it
//! stored beside the parameters (how the model was trained or fitted).

use std::path::PathBuf;

use anyhow::Result;
use neurosurf_core::BlobError;
use neurosurf_core::model::{self, Model, ModelVisitor};
use neurosurf_core::scalar::{Scalar, ScalarKind};
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
    /// Numbers per query point, and per result (the value alone; with its derivative).
    inputs: Option<usize>,
    outputs: Option<(usize, usize)>,
    /// Multiply–accumulates of one evaluation: the value alone; with its derivative.
    macs: Option<(usize, usize)>,
    /// What the core reads from the blob, in one line ([`Model::describe`]).
    structure: Option<String>,
    /// Implicit models: the tree, modules and leaves.
    tree: Option<String>,
    modules: Option<usize>,
    leaves: Option<usize>,
    /// RBF models: the centres.
    centers: Option<usize>,
    training: Option<&'a TrainingSummary>,
    fit: Option<&'a FitSummary>,
    /// Surface networks: how the network was fitted.
    network_fit: Option<&'a NetworkSummary>,
}

/// What the core reads from a blob, the same for every kind.
struct CoreView {
    inputs: usize,
    outputs: (usize, usize),
    macs: (usize, usize),
    structure: String,
}

struct Describe<'a>(&'a [u8]);

impl ModelVisitor for Describe<'_> {
    type Output = Result<CoreView, BlobError>;

    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
        let mut model = Box::<M>::default();
        model.load_blob(self.0)?;
        let mut structure = String::new();
        // Writing into a String cannot fail.
        let _ = model.describe(&mut structure);
        Ok(CoreView {
            inputs: model.input_len(),
            outputs: (model.output_len(false), model.output_len(true)),
            macs: (model.mac_count(false), model.mac_count(true)),
            structure,
        })
    }
}

pub fn run(args: &Args) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    let core = model
        .bytes()
        .and_then(|bytes| model::visit(model.kind(), ScalarKind::F32, Describe(bytes)))
        .transpose()?;
    let mut info = Info {
        kind: model.kind().name(),
        stored_as: model.stored_as().name(),
        blob_bytes: model.bytes().map_or_else(
            || std::fs::metadata(&args.model).map_or(0, |m| m.len() as usize),
            <[u8]>::len,
        ),
        parameters: model.parameter_count(),
        inputs: core.as_ref().map(|c| c.inputs),
        outputs: core.as_ref().map(|c| c.outputs),
        macs: core.as_ref().map(|c| c.macs),
        structure: core.map(|c| c.structure),
        ..Info::default()
    };
    // What the trainer stored beside the parameters.
    match &model {
        LoadedModel::Implicit { decoded, .. } => {
            let net = &decoded.network;
            info.tree = Some(net.tree().to_string());
            info.modules = Some(net.module_count());
            info.leaves = Some(net.subtree_leaves(net.root()).len());
            info.training = decoded.metadata.as_ref().and_then(|m| m.summary.as_ref());
        }
        LoadedModel::Rbf { decoded, .. } => {
            info.centers = Some(RbfModel::centers(decoded).len());
        }
        LoadedModel::Curve { decoded, .. } => info.fit = decoded.summary.as_ref(),
        LoadedModel::SplineSurface { decoded, .. } => info.fit = decoded.summary.as_ref(),
        LoadedModel::SurfaceNetwork { decoded, .. } => {
            info.network_fit = decoded.summary.as_ref();
        }
        LoadedModel::CaoEn { .. } => {}
    }
    if args.json {
        return output::json(&info);
    }
    print(&args.model, &info);
    Ok(())
}

fn print(path: &std::path::Path, info: &Info<'_>) {
    println!("{}: {} model", path.display(), info.kind);
    println!("  stored as    {}", info.stored_as);
    println!("  blob         {} bytes", info.blob_bytes);
    println!("  parameters   {}", info.parameters);
    if let Some(structure) = &info.structure {
        println!("  structure    {structure}");
    }
    if let (Some(tree), Some(modules), Some(leaves)) = (&info.tree, info.modules, info.leaves) {
        println!("  tree         {tree} ({modules} modules, {leaves} leaves)");
    }
    if let (Some(inputs), Some((value, full))) = (info.inputs, info.outputs) {
        println!("  numbers      {inputs} in, {value} out ({full} with the derivative)");
    }
    if let Some((value, full)) = info.macs {
        println!("  MACs         {value} per value, {full} with the derivative");
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
        if !fit.region.is_empty() {
            println!(
                "  region       {} corners of the (u, v) plane: the points' boundary",
                fit.region.len()
            );
        }
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
}
