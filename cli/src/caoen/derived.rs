//! The output side shared by commands that derive one network from another (`shade`,
//! `normals`, `perspective`): where the blob goes, in which scalar, and how the summary is
//! printed.

use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::Serialize;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::caoen::{self, CaoEnNetwork};
use neurosurf_trainer::evaluate::Precision;

use super::super::output::{self, blob_scalar, wrote_blob};

/// Where and how a derived network is written.
#[derive(Debug, clap::Args)]
pub struct BlobOut {
    /// How the blob stores the network: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    pub scalar: Precision,
    /// The blob to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

impl BlobOut {
    /// The scalar asked for, after checking the output path can be written (before any work).
    pub fn prepare(&self) -> Result<ScalarKind> {
        let scalar = blob_scalar(self.scalar)?;
        neurosurf_trainer::io::check_output(&self.out)?;
        Ok(scalar)
    }

    /// Writes `network` (checked through the core) and says what was written.
    pub fn write(
        &self,
        network: &CaoEnNetwork,
        scalar: ScalarKind,
        tag: &[u8],
    ) -> Result<Written<'_>> {
        let blob = caoen::to_blob(network, scalar, tag)?;
        neurosurf_trainer::blob::write_checked(&self.out, &blob)?;
        Ok(Written {
            out: &self.out,
            blob_bytes: blob.len(),
            key_points: network.key_count(),
            scalar,
        })
    }

    /// Prints `report` as JSON with --json; otherwise `summary` and the written blob.
    pub fn finish(
        &self,
        report: &impl Serialize,
        summary: impl FnOnce() -> String,
        written: &Written,
    ) -> Result<()> {
        if self.json {
            return output::json(report);
        }
        println!("{}", summary());
        wrote_blob(written.out, written.blob_bytes, written.scalar, None);
        Ok(())
    }
}

/// The blob a derived network went to: the start of every such command's report.
#[derive(Serialize)]
pub struct Written<'a> {
    pub out: &'a Path,
    pub blob_bytes: usize,
    pub key_points: usize,
    #[serde(skip)]
    pub scalar: ScalarKind,
}
