//! Φ of a network evaluated once on the grid `neurosurf mesh` uses, so that meshing it again
//! after adding guards costs only the grid points the guards reach.
//!
//! Where no added guard reaches, the core adds nothing more to the cached value, so it is the
//! guarded model's bit for bit; every other point (and any point off the grid) is evaluated
//! by the core with all its guards.

use rayon::prelude::*;

use neurosurf_core::scalar::ScalarKind;

use super::blob::to_blob;
use super::network::{Guard, ImplicitNetwork};
use crate::error::Result;
use crate::render::{CoreField, Field, MeshGrid, Region};

/// A point is taken as reached when it lies within this many radii of a guard's centre: a
/// margin over the core's `f32` test of the same ball.
const REACH_SLACK: f64 = 1.01;

/// Φ at every point of a mesh grid inside its regions.
#[derive(Debug)]
pub struct GridCache {
    grid: MeshGrid,
    regions: Vec<Region>,
    /// The guards the cached network has.
    guards: Vec<Guard>,
    /// x fastest, then y, then z; NaN outside the regions.
    base: Vec<f64>,
}

impl GridCache {
    /// Evaluates `network` (with its guards), through the core in `f32`, at every point of
    /// the grid [`crate::render::extract_mesh`] uses for `regions` at `resolution`.
    ///
    /// # Errors
    /// When the network makes no blob the core loads, or the mesher refuses the grid.
    pub fn new(
        network: &ImplicitNetwork,
        regions: Vec<Region>,
        resolution: usize,
    ) -> Result<GridCache> {
        let blob = to_blob(network, None, ScalarKind::F32)?;
        let field = CoreField::new(&blob, regions.clone())?;
        let grid = MeshGrid::new(&field, resolution)?;
        let n = grid.cells.map(|c| c + 1);
        let base: Vec<f64> = (0..n[2])
            .into_par_iter()
            .flat_map_iter(|z| {
                let mut points = Vec::new();
                let mut slots = Vec::new();
                for y in 0..n[1] {
                    for x in 0..n[0] {
                        let p = grid.point([x, y, z]);
                        if regions.iter().any(|r| r.contains(p)) {
                            points.push(p);
                            slots.push(x + n[0] * y);
                        }
                    }
                }
                let mut values = vec![0.0; points.len()];
                field.values(&points, &mut values);
                let mut slab = vec![f64::NAN; n[0] * n[1]];
                for (&slot, v) in slots.iter().zip(values) {
                    slab[slot] = v;
                }
                slab
            })
            .collect();
        Ok(GridCache {
            grid,
            regions,
            guards: network.guards().to_vec(),
            base,
        })
    }

    /// Takes on `network`'s guards: re-evaluates, through the core, the grid points that the
    /// guards beyond the cached ones reach (every point when `network`'s guards do not start
    /// with the cached ones).
    ///
    /// # Errors
    /// When the network makes no blob the core loads.
    pub fn update(&mut self, network: &ImplicitNetwork) -> Result<()> {
        let blob = to_blob(network, None, ScalarKind::F32)?;
        let field = CoreField::new(&blob, self.regions.clone())?;
        let added = network.guards().strip_prefix(self.guards.as_slice());
        let grid = self.grid;
        let n = grid.cells.map(|c| c + 1);
        let stale: Vec<usize> = (0..self.base.len())
            .into_par_iter()
            .filter(|&i| {
                !self.base[i].is_nan()
                    && added.is_none_or(|added| {
                        let p = grid.point([i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])]);
                        reaches(added, p)
                    })
            })
            .collect();
        let values: Vec<f64> = stale
            .par_chunks(4096)
            .flat_map_iter(|chunk| {
                let points: Vec<[f64; 3]> = chunk
                    .iter()
                    .map(|&i| grid.point([i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])]))
                    .collect();
                let mut values = vec![0.0; points.len()];
                field.values(&points, &mut values);
                values
            })
            .collect();
        for (i, v) in stale.into_iter().zip(values) {
            self.base[i] = v;
        }
        self.guards = network.guards().to_vec();
        Ok(())
    }

    /// The field of `network` through the cache: the cached network with guards added after
    /// its own (any other network is evaluated by the core everywhere).
    ///
    /// # Errors
    /// When the network makes no blob the core loads.
    pub fn field(&self, network: &ImplicitNetwork) -> Result<CachedField<'_>> {
        let blob = to_blob(network, None, ScalarKind::F32)?;
        let added = network
            .guards()
            .strip_prefix(self.guards.as_slice())
            .map(<[Guard]>::to_vec);
        Ok(CachedField {
            cache: self,
            exact: CoreField::new(&blob, self.regions.clone())?,
            added,
        })
    }
}

/// A guarded network's field: cached where no added guard reaches, else the core's.
#[derive(Debug)]
pub struct CachedField<'a> {
    cache: &'a GridCache,
    exact: CoreField,
    /// The guards beyond the cached ones; `None` for a network the cache does not hold.
    added: Option<Vec<Guard>>,
}

impl CachedField<'_> {
    /// The cached value at `p` when `p` is a grid point inside the regions that no added
    /// guard reaches.
    fn cached(&self, p: [f64; 3]) -> Option<f64> {
        let added = self.added.as_ref()?;
        let grid = &self.cache.grid;
        let n = grid.cells.map(|c| c + 1);
        let mut index = [0_usize; 3];
        for k in 0..3 {
            let f = ((p[k] - grid.origin[k]) / grid.cell).round();
            if !(f >= 0.0 && f < n[k] as f64) {
                return None;
            }
            index[k] = f as usize;
        }
        if grid.point(index) != p {
            return None;
        }
        if reaches(added, p) {
            return None;
        }
        let value = *self
            .cache
            .base
            .get(index[0] + n[0] * (index[1] + n[1] * index[2]))?;
        (!value.is_nan()).then_some(value)
    }
}

/// Whether any of `guards` may reach `p` in the core.
fn reaches(guards: &[Guard], p: [f64; 3]) -> bool {
    guards.iter().any(|g| {
        let d2: f64 = (0..3).map(|k| (p[k] - g.center[k]).powi(2)).sum();
        d2 * g.inverse_radius * g.inverse_radius <= REACH_SLACK * REACH_SLACK
    })
}

impl Field for CachedField<'_> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.cached(p).unwrap_or_else(|| self.exact.value(p))
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.exact.value_gradient(p)
    }

    fn regions(&self) -> &[Region] {
        &self.cache.regions
    }

    fn values(&self, points: &[[f64; 3]], out: &mut [f64]) {
        let mut missing = Vec::new();
        let mut slots = Vec::new();
        for (i, (p, o)) in points.iter().zip(out.iter_mut()).enumerate() {
            match self.cached(*p) {
                Some(v) => *o = v,
                None => {
                    missing.push(*p);
                    slots.push(i);
                }
            }
        }
        if !missing.is_empty() {
            let mut values = vec![0.0; missing.len()];
            self.exact.values(&missing, &mut values);
            for (&slot, v) in slots.iter().zip(values) {
                if let Some(o) = out.get_mut(slot) {
                    *o = v;
                }
            }
        }
    }

    fn value_gradients(&self, points: &[[f64; 3]], out: &mut [(f64, [f64; 3])]) {
        self.exact.value_gradients(points, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::tests::torus_points;
    use crate::implicit::{ImplicitOptions, TreeSpec, train};
    use crate::render::{DEFAULT_BOX_SIZE, DEFAULT_INFLATE, extract_mesh};

    #[test]
    fn the_cached_field_meshes_exactly_as_the_core() {
        let points = torus_points(200, 5);
        let tree: TreeSpec = "0".parse().expect("tree");
        let trained =
            train(&points, &tree, &ImplicitOptions::default(), None, &|_| {}).expect("train");
        // A guard that dents the tube, added after the cache is made.
        let dented = trained.network.clone().with_guards(vec![Guard {
            center: [1.0, 0.0, 0.2],
            inverse_radius: 1.0 / 0.3,
            amplitude: -2.0,
        }]);
        let regions = Region::of_network(&dented, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
        let mesh = |field: &dyn Field| extract_mesh(field, 48, &|_, _| {}).expect("mesh").mesh;
        let blob = to_blob(&dented, None, ScalarKind::F32).expect("blob");
        let core = mesh(&CoreField::new(&blob, regions.clone()).expect("core"));
        let bare = to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
        let undented = mesh(&CoreField::new(&bare, regions.clone()).expect("core"));
        assert_ne!(
            core.positions, undented.positions,
            "the guard dents the surface"
        );

        let mut cache = GridCache::new(&trained.network, regions, 48).expect("cache");
        // The guard re-evaluated where it reaches, then taken into the cache.
        let added = mesh(&cache.field(&dented).expect("field"));
        cache.update(&dented).expect("update");
        let updated = mesh(&cache.field(&dented).expect("field"));
        for m in [added, updated] {
            assert_eq!(m.positions, core.positions);
            assert_eq!(m.triangles, core.triangles);
        }
    }
}
