//! A spherical parameterization of a closed genus-0 mesh: every vertex gets a point of the
//! unit sphere, so that a Cao En network can be fitted to the mesh (y(xⱼ) ≈ pⱼ).
//!
//! # Method: a planar Tutte embedding, lifted to the sphere and balanced by area
//!
//! 1. **Cut.** Around the vertex with the largest one-ring area, the smallest geodesic ball
//!    (Dijkstra along edges) holding [`CAP_SHARE`] of the area becomes the cap, if it is a
//!    disk bounded by one simple loop (else half the share is tried, down to the vertex's own
//!    one-ring). The loop cuts the mesh into two disks: the cap and the body.
//! 2. **Planar embedding.** The loop goes onto the unit circle by arc length, and every other
//!    vertex of either disk to the weighted mean of its neighbours: one sparse symmetric
//!    positive-definite solve (faer's Cholesky) for both coordinates. With positive weights
//!    and a convex boundary this is Tutte's (Floater's) embedding, free of folds by
//!    construction, however far the mesh is from star-shaped.
//! 3. **Lift.** Inverse stereographic projection maps the body's disk onto the sphere below
//!    the loop and the cap's disk, inverted through the circle, above it, the loop at the
//!    height where the cap's share of the sphere equals its share of the mesh area. A loop of
//!    tens of edges matters: a single vertex's ring of 6–8 leaves the body's embedding far from
//!    the lift's area element, and balancing then stalls.
//! 4. **Balance.** Uniform weights shrink protrusions (the bunny's ears to 1/6 000 of their
//!    share of area), which starves them of key points. As in Yoshizawa, Belyaev & Seidel's
//!    stretch minimization (2004), each edge's weight is divided by (σᵢσⱼ)^0.6, σ being a
//!    vertex's stretch √(mesh area share / sphere area share), and both disks solved again;
//!    rounds stop after 3 without a new least worst stretch, and the best one is kept. The
//!    exponent 0.6 converges steadily (1.0 oscillates and folds the lift after a few rounds).
//! 5. **Check.** The lift maps straight planar edges onto circle arcs, not great circles, so a
//!    sliver next to a long edge can flip on the sphere. In each round's candidate, vertices of
//!    flipped triangles and their neighbours are relaxed to the normalized mean of their
//!    neighbours until none is flipped; a round that cannot be repaired does not count, and
//!    when none can, the call fails.
//!
//! Measured on this machine (release build; stretch as defined above):
//!
//! | mesh | vertices | worst stretch | `caoen fit-mesh --keys 256` in all |
//! |---|---|---|---|
//! | spot | 2 930 | 1.65 | 0.7–1.0 s |
//! | fandisk | 6 475 | 2.07 | 1.1 s |
//! | stanford-bunny, 1 113 unused vertices dropped, 5 holes capped | 35 192 | 3.04 | 9–15 s |

use super::topology::{check_sphere_topology, neighbours};
use crate::error::{Error, Result};
use crate::io::Mesh;
use crate::parametric::weighted_means;

/// Most balancing rounds after the uniform embedding.
pub const BALANCE_ROUNDS: usize = 30;
/// Each round divides an edge's weight by (σᵢσⱼ) to this power.
const STRETCH_EXPONENT: f64 = 0.6;
/// Rounds without a new least worst stretch before balancing stops.
const PATIENCE: usize = 3;
/// Most rounds of local relaxation around flipped triangles.
const REPAIR_ROUNDS: usize = 20;
/// Sweeps per repair round.
const REPAIR_SWEEPS: usize = 20;

/// A parameterization: one unit vector per mesh vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct SphericalMap {
    /// The sphere point of every vertex.
    pub points: Vec<[f64; 3]>,
    /// Disk solves done (the uniform one and the balancing rounds).
    pub rounds: usize,
    /// The smallest triangle area on the sphere divided by the mean (positive: no flips).
    pub smallest_area_ratio: f64,
    /// The largest per-vertex √(mesh area share / sphere area share): 1 for an
    /// area-preserving map.
    pub area_distortion: f64,
}

/// Parameterizes a closed genus-0 mesh onto the unit sphere (see the module documentation).
///
/// # Errors
/// [`Error::InvalidInput`] when the mesh is not a closed oriented genus-0 surface, when its
/// disk cannot be solved, or when the map still folds after the repair.
pub fn spherical_parameterization(mesh: &Mesh) -> Result<SphericalMap> {
    check_sphere_topology(mesh)?;
    let n = mesh.positions.len();
    let mesh_areas: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| triangle_area(&mesh.positions, t))
        .collect();
    let total: f64 = mesh_areas.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::invalid(format!(
            "the mesh's area is {total}: a sphere map needs a surface with area"
        )));
    }
    let disk = Disk::cut(mesh, &mesh_areas)?;
    let mut weights = vec![1.0; disk.edges.len()];
    let mut best: Option<(Vec<[f64; 3]>, f64)> = None;
    let mut rounds = 0;
    let mut since_best = 0;
    for _ in 0..=BALANCE_ROUNDS {
        let points = disk.lift(&disk.solve(&weights)?, mesh);
        rounds += 1;
        let stretch = vertex_stretch(mesh, &points, &mesh_areas, total, n);
        let worst = stretch.iter().copied().fold(1.0, f64::max);
        // A round counts when its lift can be repaired to no flip at all.
        let better = best.as_ref().is_none_or(|b| worst < b.1);
        if better && let Some(repaired) = repaired(mesh, points) {
            best = Some((repaired, worst));
            since_best = 0;
        } else {
            since_best += 1;
            if since_best >= PATIENCE {
                break;
            }
        }
        for (w, &(a, b)) in weights.iter_mut().zip(&disk.edges) {
            *w /= (stretch[a as usize] * stretch[b as usize]).powf(STRETCH_EXPONENT);
        }
    }
    let Some((points, area_distortion)) = best else {
        return Err(Error::invalid(format!(
            "the spherical parameterization folds triangles in every one of its {rounds} \
             rounds: is the mesh free of self-intersections and degenerate triangles?"
        )));
    };
    let ratio = smallest_area_ratio(mesh, &points);
    Ok(SphericalMap {
        points,
        rounds,
        smallest_area_ratio: ratio,
        area_distortion,
    })
}

/// Where a vertex lies relative to the cut.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Side {
    /// On the loop, fixed on the unit circle.
    Ring,
    /// Inside the cap (lifted above the loop, around the north pole).
    Cap,
    /// In the rest of the mesh (lifted below the loop).
    Body,
}

/// The mesh cut along a loop into two disks: a small cap around the pole and the body. Each
/// is embedded in the unit disk with the loop on the circle; the body is lifted below the
/// loop and the cap, inverted through the circle, above it.
struct Disk {
    /// The loop in the cap's order, and its places on the unit circle.
    ring: Vec<(usize, [f64; 2])>,
    /// Each vertex's side.
    side: Vec<Side>,
    /// Every edge (a < b).
    edges: Vec<(u32, u32)>,
    /// The cap's share of the mesh area (and of the sphere).
    cap_share: f64,
}

/// The cap's target share of the mesh area: large enough that its loop has tens of edges
/// (a single vertex's ring of 6–8 leaves the body's embedding far from the lift's area
/// element), small enough to stay a disk on any mesh.
const CAP_SHARE: f64 = 0.01;

impl Disk {
    fn cut(mesh: &Mesh, areas: &[f64]) -> Result<Disk> {
        let n = mesh.positions.len();
        let total: f64 = areas.iter().sum();
        let mut star = vec![0.0; n];
        for (t, &a) in mesh.triangles.iter().zip(areas) {
            for &v in t {
                star[v as usize] += a;
            }
        }
        let pole = (0..n)
            .max_by(|&a, &b| star[a].total_cmp(&star[b]).then(b.cmp(&a)))
            .unwrap_or(0);
        let adjacent = neighbours(mesh);
        let order = geodesic_order(mesh, &adjacent, pole);
        // Shrink the target until the ball of that area is a disk bounded by one simple loop;
        // the pole's one-ring always is.
        let mut share = CAP_SHARE;
        let (cap, ring) = loop {
            let star_only = share * total <= star[pole];
            let candidate = if star_only {
                (0..mesh.triangles.len())
                    .filter(|&t| mesh.triangles[t].contains(&(pole as u32)))
                    .collect()
            } else {
                ball(mesh, areas, &order, share * total)
            };
            if let Some(found) = disk_region(mesh, &candidate)? {
                break found;
            }
            if star_only {
                return Err(Error::invalid(format!(
                    "the triangles around vertex {pole} (from 0) do not form a disk: the mesh \
                     is not a manifold there"
                )));
            }
            share /= 2.0;
        };
        let cap_area: f64 = cap.iter().map(|&t| areas[t]).sum();
        let mut side = vec![Side::Body; n];
        for &t in &cap {
            for &v in &mesh.triangles[t] {
                side[v as usize] = Side::Cap;
            }
        }
        for &v in &ring {
            side[v as usize] = Side::Ring;
        }
        let p = &mesh.positions;
        let lengths: Vec<f64> = (0..ring.len())
            .map(|i| distance(p[ring[i] as usize], p[ring[(i + 1) % ring.len()] as usize]))
            .collect();
        let perimeter: f64 = lengths.iter().sum();
        let mut along = 0.0;
        let mut placed = Vec::with_capacity(ring.len());
        for (&v, &l) in ring.iter().zip(&lengths) {
            let angle = if perimeter > 0.0 {
                std::f64::consts::TAU * along / perimeter
            } else {
                std::f64::consts::TAU * placed.len() as f64 / ring.len() as f64
            };
            placed.push((v as usize, [angle.cos(), angle.sin()]));
            along += l;
        }
        let mut edges: Vec<(u32, u32)> = adjacent
            .iter()
            .enumerate()
            .flat_map(|(a, around)| {
                around
                    .iter()
                    .filter(move |&&b| (a as u32) < b)
                    .map(move |&b| (a as u32, b))
            })
            .collect();
        edges.sort_unstable();
        Ok(Disk {
            ring: placed,
            side,
            edges,
            cap_share: (cap_area / total).clamp(1e-9, 0.5),
        })
    }

    /// The planar embeddings of both disks for edge weights `weights`: every vertex off the
    /// loop at the weighted mean of its neighbours (no edge joins the cap to the body, so one
    /// solve serves both).
    fn solve(&self, weights: &[f64]) -> Result<Vec<[f64; 2]>> {
        weighted_means(self.side.len(), &self.edges, weights, &self.ring)
    }

    /// Inverse stereographic projection: the body's disk onto the sphere below the loop, the
    /// cap's (inverted through the circle) above it; mirrored if needed so that triangles wind
    /// outward.
    fn lift(&self, plane: &[[f64; 2]], mesh: &Mesh) -> Vec<[f64; 3]> {
        // The loop at |z| = s lies at height h = (s² − 1)/(s² + 1), under a cap of share
        // (1 − h)/2 = f: s² = (1 − f)/f.
        let scale = ((1.0 - self.cap_share) / self.cap_share).sqrt();
        let mut points: Vec<[f64; 3]> = plane
            .iter()
            .zip(&self.side)
            .map(|(u, side)| {
                let z = [scale * u[0], scale * u[1]];
                let r2 = z[0] * z[0] + z[1] * z[1];
                if *side == Side::Cap {
                    // z ↦ z/|z|²: the same circle, the disk's centre at the north pole.
                    let c = [u[0] / scale, u[1] / scale];
                    let c2 = c[0] * c[0] + c[1] * c[1];
                    [2.0 * c[0], 2.0 * c[1], 1.0 - c2].map(|x| x / (1.0 + c2))
                } else {
                    [2.0 * z[0], 2.0 * z[1], r2 - 1.0].map(|c| c / (r2 + 1.0))
                }
            })
            .collect();
        let winding: f64 = mesh.triangles.iter().map(|t| orientation(&points, t)).sum();
        if winding < 0.0 {
            for p in &mut points {
                p[0] = -p[0];
            }
        }
        points
    }
}

/// The vertices in order of their shortest-path distance along edges from `start`.
fn geodesic_order(mesh: &Mesh, adjacent: &[Vec<u32>], start: usize) -> Vec<usize> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = mesh.positions.len();
    let mut best = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut heap = BinaryHeap::new();
    best[start] = 0.0;
    heap.push((Reverse(Distance(0.0)), start));
    while let Some((Reverse(Distance(d)), v)) = heap.pop() {
        if done[v] {
            continue;
        }
        done[v] = true;
        order.push(v);
        for &u in &adjacent[v] {
            let u = u as usize;
            let next = d + distance(mesh.positions[v], mesh.positions[u]);
            if next < best[u] {
                best[u] = next;
                heap.push((Reverse(Distance(next)), u));
            }
        }
    }
    order
}

/// A totally ordered distance for the heap.
#[derive(Copy, Clone, Debug, PartialEq)]
struct Distance(f64);
impl Eq for Distance {}
impl PartialOrd for Distance {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Distance {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The triangles whose vertices are all among the first k of `order`, for the smallest k
/// whose triangles reach `area`.
fn ball(mesh: &Mesh, areas: &[f64], order: &[usize], area: f64) -> Vec<usize> {
    let mut rank = vec![usize::MAX; mesh.positions.len()];
    for (r, &v) in order.iter().enumerate() {
        rank[v] = r;
    }
    // A triangle joins the ball when its last vertex does.
    let mut joins: Vec<(usize, usize)> = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(t, tri)| (tri.iter().map(|&v| rank[v as usize]).max().unwrap_or(0), t))
        .collect();
    joins.sort_unstable();
    let mut sum = 0.0;
    let mut chosen = Vec::new();
    let mut last = 0;
    for &(k, t) in &joins {
        if sum >= area && k != last {
            break;
        }
        sum += areas[t];
        chosen.push(t);
        last = k;
    }
    chosen
}

/// The triangles `region` and its boundary loop, when the region is a disk bounded by one
/// simple loop (V − E + F = 1) whose complement is not empty; `None` otherwise.
fn disk_region(mesh: &Mesh, region: &[usize]) -> Result<Option<(Vec<usize>, Vec<u32>)>> {
    if region.is_empty() || region.len() >= mesh.triangles.len() {
        return Ok(None);
    }
    let triangles: Vec<[u32; 3]> = region.iter().map(|&t| mesh.triangles[t]).collect();
    let Ok(loops) = crate::geometry::boundary_loops(&triangles) else {
        return Ok(None);
    };
    if loops.len() != 1 {
        return Ok(None);
    }
    let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
    vertices.sort_unstable();
    vertices.dedup();
    let mut edge_set: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(super::topology::edges)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edge_set.sort_unstable();
    edge_set.dedup();
    let euler = vertices.len() as i64 - edge_set.len() as i64 + triangles.len() as i64;
    if euler != 1 {
        return Ok(None);
    }
    let ring = loops.into_iter().next().unwrap_or_default();
    Ok(Some((region.to_vec(), ring)))
}

/// `points` with its flipped triangles repaired ([`repair_flips`]), or `None` if some stay
/// flipped or degenerate.
fn repaired(mesh: &Mesh, mut points: Vec<[f64; 3]>) -> Option<Vec<[f64; 3]>> {
    repair_flips(mesh, &mut points);
    let ratio = smallest_area_ratio(mesh, &points);
    (ratio > 0.0 && ratio.is_finite()).then_some(points)
}

/// Relaxes the vertices of flipped triangles and their neighbours to the normalized mean of
/// their neighbours, a few sweeps at a time, until nothing is flipped or the rounds run out.
fn repair_flips(mesh: &Mesh, points: &mut [[f64; 3]]) {
    let adjacent = neighbours(mesh);
    for _ in 0..REPAIR_ROUNDS {
        let mut active: Vec<usize> = mesh
            .triangles
            .iter()
            .filter(|t| {
                orientation(points, t).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            })
            .flat_map(|t| t.map(|v| v as usize))
            .collect();
        if active.is_empty() {
            return;
        }
        let seeds = active.clone();
        for v in seeds {
            active.extend(adjacent[v].iter().map(|&u| u as usize));
        }
        active.sort_unstable();
        active.dedup();
        for _ in 0..REPAIR_SWEEPS {
            for &v in &active {
                let mut sum = [0.0; 3];
                for &u in &adjacent[v] {
                    for k in 0..3 {
                        sum[k] += points[u as usize][k];
                    }
                }
                points[v] = normalize_or_pole(sum);
            }
        }
    }
}

/// Per vertex, √(mesh area / sphere area) of its triangles, each as a share of the whole
/// (1 where the map preserves area; larger where the sphere shrinks the mesh).
fn vertex_stretch(
    mesh: &Mesh,
    points: &[[f64; 3]],
    mesh_areas: &[f64],
    total: f64,
    n: usize,
) -> Vec<f64> {
    let sphere_areas: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| triangle_area(points, t))
        .collect();
    let sphere_total: f64 = sphere_areas.iter().sum();
    let mut sum = vec![0.0; n];
    let mut weight = vec![0.0; n];
    for ((t, &a), &s) in mesh.triangles.iter().zip(mesh_areas).zip(&sphere_areas) {
        let ratio = (a / total) / (s / sphere_total).max(1e-300);
        for &v in t {
            sum[v as usize] += a * ratio;
            weight[v as usize] += a;
        }
    }
    sum.iter()
        .zip(&weight)
        .map(|(s, w)| {
            if *w > 0.0 {
                (s / w).sqrt().clamp(1e-3, 1e3)
            } else {
                1.0
            }
        })
        .collect()
}

fn triangle_area(positions: &[[f64; 3]], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| positions[v as usize]);
    let (u, v) = (
        [0, 1, 2].map(|k| b[k] - a[k]),
        [0, 1, 2].map(|k| c[k] - a[k]),
    );
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// Triangles whose image on the sphere is flipped or degenerate (det[a, b, c] ≤ 0).
pub fn flipped_triangles(mesh: &Mesh, points: &[[f64; 3]]) -> usize {
    mesh.triangles
        .iter()
        .filter(|t| orientation(points, t).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater))
        .count()
}

/// det[a, b, c]: six times the signed volume of the tetrahedron (0, a, b, c), positive for a
/// triangle wound counter-clockwise seen from outside the sphere.
fn orientation(points: &[[f64; 3]], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| points[v as usize]);
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The smallest signed triangle orientation over the mean (NaN-safe: NaN gives −1).
fn smallest_area_ratio(mesh: &Mesh, points: &[[f64; 3]]) -> f64 {
    let values: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| orientation(points, t))
        .collect();
    let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
    let smallest = values.iter().copied().fold(f64::INFINITY, f64::min);
    let ratio = smallest / mean;
    if ratio.is_nan() { -1.0 } else { ratio }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// v/|v|, or the north pole for a zero vector (the relaxation moves it on).
pub(crate) fn normalize_or_pole(v: [f64; 3]) -> [f64; 3] {
    let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if r > 0.0 && r.is_finite() {
        v.map(|c| c / r)
    } else {
        [0.0, 0.0, 1.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::icosphere;

    /// A sphere with five long thin spikes (a projection from the centre folds around each)
    /// maps without a fold, and balancing leaves every vertex within a stretch of 3.
    #[test]
    fn spikes_map_without_folds_and_keep_their_area() {
        let mut mesh = icosphere(4).unwrap();
        let spikes = [
            [1.0, 0.0, 0.0],
            [-0.6, 0.8, 0.0],
            [0.0, -0.6, 0.8],
            [0.0, 0.0, -1.0],
            [0.6, 0.6, 0.53],
        ];
        for p in &mut mesh.positions {
            let bump: f64 = spikes
                .iter()
                .map(|d| {
                    let cos = (p[0] * d[0] + p[1] * d[1] + p[2] * d[2])
                        / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    1.5 * (-(1.0 - cos) / 0.02).exp()
                })
                .sum();
            *p = p.map(|c| c * (1.0 + bump));
        }
        let map = spherical_parameterization(&mesh).unwrap();
        assert_eq!(flipped_triangles(&mesh, &map.points), 0);
        assert!(map.smallest_area_ratio > 0.0);
        assert!(map.area_distortion < 3.0, "{}", map.area_distortion);
        assert!(map.rounds >= 2);
        for p in &map.points {
            assert!((p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.0).abs() < 1e-9);
        }
    }
}
