//! Texture and lighting through the network (paper §12.3–12.4).
//!
//! **Texture.** Any texture defined on the source sphere is carried onto the surface: a
//! vertex's texture coordinates are those of its *source* point, not of its position.
//! [`texture_coordinates`] is the parameterization — on the sphere the longitude/latitude map
//! u = atan2(x₂, x₁)/2π mod 1, v = 1 − arccos(x₃)/π (v = 1 at the north pole), on the torus
//! (θ/2π, φ/2π) from x = (cos θ, sin θ, cos φ, sin φ). [`mesh_texture`] gives every triangle
//! corner its `vt`: the vertex's own (u, v) where the triangle does not cross the u = 0 seam,
//! u + 1 on the far side of a seam, and at a pole (where u is undefined) the mean u of the
//! triangle's other corners — so the texture never wraps backwards across a triangle.
//!
//! **Lighting.** The cosine law for a fixed light L is N(x)·L, N the unit surface normal. It is
//! a smooth function on the sphere, so it can ride along as extra outputs of the same network
//! (p = 3 + k for k lights): [`fold_lighting`] keeps the key points, the sharpness and the
//! three position rows of V, and fits one more row of V per light so that the extra output
//! passes through N(wᵢ)·L at every key point (one least-squares solve, as for the shape). The
//! network then returns position and shading in one pass of n·(m + 3 + k) MACs, instead of the
//! n·m·(p + 1) more the exact normal costs. The output is the *unclamped* cosine (Lambert's
//! max(0, ·) is applied by whoever shades: clamping before the fit would put a kink into the
//! function the network interpolates). Accuracy: at the key points the solve's residual
//! (asserted ≤ 10⁻⁹ in f64); between them [`LightingFit`] reports the measured error against
//! the direct cosine law over an icosphere of source points (the tests assert the bound).

use super::fit::fit_shape;
use super::mesh::{CaoEnMesh, icosphere};
use super::network::{CaoEnNetwork, on_domain};
use crate::error::{Error, Result};
use crate::geometry::vector::inner;
use crate::io::TextureCoordinates;

use std::f64::consts::{PI, TAU};

/// Icosphere level of the source points [`fold_lighting`] measures between key points on
/// (642 points).
pub const LIGHTING_CHECK_SUBDIVISIONS: usize = 3;

/// The texture coordinates (u, v) ∈ [0, 1)×[0, 1] of a source point: longitude/latitude on
/// the sphere (m = 3, `domain` 0), (θ/2π, φ/2π) on the torus (`domain` 1, m = 4). At a pole
/// u is 0.
pub fn texture_coordinates(domain: u8, x: &[f64]) -> [f64; 2] {
    let turn = |cos: f64, sin: f64| (sin.atan2(cos) / TAU).rem_euclid(1.0);
    match (domain, x) {
        (1, [c1, s1, c2, s2, ..]) => [turn(*c1, *s1), turn(*c2, *s2)],
        (_, [x1, x2, x3, ..]) => {
            let r = (x1 * x1 + x2 * x2 + x3 * x3).sqrt();
            let z = if r > 0.0 {
                (x3 / r).clamp(-1.0, 1.0)
            } else {
                1.0
            };
            let u = if x1 * x1 + x2 * x2 > 0.0 {
                turn(*x1, *x2)
            } else {
                0.0
            };
            [u, 1.0 - z.acos() / PI]
        }
        _ => [0.0, 0.0],
    }
}

/// The `vt` of every triangle corner of a mapped mesh, from its source points (see the module
/// notes: seams and poles get their own entries). The first `sources.len()` coordinates are
/// the vertices' own (u, v), in vertex order.
pub fn mesh_texture(domain: u8, mapped: &CaoEnMesh) -> TextureCoordinates {
    let mut coordinates: Vec<[f64; 2]> = mapped
        .sources
        .iter()
        .map(|x| texture_coordinates(domain, x))
        .collect();
    let at_pole = |v: u32| {
        let x = &mapped.sources[v as usize];
        domain != 1 && x.len() >= 2 && x[0] * x[0] + x[1] * x[1] < 1e-24
    };
    let mut corners = Vec::with_capacity(mapped.mesh.triangles.len());
    for triangle in &mapped.mesh.triangles {
        let uv = triangle.map(|v| coordinates[v as usize]);
        // Each coordinate that wraps (u on the sphere, u and v on the torus) is unwrapped
        // to within half a turn of the triangle's first corner that is not at a pole.
        let mut wanted = uv;
        let wrapping: &[usize] = if domain == 1 { &[0, 1] } else { &[0] };
        let reference = (0..3).find(|&c| !at_pole(triangle[c])).unwrap_or(0);
        for &axis in wrapping {
            let base = uv[reference][axis];
            for corner in &mut wanted {
                let delta = corner[axis] - base;
                corner[axis] -= delta.round();
            }
        }
        let poles: Vec<usize> = (0..3).filter(|&c| at_pole(triangle[c])).collect();
        if !poles.is_empty() && poles.len() < 3 {
            let others: Vec<f64> = (0..3)
                .filter(|c| !poles.contains(c))
                .map(|c| wanted[c][0])
                .collect();
            let mean = others.iter().sum::<f64>() / others.len() as f64;
            for &c in &poles {
                wanted[c][0] = mean;
            }
        }
        let mut corner_indices = [0_u32; 3];
        for c in 0..3 {
            corner_indices[c] = if wanted[c] == uv[c] {
                triangle[c]
            } else {
                coordinates.push(wanted[c]);
                (coordinates.len() - 1) as u32
            };
        }
        corners.push(corner_indices);
    }
    TextureCoordinates {
        coordinates,
        corners,
    }
}

/// The cosine law N(x)·L at source point x of a shape network (the first three outputs), with
/// L normalized; `None` where the normal is undefined.
pub fn cosine_law(network: &CaoEnNetwork, x: &[f64], light: [f64; 3]) -> Option<f64> {
    let length = inner(&light, &light).sqrt();
    network
        .normal(x)
        .map(|n| inner(&n, &light) / length.max(f64::MIN_POSITIVE))
}

/// A shape network with its lighting folded in, and how well the folded outputs follow the
/// cosine law.
#[derive(Clone, Debug, PartialEq)]
pub struct LightingFit {
    /// p = 3 + k outputs: the position, then N·Lⱼ for each light.
    pub network: CaoEnNetwork,
    /// The lights, normalized.
    pub lights: Vec<[f64; 3]>,
    /// Largest |shading output − N·L| at the key points, over all lights.
    pub max_error_at_keys: f64,
    /// Largest |shading output − N·L| over the icosphere of
    /// [`LIGHTING_CHECK_SUBDIVISIONS`], over all lights.
    pub max_error_between: f64,
    /// Root-mean-square of the same.
    pub rms_error_between: f64,
}

/// The network restricted to its first three outputs (the position of a shape with extra
/// channels); the network itself when p ≤ 3.
pub fn position_part(network: &CaoEnNetwork) -> CaoEnNetwork {
    CaoEnNetwork {
        targets: network
            .targets
            .iter()
            .map(|t| t.iter().take(3).copied().collect())
            .collect(),
        ..network.clone()
    }
}

/// Folds the cosine law for each of `lights` into extra outputs of the sphere or torus shape
/// `network` (its first three outputs are the position; further outputs are replaced), fitted
/// through N(wᵢ)·L at the key points; see the module notes.
///
/// # Errors
/// [`Error::InvalidInput`] for no light or a zero one, more than p = 8 outputs in all, a
/// network without normals (not a sphere or torus shape) or with a vanishing normal at a key
/// point, or when the solve fails.
pub fn fold_lighting(network: &CaoEnNetwork, lights: &[[f64; 3]]) -> Result<LightingFit> {
    let shape = position_part(network);
    shape.validate()?;
    let total = 3 + lights.len();
    if lights.is_empty() || total > neurosurf_core::caoen::MAX_TARGET_DIMENSION {
        return Err(Error::invalid(format!(
            "1 to {} lights fit beside the position, got {}",
            neurosurf_core::caoen::MAX_TARGET_DIMENSION - 3,
            lights.len()
        )));
    }
    let lights = lights
        .iter()
        .map(|l| {
            let length = inner(l, l).sqrt();
            if length > 0.0 && length.is_finite() {
                Ok(l.map(|c| c / length))
            } else {
                Err(Error::invalid(format!("the light {l:?} has no direction")))
            }
        })
        .collect::<Result<Vec<[f64; 3]>>>()?;
    if shape.target_dimension() != 3 {
        return Err(Error::invalid(
            "lighting needs a shape network (at least three outputs)",
        ));
    }
    let keys: Vec<Vec<f64>> = shape
        .weights
        .iter()
        .map(|w| on_domain(shape.domain, w))
        .collect();
    let shading = |x: &[f64]| -> Option<Vec<f64>> {
        let n = shape.normal(x)?;
        Some(lights.iter().map(|l| inner(&n, l)).collect())
    };
    let values = keys
        .iter()
        .enumerate()
        .map(|(i, x)| {
            shading(x).ok_or_else(|| {
                Error::invalid(format!(
                    "no surface normal at key point {i} (not a sphere or torus shape, or a \
                     singular point)"
                ))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let channels = CaoEnNetwork {
        targets: vec![vec![0.0; lights.len()]; shape.key_count()],
        ..shape.clone()
    };
    let channels = fit_shape(&channels, &keys, &values)?;
    let mut folded = shape.clone();
    for (t, extra) in folded.targets.iter_mut().zip(&channels.targets) {
        t.extend(extra);
    }
    folded.validate()?;
    let error_at = |x: &[f64], expected: &[f64]| -> f64 {
        let y = folded.position(x);
        expected
            .iter()
            .zip(&y[3..])
            .map(|(e, y)| (e - y).abs())
            .fold(0.0, f64::max)
    };
    let max_error_at_keys = keys
        .iter()
        .zip(&values)
        .map(|(x, v)| error_at(x, v))
        .fold(0.0, f64::max);
    let check = check_points(shape.domain)?;
    let (mut max_error_between, mut squares, mut count) = (0.0_f64, 0.0, 0_usize);
    for x in &check {
        let Some(expected) = shading(x) else { continue };
        let y = folded.position(x);
        for (e, y) in expected.iter().zip(&y[3..]) {
            max_error_between = max_error_between.max((e - y).abs());
            squares += (e - y) * (e - y);
            count += 1;
        }
    }
    Ok(LightingFit {
        network: folded,
        lights,
        max_error_at_keys,
        max_error_between,
        rms_error_between: (squares / count.max(1) as f64).sqrt(),
    })
}

/// Source points between the key points: the icosphere of [`LIGHTING_CHECK_SUBDIVISIONS`] on
/// the sphere, a 36 × 18 grid on the torus.
pub(super) fn check_points(domain: u8) -> Result<Vec<Vec<f64>>> {
    if domain == 1 {
        return Ok(super::mesh::torus_grid(36, 18)?.sources);
    }
    Ok(icosphere(LIGHTING_CHECK_SUBDIVISIONS)?
        .positions
        .iter()
        .map(|p| p.to_vec())
        .collect())
}

#[cfg(test)]
mod tests {
    use neurosurf_core::caoen::{Blending, CaoEnModel};
    use neurosurf_core::scalar::ScalarKind;

    use super::super::support::{fibonacci, fitted};
    use super::super::{sphere_mesh, to_blob, torus_mesh};
    use super::*;
    use crate::io::write_textured_obj;

    /// `n` keys through an ellipsoid with radii 1, 1.5, 0.7 (exponential, q = 6).
    fn ellipsoid(n: usize) -> CaoEnNetwork {
        let keys = fibonacci(n);
        let targets: Vec<Vec<f64>> = keys
            .iter()
            .map(|k| vec![k[0], 1.5 * k[1], 0.7 * k[2]])
            .collect();
        fitted(&keys, &targets, Blending::Exponential, false, 6.0)
    }

    /// The (vertex, vt) index pairs of one face's corners.
    type Face = [(usize, usize); 3];

    /// The `vt` lines and the faces of an OBJ file.
    fn read_obj_texture(text: &str) -> (Vec<[f64; 2]>, Vec<Face>) {
        let mut vt = Vec::new();
        let mut faces = Vec::new();
        for line in text.lines() {
            let mut words = line.split_whitespace();
            match words.next() {
                Some("vt") => {
                    let c: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
                    vt.push([c[0], c[1]]);
                }
                Some("f") => {
                    let corners: Vec<(usize, usize)> = words
                        .map(|w| {
                            let mut parts = w.split('/');
                            let v: usize = parts.next().unwrap().parse().unwrap();
                            let t: usize = parts.next().unwrap().parse().unwrap();
                            (v - 1, t - 1)
                        })
                        .collect();
                    faces.push([corners[0], corners[1], corners[2]]);
                }
                _ => {}
            }
        }
        (vt, faces)
    }

    /// Writes the textured mesh and checks every corner's `vt` against the parameterization
    /// of its source point (equal, up to whole turns along the wrapping axes; u free at a
    /// pole) and that no triangle spans half a turn or more in texture space.
    fn check_written_texture(domain: u8, mapped: &CaoEnMesh) {
        let texture = mesh_texture(domain, mapped);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("textured.obj");
        write_textured_obj(&path, &mapped.mesh, Some(&mapped.normals), Some(&texture)).unwrap();
        let (vt, faces) = read_obj_texture(&std::fs::read_to_string(&path).unwrap());
        assert_eq!(vt, texture.coordinates, "vt round trip");
        assert_eq!(faces.len(), mapped.mesh.triangles.len());
        for (i, x) in mapped.sources.iter().enumerate() {
            assert_eq!(vt[i], texture_coordinates(domain, x), "vertex {i}");
        }
        let wraps = if domain == 1 {
            [true, true]
        } else {
            [true, false]
        };
        for (face, triangle) in faces.iter().zip(&mapped.mesh.triangles) {
            for (c, &(v, t)) in face.iter().enumerate() {
                assert_eq!(v, triangle[c] as usize);
                let x = &mapped.sources[v];
                let expected = texture_coordinates(domain, x);
                let pole = domain == 0 && x[0].hypot(x[1]) < 1e-12;
                for axis in 0..2 {
                    let delta = vt[t][axis] - expected[axis];
                    if axis == 0 && pole {
                        continue;
                    }
                    let off = if wraps[axis] {
                        delta - delta.round()
                    } else {
                        delta
                    };
                    assert!(off.abs() < 1e-12, "corner {c} of {face:?}: {:?}", vt[t]);
                }
            }
            for axis in 0..2 {
                let values = face.map(|(_, t)| vt[t][axis]);
                let span = values.iter().fold(f64::MIN, |a, &b| a.max(b))
                    - values.iter().fold(f64::MAX, |a, &b| a.min(b));
                assert!(span < 0.5, "{face:?} spans {span} along axis {axis}");
            }
        }
    }

    #[test]
    fn sphere_vt_values_are_the_source_parameterization() {
        let mapped = sphere_mesh(&ellipsoid(26), 3).unwrap();
        // The level-3 icosphere has both poles: they get the mean u of their triangles.
        let poles = mapped.sources.iter().filter(|x| x[0].hypot(x[1]) < 1e-12);
        assert_eq!(poles.count(), 2);
        check_written_texture(0, &mapped);
        // (u, v) is the sphere point's longitude and latitude: it maps back onto x.
        for x in &mapped.sources {
            let [u, v] = texture_coordinates(0, x);
            let (theta, phi) = (PI * (1.0 - v), TAU * u);
            let back = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            assert!((0..3).all(|k| (back[k] - x[k]).abs() < 1e-12), "{x:?}");
        }
    }

    #[test]
    fn torus_vt_values_are_the_angles() {
        let keys: Vec<Vec<f64>> = super::super::torus_grid(6, 4).unwrap().sources;
        let targets: Vec<Vec<f64>> = keys
            .iter()
            .map(|x| {
                let r = 1.0 + 0.4 * x[2];
                vec![r * x[0], r * x[1], 0.4 * x[3]]
            })
            .collect();
        let built = super::super::from_key_points(
            neurosurf_core::caoen::Domain::Torus,
            Blending::Exponential,
            false,
            &keys,
            &targets,
            2.0,
        )
        .unwrap();
        let network = fit_shape(&built, &keys, &targets).unwrap();
        let mapped = torus_mesh(&network, 24, 12).unwrap();
        check_written_texture(1, &mapped);
        for (i, x) in mapped.sources.iter().enumerate() {
            let [u, v] = texture_coordinates(1, x);
            assert!((u - (i / 12) as f64 / 24.0).abs() < 1e-12);
            assert!((v - (i % 12) as f64 / 12.0).abs() < 1e-12);
        }
    }

    #[test]
    fn folded_lighting_follows_the_cosine_law() {
        // 104 keys: the shading has the shape's resolution. With 26 keys (q = 3 … 6) the error
        // between keys measures 0.10 … 0.29 (RMS 0.02 … 0.08): the surface's own normal wobbles
        // between the keys, and one channel through 26 values cannot follow it.
        let shape = ellipsoid(104);
        let lights = [[0.0, 0.0, 1.0], [1.0, -1.0, 0.5]];
        let fit = fold_lighting(&shape, &lights).unwrap();
        assert_eq!(fit.network.target_dimension(), 5);
        // At the key points: the solve interpolates.
        assert!(fit.max_error_at_keys <= 1e-9, "{}", fit.max_error_at_keys);
        // Between them, recomputed here against the direct cosine law at other points (a
        // Fibonacci lattice of 500, not the icosphere the fit reports on): measured 0.0055
        // max, 0.0009 RMS on the icosphere.
        let (mut worst, mut squares) = (0.0_f64, 0.0);
        let points = fibonacci(500);
        for x in &points {
            let y = fit.network.position(x);
            assert_eq!(&y[..3], &shape.position(x)[..], "the position is unchanged");
            for (j, &light) in lights.iter().enumerate() {
                let e = y[3 + j] - cosine_law(&shape, x, light).unwrap();
                worst = worst.max(e.abs());
                squares += e * e;
            }
        }
        let rms = (squares / (2 * points.len()) as f64).sqrt();
        println!(
            "lighting: at keys {:.1e}, between (icosphere) max {:.4} RMS {:.4}, (lattice) max {worst:.4} RMS {rms:.4}",
            fit.max_error_at_keys, fit.max_error_between, fit.rms_error_between
        );
        assert!(worst < 0.01 && rms < 0.002, "max {worst}, RMS {rms}");
        assert!(fit.max_error_between < 0.01 && fit.rms_error_between < 0.002);
        // The core evaluates the folded network: its f32 shading follows the f64 one.
        let blob = to_blob(&fit.network, ScalarKind::F32, b"lit").unwrap();
        let model = CaoEnModel::<f32>::from_blob(&blob).unwrap();
        for x in points.iter().take(50) {
            let y: [f32; 5] = model.eval(&[x[0] as f32, x[1] as f32, x[2] as f32]);
            let reference = fit.network.position(x);
            for j in 3..5 {
                assert!((f64::from(y[j]) - reference[j]).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn lighting_refuses_bad_input() {
        let shape = ellipsoid(26);
        assert!(fold_lighting(&shape, &[]).is_err());
        assert!(fold_lighting(&shape, &[[0.0; 3]]).is_err());
        assert!(fold_lighting(&shape, &[[0.0, 0.0, 1.0]; 6]).is_err());
    }
}
