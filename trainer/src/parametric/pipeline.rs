//! The whole of Fig. 2: points → LLE parameters → fitted network → tessellation → mesh.

use super::boundary::BoundaryOptions;
use super::coons::{coons_boundary, coons_grid};
use super::embedding::{Embedding, LleOptions, embed_points};
use super::fit::{SurfaceFit, fit_network};
use super::grid::delaunay_grid;
use super::planar::PlanarMesh;
use super::synthesis::{SynthesizedSurface, synthesize};
use super::topology::TopologyOptions;
use crate::error::Result;

/// Which tessellation of §5.3.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Tessellation {
    /// A `resolution × resolution` quad grid from the bilinear Coons patch.
    Coons {
        /// Vertices per side (≥ 2).
        resolution: usize,
    },
    /// The resampled boundary loop and a uniform grid inside it, Delaunay triangulated.
    Delaunay {
        /// About this many vertices.
        vertices: usize,
    },
}

/// Settings of the whole reconstruction.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReconstructOptions {
    /// Embedding.
    pub embedding: LleOptions,
    /// Regression and topology search.
    pub topology: TopologyOptions,
    /// Boundary of the parameter points.
    pub boundary: BoundaryOptions,
    /// Grid.
    pub tessellation: Tessellation,
}

impl Default for ReconstructOptions {
    fn default() -> Self {
        ReconstructOptions {
            embedding: LleOptions::default(),
            topology: TopologyOptions::default(),
            boundary: BoundaryOptions::default(),
            tessellation: Tessellation::Coons { resolution: 30 },
        }
    }
}

/// Everything a reconstruction produced.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    /// The parameterization.
    pub embedding: Embedding,
    /// The network and its search.
    pub fit: SurfaceFit,
    /// The tessellation in the parameter plane.
    pub grid: PlanarMesh,
    /// The mesh and normals.
    pub surface: SynthesizedSurface,
}

/// Reconstructs an open surface patch from unstructured points.
///
/// # Errors
/// Every error of [`embed_points`], [`fit_network`] and the tessellations.
pub fn reconstruct(points: &[[f64; 3]], options: &ReconstructOptions) -> Result<Reconstruction> {
    let embedding = embed_points(points, &options.embedding)?;
    let fit = fit_network(points, &embedding.parameters, &options.topology)?;
    let grid = match options.tessellation {
        Tessellation::Coons { resolution } => {
            let boundary = coons_boundary(&embedding.parameters, &options.boundary)?;
            coons_grid(&boundary, resolution, resolution)?
        }
        Tessellation::Delaunay { vertices } => {
            delaunay_grid(&embedding.parameters, vertices, &options.boundary)?
        }
    };
    let surface = synthesize(&fit.network, &grid);
    Ok(Reconstruction {
        embedding,
        fit,
        grid,
        surface,
    })
}
