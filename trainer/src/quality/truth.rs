//! The reference surface a model is measured against: a triangle mesh (exact point-to-triangle
//! distances) or, when only points are known, the points themselves.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::caoen::TriangleTree;
use crate::error::{Error, Result};
use crate::geometry::vector::{add, cross, norm, scale, sub};
use crate::implicit::Normalization;
use crate::io::Mesh;
use crate::points::PointSet;
use crate::render::{Aabb, Field, Region, extract_mesh};

/// The zero set of a signed distance `distance` (negative inside) within `bounds`, meshed at
/// `resolution` cells along the longest side (distances to the mesh are then within about 1 %
/// of a cell of the zero set's).
///
/// # Errors
/// [`Error::InvalidInput`] when `bounds` is empty; mesher errors.
pub fn signed_distance_mesh(
    distance: impl Fn([f64; 3]) -> f64 + Sync,
    bounds: Aabb,
    resolution: usize,
) -> Result<Mesh> {
    let half = bounds.half();
    let normalization = Normalization {
        center: bounds.center(),
        matrix: [0, 1, 2].map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
    };
    let region = Region::new(normalization, 2.0, 1.0)
        .ok_or_else(|| Error::invalid(format!("empty bounds {bounds:?}")))?;
    let field = SignedDistance {
        distance,
        regions: vec![region],
    };
    Ok(extract_mesh(&field, resolution, &|_, _| {})?.mesh)
}

/// A signed distance (negative inside) as a field for the mesher: Φ = −d, gradient by central
/// differences.
struct SignedDistance<F> {
    distance: F,
    regions: Vec<Region>,
}

impl<F: Fn([f64; 3]) -> f64 + Sync> Field for SignedDistance<F> {
    fn value(&self, p: [f64; 3]) -> f64 {
        -(self.distance)(p)
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let h = 1e-6 * (1.0 + p.iter().fold(0.0_f64, |m, v| m.max(v.abs())));
        let g = [0, 1, 2].map(|k| {
            let (mut a, mut b) = (p, p);
            a[k] += h;
            b[k] -= h;
            (self.value(a) - self.value(b)) / (2.0 * h)
        });
        (self.value(p), g)
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }
}

/// A known surface: where it is, how big it is, and how far any point is from it.
#[derive(Debug)]
pub struct Truth {
    /// Sample points on the surface (a mesh's used vertices, or the given points).
    positions: Vec<[f64; 3]>,
    /// Their outward unit normals (area-weighted vertex normals for a mesh).
    normals: Vec<[f64; 3]>,
    /// Exact distances for a mesh; nearest-sample distances otherwise.
    triangles: Option<TriangleTree>,
    points: ImmutableKdTree<f64, 3>,
    bounds: Aabb,
}

impl Truth {
    /// The surface of a triangle mesh. Distances are exact point-to-triangle distances; the
    /// samples are the vertices that some triangle uses, with area-weighted normals.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an invalid mesh (see [`Mesh::validated`]) or one whose
    /// triangles all have zero area.
    pub fn from_mesh(mesh: &Mesh) -> Result<Truth> {
        let mesh = mesh.clone().validated()?;
        let mut sums = vec![[0.0; 3]; mesh.positions.len()];
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            // |(b − a) × (c − a)| is twice the area: the sum is area-weighted.
            let n = cross(sub(b, a), sub(c, a));
            for &v in t {
                sums[v as usize] = add(sums[v as usize], n);
            }
        }
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        for (p, n) in mesh.positions.iter().zip(&sums) {
            let len = norm(*n);
            if len > 0.0 && len.is_finite() {
                positions.push(*p);
                normals.push(scale(*n, 1.0 / len));
            }
        }
        if positions.is_empty() {
            return Err(Error::invalid(
                "the reference mesh has no triangle of positive area",
            ));
        }
        let triangles = Some(TriangleTree::new(&mesh)?);
        Self::build(positions, normals, triangles)
    }

    /// The zero set of a signed distance `distance` (negative inside) within `bounds`, meshed
    /// by [`signed_distance_mesh`] at `resolution` cells along the longest side.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when `bounds` is empty or the zero set has no triangle inside it.
    pub fn from_signed_distance(
        distance: impl Fn([f64; 3]) -> f64 + Sync,
        bounds: Aabb,
        resolution: usize,
    ) -> Result<Truth> {
        Self::from_mesh(&signed_distance_mesh(distance, bounds, resolution)?)
    }

    /// The surface known only by oriented points: distances are to the nearest point (an
    /// overestimate by up to half the sample spacing).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an unusable point set (see [`PointSet::validated`]).
    pub fn from_points(points: &PointSet) -> Result<Truth> {
        let points = points.clone().validated()?;
        Self::build(points.positions, points.normals, None)
    }

    fn build(
        positions: Vec<[f64; 3]>,
        normals: Vec<[f64; 3]>,
        triangles: Option<TriangleTree>,
    ) -> Result<Truth> {
        let bounds = positions.iter().fold(
            Aabb {
                lo: positions[0],
                hi: positions[0],
            },
            |b, p| b.union(&Aabb { lo: *p, hi: *p }),
        );
        let diagonal = norm(sub(bounds.hi, bounds.lo));
        if !(diagonal > 0.0 && diagonal.is_finite()) {
            return Err(Error::invalid(
                "the reference surface has no extent: all its points coincide",
            ));
        }
        let points = ImmutableKdTree::new_from_slice(&positions)
            .map_err(|e| Error::invalid(format!("k-d tree construction failed: {e}")))?;
        Ok(Truth {
            positions,
            normals,
            triangles,
            points,
            bounds,
        })
    }

    /// The axis-aligned bounding box of the samples.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The length of the bounding box's diagonal: the unit of every relative figure.
    pub fn diagonal(&self) -> f64 {
        norm(sub(self.bounds.hi, self.bounds.lo))
    }

    /// The sample points on the surface.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Their outward unit normals.
    pub fn normals(&self) -> &[[f64; 3]] {
        &self.normals
    }

    /// The unsigned distance from `p` to the surface.
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        match &self.triangles {
            Some(tree) => tree.distance(p),
            None => self
                .points
                .query(&p)
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute()
                .distance
                .sqrt(),
        }
    }

    /// Whether the surface is known exactly (a mesh) rather than by samples.
    pub fn is_exact(&self) -> bool {
        self.triangles.is_some()
    }
}
