//! Φ and ∇Φ of a guarded network at single points and over the grid.

use super::*;

/// Φ and ∇Φ of a guarded network: through the core in `f32` when the network makes a blob
/// (what `mesh` and the microcontroller evaluate); else the `f64` network.
pub(super) struct Probe<'a> {
    pub(super) network: &'a ImplicitNetwork,
    pub(super) model: Option<Box<ImplicitModel<f32>>>,
}

impl<'a> Probe<'a> {
    pub(super) fn new(network: &'a ImplicitNetwork) -> Self {
        let model = to_blob(network, None, ScalarKind::F32)
            .ok()
            .and_then(|blob| ImplicitModel::<f32>::from_blob(&blob).ok().map(Box::new));
        Probe { network, model }
    }

    pub(super) fn at(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        match &self.model {
            Some(model) => {
                let g = model.field_gradient(p.map(|v| v as f32));
                (f64::from(g.value), g.gradient.map(f64::from))
            }
            None => self.network.eval(p),
        }
    }

    /// Φ and ∇Φ at the `far` grid points whose side is known, in batches; `None` elsewhere
    /// and where the grid is settled. Every second point along each axis comes first (and
    /// the last); a point between them is evaluated only when a corner of its coarse cell is
    /// not on the point's side by `push` all across the cell by its tangent plane. Elsewhere
    /// Φ keeps its side through the cell, as far as first order tells.
    pub(super) fn grid(
        &self,
        grid: &Grid,
        far: &[bool],
        inside: &[Option<bool>],
        push: f64,
    ) -> Vec<Option<(f64, [f64; 3])>> {
        let mut out = vec![None; grid.len()];
        let wanted = |i: usize| far[i] && inside[i].is_some();
        let coarse: Vec<usize> = (0..grid.len())
            .filter(|&i| wanted(i) && grid.is_coarse(i))
            .collect();
        for (&i, jet) in coarse.iter().zip(self.batch(grid, &coarse)) {
            out[i] = Some(jet);
        }
        let across = 2.0 * norm(grid.spacing);
        let settled = |i: usize, side: bool| {
            grid.coarse_corners(i).all(|c| {
                inside[c] == Some(side)
                    && out[c].is_some_and(|(v, g)| toward(side, v) - norm(g) * across >= push)
            })
        };
        let fine: Vec<usize> = (0..grid.len())
            .into_par_iter()
            .filter(|&i| {
                wanted(i) && !grid.is_coarse(i) && inside[i].is_some_and(|s| !settled(i, s))
            })
            .collect();
        for (&i, jet) in fine.iter().zip(self.batch(grid, &fine)) {
            out[i] = Some(jet);
        }
        out
    }

    /// Φ and ∇Φ at the grid points `indices`.
    pub(super) fn batch(&self, grid: &Grid, indices: &[usize]) -> Vec<(f64, [f64; 3])> {
        indices
            .par_chunks(LANES * 64)
            .flat_map_iter(|chunk| {
                let points: Vec<[f64; 3]> = chunk.iter().map(|&i| grid.point(i)).collect();
                match &self.model {
                    Some(model) => {
                        let points: Vec<[f32; 3]> =
                            points.iter().map(|p| p.map(|v| v as f32)).collect();
                        let zero = FieldGradient {
                            value: 0.0_f32,
                            gradient: [0.0; 3],
                        };
                        let mut out = vec![zero; points.len()];
                        if model.field_gradient_batch(&points, &mut out).is_err() {
                            out.fill(zero);
                        }
                        out.into_iter()
                            .map(|g| (f64::from(g.value), g.gradient.map(f64::from)))
                            .collect::<Vec<_>>()
                    }
                    None => points.iter().map(|&p| self.network.eval(p)).collect(),
                }
            })
            .collect()
    }
}
