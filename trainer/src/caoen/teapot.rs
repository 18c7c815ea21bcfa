//! The teapot as four Cao En surfaces (paper §10.2, Fig. 7): body, lid, spout and handle,
//! each mapped from the sphere, 104 key points in all.
//!
//! Parts: the mesh is welded (coincident vertices of the Bézier patches merged) and split
//! into edge-connected parts — in `teapot.obj` exactly four: the body (open at the top), the
//! lid (open at its rim), the spout and the handle (tubes open at both ends). The lid is the
//! part highest up, the spout the one farthest along +x, the handle along −x. Every part's
//! holes are capped, so each is a closed genus-0 surface; the caps lie inside the teapot.
//!
//! Body and lid: the sphere map that fits best of three — the directions from the centre of
//! the part's volume (radial: the sphere seen from inside, smooth wherever the part is nearly
//! star-shaped, as the body is), the spherical Tutte embedding
//! ([`spherical_parameterization`]) and the axial map (latitude along the teapot's axis,
//! longitude around it). Spout and handle: tube coordinates — t ∈ [0, 1] along the tube
//! between its caps' centres (graph distance from one over the sum of the distances from
//! both) and φ, the angle around the tube's centre line in the plane spanned by the teapot's
//! symmetry normal (z) and the centre line's in-plane normal — as the sphere point
//! (cos πt, sin πt·cos φ, sin πt·sin φ), the tube's axis becoming the sphere's polar axis (the
//! Tutte map squeezes a long bent tube into a thin band). A tube's keys are rings of six
//! along it ([`KeyPlacement::Sixfold`]): a smooth tube, where farthest-first keys leave it
//! knobbly.
//!
//! The whole teapot is measured by what shows: the outer surface of the four surfaces
//! against the outer surface of the mesh ([`outer_surface_distance`]), so the caps pressed on
//! each other under the lid and the tubes' roots inside the body count as hidden.

use std::collections::BinaryHeap;

use super::distance::{OuterDistance, SurfaceDistance, outer_surface_distance, surface_distance};
use super::mesh::sphere_mesh;
use super::mesh_fit::{KeyPlacement, MeshFit, MeshFitOptions, fit_parameterized};
use super::network::CaoEnNetwork;
use super::spherical::spherical_parameterization;
use super::topology::{cap_holes, edge_components, neighbours, oriented_boundary_loops, weld};
use crate::error::{Error, Result};
use crate::geometry::vector::cross;
use crate::io::Mesh;

/// The default key counts of the body, the lid, the spout and the handle: 104 in all, as in
/// the paper's Fig. 7, each two poles and rings of six (5, 4, 3 and 4 rings).
pub const TEAPOT_KEYS: [usize; 4] = [32, 26, 20, 26];

/// The blending value at a key's nearest neighbour: broader than [`MeshFitOptions`]' 0.3,
/// because narrow bumps leave creases between the keys of so few on a smooth shape.
/// Measured at the default keys through the axial map: 0.3 left a diagonal crease across the
/// body; 0.6 lowers the two-sided RMS of body, lid and spout (0.0104, 0.0199, 0.0178 to
/// 0.0095, 0.0180, 0.0160 of their diagonals) and shows no crease.
const OVERLAP: f64 = 0.6;

/// The outer-surface cell of the whole-teapot measure, relative to its diagonal (0.041 units
/// on `teapot.obj`): gaps narrower than it count as closed.
pub const TEAPOT_CELL: f64 = 0.005;

/// Where the body's and the lid's keys go.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum TeapotLayout {
    /// The paper's Fig. 7 (the default): rings of six keys around the teapot's axis, and a
    /// key at each pole ([`KeyPlacement::Sixfold`]), on the radial or the axial map,
    /// whichever fits better.
    Sixfold,
    /// Farthest-first on the surface, on whichever map (radial, Tutte or axial) fits better.
    /// Closer on the lid by RMS, but its rim comes out wavy.
    Farthest,
}

/// One fitted part.
#[derive(Clone, Debug, PartialEq)]
pub struct TeapotPart {
    /// "body", "lid", "spout" or "handle".
    pub name: &'static str,
    /// How the part was parameterized: "radial" (directions from the centre of its volume),
    /// "tutte" (the spherical Tutte embedding), "axial" (latitude along the axis, longitude
    /// around it) or "tube" (tube coordinates), with ", sixfold keys" for rings of six.
    pub parameterization: &'static str,
    /// The sphere network.
    pub network: CaoEnNetwork,
    /// The part's mesh as found in the file (welded).
    pub mesh: Mesh,
    /// Surface against the part's mesh with its holes capped.
    pub distance: SurfaceDistance,
}

/// The fitted teapot.
#[derive(Clone, Debug, PartialEq)]
pub struct Teapot {
    /// Body, lid, spout and handle.
    pub parts: Vec<TeapotPart>,
    /// The four mapped surfaces in one mesh (icosphere level 4 each).
    pub combined: Mesh,
    /// What shows of the four surfaces against what shows of the welded mesh
    /// ([`TEAPOT_CELL`]), relative to the whole teapot's diagonal.
    pub whole: OuterDistance,
    /// Every surface, caps inside the teapot included, against the whole welded mesh.
    pub all_surfaces: SurfaceDistance,
}

/// Splits, parameterizes and fits the teapot with `keys` = (body, lid, spout, handle) key
/// counts ([`TEAPOT_KEYS`] by default); measures each part and the whole.
///
/// # Errors
/// [`Error::InvalidInput`] when the mesh does not split into four parts of the expected
/// topology, or any fit fails.
pub fn fit_teapot(mesh: &Mesh, keys: [usize; 4], layout: TeapotLayout) -> Result<Teapot> {
    let (welded, _) = weld(mesh, 1e-6)?;
    let parts = edge_components(&welded);
    if parts.len() != 4 {
        return Err(Error::invalid(format!(
            "the teapot should split into 4 parts (body, lid, spout, handle), found {}",
            parts.len()
        )));
    }
    let mean = |m: &Mesh, k: usize| {
        m.positions.iter().map(|p| p[k]).sum::<f64>() / m.positions.len() as f64
    };
    let pick = |key: &dyn Fn(&Mesh) -> f64, taken: &[usize]| -> usize {
        (0..4)
            .filter(|i| !taken.contains(i))
            .max_by(|&a, &b| key(&parts[a]).total_cmp(&key(&parts[b])))
            .unwrap_or(0)
    };
    let lid = pick(&|m| mean(m, 1), &[]);
    let spout = pick(&|m| mean(m, 0), &[lid]);
    let handle = pick(&|m| -mean(m, 0), &[lid, spout]);
    let body = pick(&|m| m.positions.len() as f64, &[lid, spout, handle]);
    let options = MeshFitOptions {
        sample_subdivisions: 4,
        overlap: OVERLAP,
        ..MeshFitOptions::default()
    };
    let named = |name: &'static str, n: usize| {
        move |e: Error| Error::invalid(format!("the teapot's {name} with {n} key points: {e}"))
    };
    let mut fitted = Vec::new();
    for (name, index, n) in [("body", body, keys[0]), ("lid", lid, keys[1])] {
        fitted.push(fit_solid(name, &parts[index], n, layout, &options).map_err(named(name, n))?);
    }
    for (name, index, n) in [("spout", spout, keys[2]), ("handle", handle, keys[3])] {
        fitted.push(fit_tube_part(name, &parts[index], n, &options).map_err(named(name, n))?);
    }
    let mut combined = Mesh::default();
    for part in &fitted {
        let surface = sphere_mesh(&part.network, 4)?.mesh;
        let offset = combined.positions.len() as u32;
        combined.positions.extend(surface.positions);
        combined
            .triangles
            .extend(surface.triangles.iter().map(|t| t.map(|v| v + offset)));
    }
    Ok(Teapot {
        whole: outer_surface_distance(&combined, &welded, TEAPOT_CELL)?,
        all_surfaces: surface_distance(&combined, &welded)?,
        parts: fitted,
        combined,
    })
}

/// The body or the lid: its hole capped, then fitted through the best of its sphere maps.
fn fit_solid(
    name: &'static str,
    part: &Mesh,
    keys: usize,
    layout: TeapotLayout,
    options: &MeshFitOptions,
) -> Result<TeapotPart> {
    let closed = cap_holes(part)?;
    let mut candidates: Vec<(MeshFit, &'static str)> = Vec::new();
    if layout == TeapotLayout::Sixfold {
        let sixfold = MeshFitOptions {
            placement: KeyPlacement::Sixfold,
            ..*options
        };
        // The axial map needs every band of latitude populated; the radial map needs a
        // volume. Where neither can be built, the part keeps farthest-first keys below.
        if let Some(points) = radial_map(&closed) {
            candidates.push((
                fit_parameterized(&closed, &points, keys, &sixfold)?,
                "radial, sixfold keys",
            ));
        }
        if let Ok(fit) = fit_axial(part, &closed, keys, &sixfold) {
            candidates.push((fit, "axial, sixfold keys"));
        }
    }
    if candidates.is_empty() {
        let map = spherical_parameterization(&closed)
            .map_err(|e| Error::invalid(format!("teapot {name}: {e}")))?;
        candidates.push((
            fit_parameterized(&closed, &map.points, keys, options)?,
            "tutte",
        ));
        if let Some(points) = radial_map(&closed) {
            candidates.push((
                fit_parameterized(&closed, &points, keys, options)?,
                "radial",
            ));
        }
        if let Ok(fit) = fit_axial(part, &closed, keys, options) {
            candidates.push((fit, "axial"));
        }
    }
    let (fit, parameterization) = candidates
        .into_iter()
        .min_by(|a, b| a.0.distance.rms.total_cmp(&b.0.distance.rms))
        .ok_or_else(|| Error::invalid(format!("teapot {name}: no sphere map fits")))?;
    Ok(TeapotPart {
        name,
        parameterization,
        network: fit.network,
        mesh: part.clone(),
        distance: fit.distance,
    })
}

/// The radial map of a closed mesh: each vertex's direction from the centre of the mesh's
/// volume, turned so the teapot's axis (y) is the sphere's x axis, the axis of
/// [`KeyPlacement::Sixfold`]'s rings. It folds where a ray from the centre crosses the
/// surface more than once (the body's dimpled bottom); the fit decides whether it serves.
/// `None` when the volume is not positive or a vertex sits at the centre.
fn radial_map(mesh: &Mesh) -> Option<Vec<[f64; 3]>> {
    let (mut volume, mut moment) = (0.0, [0.0; 3]);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let n = cross(b, c);
        let six = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
        volume += six / 6.0;
        for k in 0..3 {
            moment[k] += six / 6.0 * (a[k] + b[k] + c[k]) / 4.0;
        }
    }
    if !(volume > 0.0 && volume.is_finite()) {
        return None;
    }
    let centre = moment.map(|m| m / volume);
    mesh.positions
        .iter()
        .map(|p| {
            let d = [0, 1, 2].map(|k| p[k] - centre[k]);
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            (r > 0.0).then(|| [d[1] / r, d[2] / r, d[0] / r])
        })
        .collect()
}

/// Graph distances (edge lengths) from every vertex of `sources`.
fn distances_from(mesh: &Mesh, adjacent: &[Vec<u32>], sources: &[u32]) -> Vec<f64> {
    #[derive(PartialEq)]
    struct Entry(f64, u32);
    impl Eq for Entry {}
    impl PartialOrd for Entry {
        fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Entry {
        fn cmp(&self, other: &Self) -> std::cmp::Ordering {
            other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
        }
    }
    let mut distance = vec![f64::INFINITY; mesh.positions.len()];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        distance[s as usize] = 0.0;
        heap.push(Entry(0.0, s));
    }
    while let Some(Entry(d, v)) = heap.pop() {
        if d > distance[v as usize] {
            continue;
        }
        for &w in &adjacent[v as usize] {
            let (a, b) = (mesh.positions[v as usize], mesh.positions[w as usize]);
            let next = d + (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
            if next < distance[w as usize] {
                distance[w as usize] = next;
                heap.push(Entry(next, w));
            }
        }
    }
    distance
}

/// Coordinates along and around a tube: t ∈ [0, 1] (graph distance from the `from` vertices
/// over the sum of the distances from both ends) and φ, the angle around the centre line in
/// the plane of the teapot's symmetry normal (z) and the centre line's in-plane normal.
struct Tube {
    t: Vec<f64>,
    phi: Vec<f64>,
}

/// Bands of t along a tube's centre line.
const BANDS: usize = 12;

/// [`Tube`] coordinates of `mesh` between the vertex sets `from` (t = 0) and `to` (t = 1).
fn tube_coordinates(mesh: &Mesh, from: &[u32], to: &[u32]) -> Result<Tube> {
    let adjacent = neighbours(mesh);
    let (from_a, from_b) = (
        distances_from(mesh, &adjacent, from),
        distances_from(mesh, &adjacent, to),
    );
    let t: Vec<f64> = from_a
        .iter()
        .zip(&from_b)
        .map(|(a, b)| if a + b > 0.0 { a / (a + b) } else { 0.0 })
        .collect();
    if t.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid("the tube is not connected"));
    }
    let band = |t: f64| ((t * BANDS as f64) as usize).min(BANDS - 1);
    let mut centre = vec![[0.0; 3]; BANDS];
    let mut count = vec![0.0; BANDS];
    for (p, &tv) in mesh.positions.iter().zip(&t) {
        let b = band(tv);
        for k in 0..3 {
            centre[b][k] += p[k];
        }
        count[b] += 1.0;
    }
    for (c, n) in centre.iter_mut().zip(&count) {
        if *n == 0.0 {
            return Err(Error::invalid(
                "the tube has an empty band along its length",
            ));
        }
        *c = c.map(|v| v / n);
    }
    let phi = mesh
        .positions
        .iter()
        .zip(&t)
        .map(|(p, &tv)| {
            let b = band(tv);
            let (before, after) = (centre[b.saturating_sub(1)], centre[(b + 1).min(BANDS - 1)]);
            let normal = [before[1] - after[1], after[0] - before[0]];
            let d = [0, 1, 2].map(|k| p[k] - centre[b][k]);
            let length = normal[0].hypot(normal[1]).max(1e-300);
            d[2].atan2((d[0] * normal[0] + d[1] * normal[1]) / length)
        })
        .collect();
    Ok(Tube { t, phi })
}

/// A tube (the spout, the handle) as a sphere network: its open ends capped, then the tube
/// coordinates of the capped mesh (t from one cap's centre to the other's) become a sphere
/// point with the tube's axis as the polar axis, (cos πt, sin πt·cos φ, sin πt·sin φ). A
/// long, thin, bent tube has no good conformal (Tutte) map to the sphere — its middle shrinks
/// to a thin band — but this one spreads the vertices evenly in latitude. Keys: rings of six
/// along the tube (farthest-first below 8 keys).
fn fit_tube_part(
    name: &'static str,
    mesh: &Mesh,
    keys: usize,
    options: &MeshFitOptions,
) -> Result<TeapotPart> {
    let loops = oriented_boundary_loops(mesh)?;
    if loops.len() != 2 {
        return Err(Error::invalid(format!(
            "the {name} should be a tube with 2 open ends, found {}",
            loops.len()
        )));
    }
    let closed = cap_holes(mesh)?;
    let first_cap = mesh.positions.len() as u32;
    let tube = tube_coordinates(&closed, &[first_cap], &[first_cap + 1])?;
    let (placement, parameterization) = if keys >= 8 {
        (KeyPlacement::Sixfold, "tube, sixfold keys")
    } else {
        (options.placement, "tube")
    };
    let rings = MeshFitOptions {
        placement,
        ..*options
    };
    let fit = fit_tube(&closed, &tube, keys, &rings)?;
    Ok(TeapotPart {
        name,
        parameterization,
        network: fit.network,
        mesh: mesh.clone(),
        distance: fit.distance,
    })
}

/// Fits a closed mesh through its tube coordinates as sphere points (cos πt, sin πt·cos φ,
/// sin πt·sin φ), with φ's sense chosen so the network's normals point out of the mesh.
fn fit_tube(closed: &Mesh, tube: &Tube, keys: usize, options: &MeshFitOptions) -> Result<MeshFit> {
    let points = |sense: f64| -> Vec<[f64; 3]> {
        tube.t
            .iter()
            .zip(&tube.phi)
            .map(|(&t, &phi)| {
                let a = std::f64::consts::PI * t;
                [a.cos(), a.sin() * phi.cos(), sense * a.sin() * phi.sin()]
            })
            .collect()
    };
    let forward = points(1.0);
    let fit = fit_parameterized(closed, &forward, keys, options)?;
    let sources: Vec<Vec<f64>> = forward.iter().map(|p| p.to_vec()).collect();
    if faces_outward(&fit.network, &sources, closed) {
        Ok(fit)
    } else {
        fit_parameterized(closed, &points(-1.0), keys, options)
    }
}

/// A body of revolution about y (the body, the lid) on the sphere: its hole capped, t from
/// the pole at the bottom (the lowest vertex nearest the axis, or the cap's centre when the
/// part is open at the bottom) to the top one, φ around the axis.
fn fit_axial(part: &Mesh, closed: &Mesh, keys: usize, options: &MeshFitOptions) -> Result<MeshFit> {
    let caps: Vec<u32> = (part.positions.len() as u32..closed.positions.len() as u32).collect();
    let axis_distance = |p: &[f64; 3]| p[0].hypot(p[2]);
    let extreme = |sign: f64| -> u32 {
        (0..closed.positions.len() as u32)
            .min_by(|&a, &b| {
                let (p, q) = (closed.positions[a as usize], closed.positions[b as usize]);
                (sign * p[1])
                    .total_cmp(&(sign * q[1]))
                    .then(axis_distance(&p).total_cmp(&axis_distance(&q)))
            })
            .unwrap_or(0)
    };
    let (bottom, top) = (extreme(1.0), extreme(-1.0));
    // A cap is a pole when it is the lowest or highest point's neighbour in height.
    let pole = |v: u32| {
        caps.iter()
            .copied()
            .find(|&c| {
                (closed.positions[c as usize][1] - closed.positions[v as usize][1]).abs() < 1e-3
            })
            .unwrap_or(v)
    };
    let tube = tube_coordinates(closed, &[pole(bottom)], &[pole(top)])?;
    fit_tube(closed, &tube, keys, options)
}

/// Whether the network's normals at `sources` agree (mostly) with the mesh's outward vertex
/// normals (area-weighted sums of its triangles' normals).
fn faces_outward(network: &CaoEnNetwork, sources: &[Vec<f64>], mesh: &Mesh) -> bool {
    let mut normals = vec![[0.0; 3]; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let n = cross(
            [0, 1, 2].map(|k| b[k] - a[k]),
            [0, 1, 2].map(|k| c[k] - a[k]),
        );
        for &v in t {
            for k in 0..3 {
                normals[v as usize][k] += n[k];
            }
        }
    }
    let agreement: f64 = sources
        .iter()
        .zip(&normals)
        .filter_map(|(x, m)| {
            let n = network.normal(x)?;
            Some((n[0] * m[0] + n[1] * m[1] + n[2] * m[2]).signum())
        })
        .sum();
    agreement > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{data_file, read_mesh};

    /// Four parts, 104 keys in all, each part's distance to its own capped mesh (two-sided
    /// RMS and Hausdorff, of the part's bounding diagonal) below its bound, and the whole
    /// teapot's outer surface within 3 % of the mesh's both ways. Measured: see
    /// `docs/caoen.md`.
    #[test]
    fn teapot_as_four_surfaces() {
        let mesh = read_mesh(&data_file("teapot.obj").unwrap()).unwrap();
        let teapot = fit_teapot(&mesh, TEAPOT_KEYS, TeapotLayout::Sixfold).unwrap();
        let keys: usize = teapot.parts.iter().map(|p| p.network.key_count()).sum();
        assert_eq!(keys, 104);
        for p in &teapot.parts {
            let d = p.distance;
            println!(
                "{:<6} {:<20} {:>3} keys, {:>4} vertices: rms {:.4}, Hausdorff {:.4} (of the diagonal)",
                p.name,
                p.parameterization,
                p.network.key_count(),
                p.mesh.vertex_count(),
                d.rms,
                d.hausdorff
            );
        }
        println!("whole: {:?}", teapot.whole);
        for p in &teapot.parts {
            let d = p.distance;
            let (rms, hausdorff) = match p.name {
                "body" => (0.012, 0.045),
                "lid" => (0.03, 0.09),
                _ => (0.02, 0.1),
            };
            assert!(
                d.rms < rms && d.hausdorff < hausdorff,
                "{}: rms {} Hausdorff {}",
                p.name,
                d.rms,
                d.hausdorff
            );
        }
        let whole = teapot.whole;
        assert!(whole.distance.hausdorff < 0.03, "{whole:?}");
        assert!(whole.distance.rms < 0.01, "{whole:?}");
        // Hidden: the caps and the tubes' roots, a small share of either side.
        assert!(
            whole.hidden_surface < 0.25 && whole.hidden_reference < 0.25,
            "{whole:?}"
        );
        assert!(teapot.combined.validated().is_ok());
    }

    /// Farthest-first keys on the body and the lid, through whichever map fits best: within
    /// the same bounds, and the tubes keep their rings.
    #[test]
    fn farthest_keys_fit_as_closely() {
        let mesh = read_mesh(&data_file("teapot.obj").unwrap()).unwrap();
        let teapot = fit_teapot(&mesh, TEAPOT_KEYS, TeapotLayout::Farthest).unwrap();
        let body = &teapot.parts[0];
        assert_eq!((body.name, body.network.key_count()), ("body", 32));
        assert!(!body.parameterization.contains("sixfold"));
        assert!(body.distance.rms < 0.012 && body.distance.hausdorff < 0.045);
        for tube in &teapot.parts[2..] {
            assert_eq!(tube.parameterization, "tube, sixfold keys");
        }
        assert!(teapot.whole.distance.hausdorff < 0.03, "{:?}", teapot.whole);
    }
}
