//! Ray-marched pictures of the convex implicit form (paper §9, §10.1): the network is built
//! from the foot points of a convex polyhedron's faces, loaded into the core
//! (`CaoEnModel<f32>`), and every pixel's ray is intersected with {f ≤ level} by the core's
//! [`ray_intersections`](neurosurf_core::caoen::CaoEnModel::ray_intersections) inside the
//! bounding sphere. Shading is Lambert with the exact normal ∇f/|∇f| (f64, at the entry
//! point), so the picture checks the core's intersections against the f64 gradient.

use neurosurf_core::caoen::{Blending, CaoEnModel, Domain, Ray};
use neurosurf_core::scalar::ScalarKind;

use super::blob::to_blob;
use super::network::CaoEnNetwork;
use super::render::{Rendering, View};
use crate::error::{Error, Result};
use crate::geometry::vector::inner;
use crate::plot::Rgb;

/// The implicit network of a convex polyhedron whose face planes have foot points `feet`
/// (perpendiculars from the origin, which must be inside): wᵢ = tᵢ/|tᵢ|² (eq. 17), p = 1,
/// every target 1, unnormalized, so f(x) = Σᵢ F(x·wᵢ) and the solid is {f ≤ s} for s > 1.
///
/// # Errors
/// [`Error::InvalidInput`] for a zero or non-finite foot point, or an invalid network.
pub fn convex_implicit(feet: &[[f64; 3]], blending: Blending, q: f64) -> Result<CaoEnNetwork> {
    let weights = feet
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let r2 = inner(t, t);
            if r2 > 0.0 && r2.is_finite() {
                Ok(t.iter().map(|c| c / r2).collect())
            } else {
                Err(Error::invalid(format!(
                    "foot point {i} {t:?} is zero or not finite"
                )))
            }
        })
        .collect::<Result<Vec<Vec<f64>>>>()?;
    let network = CaoEnNetwork {
        domain: Domain::Sphere.code(),
        blending: blending.code(),
        normalized: false,
        targets: vec![vec![1.0]; weights.len()],
        sharpness: vec![q; weights.len()],
        weights,
    };
    network.validate()?;
    Ok(network)
}

/// Ray-marches the solid {f ≤ `level`} of an implicit network (m = 3, p = 1, at most the
/// core's default 256 keys) within the sphere of `radius` around the view's centre, one
/// orthographic ray per pixel centre. The depth buffer holds the entry distance.
///
/// # Errors
/// [`Error::InvalidInput`] for a network that is not m = 3, p = 1 or does not fit the
/// core's f32 model, or a non-positive radius.
pub fn ray_marched_image(
    network: &CaoEnNetwork,
    level: f64,
    view: &View,
    radius: f64,
    color: Rgb,
) -> Result<Rendering> {
    network.validate()?;
    if network.source_dimension() != 3 || network.target_dimension() != 1 {
        return Err(Error::invalid(
            "ray marching needs an implicit network with m = 3 and p = 1",
        ));
    }
    if !(radius > 0.0 && radius.is_finite() && level.is_finite()) {
        return Err(Error::invalid(format!(
            "ray marching needs a positive radius and a finite level, got {radius} and {level}"
        )));
    }
    let blob = to_blob(network, ScalarKind::F32, &[])?;
    let model = CaoEnModel::<f32>::from_blob(&blob)
        .map_err(|e| Error::invalid(format!("the core cannot load the implicit network: {e}")))?;
    let mut picture = Rendering::new(view);
    let to_f32 = |v: [f64; 3]| v.map(|c| c as f32);
    for py in 0..view.height {
        for px in 0..view.width {
            let u = (f64::from(px) + 0.5 - 0.5 * f64::from(view.width)) / view.scale;
            let v = (0.5 * f64::from(view.height) - f64::from(py) - 0.5) / view.scale;
            if u * u + v * v >= radius * radius {
                continue;
            }
            let half = (radius * radius - u * u - v * v).sqrt();
            let origin: [f64; 3] =
                [0, 1, 2].map(|k| view.centre[k] + u * view.right[k] + v * view.up[k]);
            let ray = Ray {
                origin: to_f32(origin),
                direction: to_f32(view.direction),
                near: -half as f32,
                far: half as f32,
            };
            let Some(hit) = model.ray_intersections(&ray, level as f32) else {
                continue;
            };
            let t = f64::from(hit.entry);
            let p: Vec<f64> = (0..3).map(|k| origin[k] + t * view.direction[k]).collect();
            let gradient = &network.evaluate(&p).jacobian[0];
            let length = inner(gradient, gradient).sqrt();
            let n = if length > 0.0 {
                [0, 1, 2].map(|k| gradient[k] / length)
            } else {
                view.direction.map(|c| -c)
            };
            picture.splat(
                [f64::from(px) + 0.5, f64::from(py) + 0.5, t],
                0,
                view.shade(n, color),
            );
        }
    }
    Ok(picture)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six faces at distance 1 on the axes with F(s) = s² (s > 0) give f(x) = |x|² exactly:
    /// the solid {f ≤ 1.5} is the ball of radius √1.5, a disc of πr² pixel centres (within
    /// 1 %), entered at depth −√(1.5 − ρ²).
    #[test]
    fn ball_ray_marches_to_a_disc() {
        let feet: Vec<[f64; 3]> = (0..6)
            .map(|i| {
                let mut t = [0.0; 3];
                t[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
                t
            })
            .collect();
        let network = convex_implicit(&feet, Blending::Power, 2.0).unwrap();
        let view =
            View::framing([0.0; 3], 1.6, [0.2, -0.3, -1.0], [0.0, 1.0, 0.0], 160, 160).unwrap();
        let picture = ray_marched_image(&network, 1.5, &view, 2.0, Rgb(40, 120, 220)).unwrap();
        let r = 1.5_f64.sqrt() * view.scale;
        let expected = std::f64::consts::PI * r * r;
        let covered = picture.covered() as f64;
        println!("ray-marched disc: {covered} pixels, πr² = {expected:.0}");
        assert!((covered / expected - 1.0).abs() < 0.01);
        let centre = 80 * 160 + 80;
        let rho = (0.5_f64.powi(2) * 2.0).sqrt() / view.scale;
        assert!((picture.depth[centre] + (1.5 - rho * rho).sqrt()).abs() < 1e-4);
        assert!(convex_implicit(&[[0.0; 3]], Blending::Power, 2.0).is_err());
        assert!(ray_marched_image(&network, 1.5, &view, -1.0, Rgb::WHITE).is_err());
    }
}
