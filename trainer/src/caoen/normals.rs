//! The paper's approximate-normal network (§7) with its measured error. The exact normal costs
//! n·m·(p + 1) more multiply–adds than the position; the approximate one keeps the key points
//! and blending and takes the exact unit normal at each key point as its target
//! ([`CaoEnNetwork::normal_network`]), so it costs what the position costs. Its output is not
//! unit length between the keys: normalize before shading. [`NormalFit`] reports the angle
//! between the normalized output and the exact normal over a grid of source points (an
//! icosphere, or a 36 × 18 torus grid).

use super::network::CaoEnNetwork;
use super::texture::{check_points, position_part};
use crate::error::{Error, Result};
use crate::geometry::vector::inner;

/// An approximate-normal network and its angle error against the exact normals.
#[derive(Clone, Debug)]
pub struct NormalFit {
    /// The network whose three outputs point along the surface normal.
    pub network: CaoEnNetwork,
    /// Mean, median and largest angle in degrees over the check points.
    pub mean_degrees: f64,
    /// See [`NormalFit::mean_degrees`].
    pub median_degrees: f64,
    /// See [`NormalFit::mean_degrees`].
    pub max_degrees: f64,
    /// Source points checked (those where the exact normal exists).
    pub checked: usize,
}

/// The approximate-normal network of a sphere or torus shape `network` (its first three
/// outputs are the position).
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than three outputs, or no exact normal at a key point or
/// at any check point.
pub fn approximate_normals(network: &CaoEnNetwork) -> Result<NormalFit> {
    if network.target_dimension() < 3 {
        return Err(Error::invalid(
            "normals need a shape network (at least three outputs)",
        ));
    }
    let shape = position_part(network);
    shape.validate()?;
    let normals = shape.normal_network()?;
    let mut angles: Vec<f64> = check_points(shape.domain)?
        .iter()
        .filter_map(|x| {
            let exact = shape.normal(x)?;
            let approx = normals.position(x);
            let length = inner(&approx, &approx).sqrt();
            if length.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Some(180.0);
            }
            let cos = (0..3).map(|k| exact[k] * approx[k]).sum::<f64>() / length;
            Some(cos.clamp(-1.0, 1.0).acos().to_degrees())
        })
        .collect();
    if angles.is_empty() {
        return Err(Error::invalid(
            "the surface has no exact normal at any check point",
        ));
    }
    angles.sort_by(f64::total_cmp);
    let count = angles.len();
    Ok(NormalFit {
        network: normals,
        mean_degrees: angles.iter().sum::<f64>() / count as f64,
        median_degrees: angles[count / 2],
        max_degrees: angles[count - 1],
        checked: count,
    })
}

#[cfg(test)]
mod tests {
    use neurosurf_core::caoen::Blending;

    use super::super::support::{fibonacci, fitted};
    use super::*;

    /// On the unit sphere (targets = keys) the normal is the source point itself, which the
    /// normalized network through unit targets follows closely; on an ellipsoid the error is
    /// a few degrees and grows with fewer keys.
    #[test]
    fn the_angle_error_is_measured() {
        let keys = fibonacci(104);
        let sphere = fitted(&keys, &keys, Blending::Exponential, true, 12.0);
        let fit = approximate_normals(&sphere).unwrap();
        println!(
            "sphere: {:.3}° mean, {:.3}° max",
            fit.mean_degrees, fit.max_degrees
        );
        assert!(fit.max_degrees < 1.0);
        let mut worst = Vec::new();
        for n in [104, 40] {
            let keys = fibonacci(n);
            let targets: Vec<Vec<f64>> = keys
                .iter()
                .map(|k| vec![k[0], 1.5 * k[1], 0.7 * k[2]])
                .collect();
            let ellipsoid = fitted(&keys, &targets, Blending::Exponential, true, 12.0);
            let fit = approximate_normals(&ellipsoid).unwrap();
            println!(
                "ellipsoid, {n} keys: {:.2}° mean, {:.2}° median, {:.2}° max over {}",
                fit.mean_degrees, fit.median_degrees, fit.max_degrees, fit.checked
            );
            assert!(fit.mean_degrees <= fit.max_degrees && fit.median_degrees <= fit.max_degrees);
            worst.push(fit.max_degrees);
        }
        assert!(worst[0] < 10.0 && worst[1] > worst[0], "{worst:?}");
    }
}
