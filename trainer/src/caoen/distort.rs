//! Distortion of space by a 4-D hypersphere → 3-D network (paper §11, §12.2).
//!
//! The ball of `radius` around `centre` is the projection of a hemisphere of S³: a point p
//! of the ball, u = (p − centre)/radius with |u| ≤ 1, lifts to x = (u, √(1 − |u|²)). A
//! network with m = 4, p = 3 maps x back to space, so it distorts everything inside the ball.
//! [`Distortion::identity`] is the network W = V = the six axis points ±eₖ (no fourth
//! component) with q = 1 and power blending, unnormalized: y = Σₖ max(0, ±uₖ)(±eₖ) = u
//! exactly. Each control added by [`Distortion::add_control`] is one more key point: the
//! lift w of a point c of the ball, with target d/radius and whole sharpness q, so
//!
//! p′ = p + Σ_c d_c · max(0, x·w_c)^q_c,
//!
//! a displacement of d at the control itself (x = w gives 1), fading with the angle on S³ —
//! an arbitrary number of controls, as the paper says.

use neurosurf_core::caoen::{Blending, Domain};

use super::network::CaoEnNetwork;
use crate::error::{Error, Result};
use crate::geometry::vector::inner;
use crate::io::Mesh;

/// A distortion of the ball of `radius` around `centre`.
#[derive(Clone, Debug, PartialEq)]
pub struct Distortion {
    network: CaoEnNetwork,
    centre: [f64; 3],
    radius: f64,
}

impl Distortion {
    /// The identity on the ball of `radius` around `centre`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a non-finite centre or a non-positive radius.
    pub fn identity(centre: [f64; 3], radius: f64) -> Result<Distortion> {
        if !(radius > 0.0 && radius.is_finite()) || centre.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(format!(
                "a distortion needs a finite centre and a positive radius, got {centre:?}, \
                 {radius}"
            )));
        }
        let axes: Vec<[f64; 3]> = (0..6)
            .map(|i| {
                let mut a = [0.0; 3];
                a[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
                a
            })
            .collect();
        let network = CaoEnNetwork {
            domain: Domain::Sphere.code(),
            blending: Blending::Power.code(),
            normalized: false,
            weights: axes.iter().map(|a| vec![a[0], a[1], a[2], 0.0]).collect(),
            targets: axes.iter().map(|a| a.to_vec()).collect(),
            sharpness: vec![1.0; 6],
        };
        Ok(Distortion {
            network,
            centre,
            radius,
        })
    }

    /// Adds a control at `at` (inside the ball) moving it by `displacement`, with an
    /// influence that falls as cos^q of the angle on S³ (larger q: more local).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a point outside the ball, a non-finite displacement, q
    /// outside 1 … 64, or more controls than a network may have.
    pub fn add_control(&mut self, at: [f64; 3], displacement: [f64; 3], q: u8) -> Result<()> {
        let w = self.lift(at)?;
        if displacement.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid("a control displacement is not finite"));
        }
        let mut network = self.network.clone();
        network.weights.push(w.to_vec());
        network
            .targets
            .push(displacement.iter().map(|d| d / self.radius).collect());
        network.sharpness.push(f64::from(q.max(1)));
        network.validate()?;
        self.network = network;
        Ok(())
    }

    /// The network (m = 4, p = 3) in ball coordinates.
    pub fn network(&self) -> &CaoEnNetwork {
        &self.network
    }

    /// The point of S³ above `p`.
    fn lift(&self, p: [f64; 3]) -> Result<[f64; 4]> {
        let u = [0, 1, 2].map(|k| (p[k] - self.centre[k]) / self.radius);
        let r2 = inner(&u, &u);
        if r2.is_nan() || r2 > 1.0 + 1e-12 {
            return Err(Error::invalid(format!(
                "{p:?} is outside the distortion's ball (radius {} around {:?})",
                self.radius, self.centre
            )));
        }
        let h = (1.0 - r2).max(0.0).sqrt();
        Ok([u[0], u[1], u[2], h])
    }

    /// Where the distortion moves `p`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a point outside the ball (or not finite).
    pub fn apply_point(&self, p: [f64; 3]) -> Result<[f64; 3]> {
        let y = self.network.position(&self.lift(p)?);
        Ok([0, 1, 2].map(|k| self.centre[k] + self.radius * y[k]))
    }

    /// The mesh with every vertex moved (triangles unchanged).
    ///
    /// # Errors
    /// As [`Mesh::validated`], and [`Error::InvalidInput`] naming the first vertex outside
    /// the ball.
    pub fn apply(&self, mesh: &Mesh) -> Result<Mesh> {
        let mesh = mesh.clone().validated()?;
        let positions = mesh
            .positions
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                self.apply_point(p)
                    .map_err(|e| Error::invalid(format!("vertex {i}: {e}")))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Mesh {
            positions,
            triangles: mesh.triangles,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::icosphere;

    /// The identity leaves a mesh in place (to rounding); a control at the centre lifts
    /// every point by d·(1 − |u|²)^{q/2}, one elsewhere by d·max(0, x·w)^q.
    #[test]
    fn identity_and_predicted_displacements() {
        let mut mesh = icosphere(2).unwrap();
        for p in &mut mesh.positions {
            *p = [0.7 * p[0] + 1.0, 0.5 * p[1] - 2.0, 0.3 * p[2] + 0.5];
        }
        let centre = [1.0, -2.0, 0.5];
        let identity = Distortion::identity(centre, 2.0).unwrap();
        let same = identity.apply(&mesh).unwrap();
        let worst = same
            .positions
            .iter()
            .zip(&mesh.positions)
            .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
            .fold(0.0, f64::max);
        assert!(worst < 1e-14, "{worst:e}");
        assert_eq!(same.triangles, mesh.triangles);

        let mut bump = identity.clone();
        bump.add_control(centre, [0.0, 0.0, 0.4], 2).unwrap();
        let side = [centre[0] + 1.2, centre[1], centre[2] + 0.8];
        bump.add_control(side, [-0.3, 0.1, 0.0], 6).unwrap();
        let w = bump.lift(side).unwrap();
        for (p, moved) in mesh
            .positions
            .iter()
            .zip(&bump.apply(&mesh).unwrap().positions)
        {
            let u = [0, 1, 2].map(|k| (p[k] - centre[k]) / 2.0);
            let x = bump.lift(*p).unwrap();
            let near = inner(&x, &w).max(0.0).powi(6);
            let expected = [
                p[0] - 0.3 * near,
                p[1] + 0.1 * near,
                p[2] + 0.4 * (1.0 - inner(&u, &u)),
            ];
            for k in 0..3 {
                assert!((moved[k] - expected[k]).abs() < 1e-12, "{p:?}");
            }
        }
        // At a control the displacement is the control's own (plus the others' tails).
        let at = bump.apply_point(side).unwrap();
        assert!((at[0] - (side[0] - 0.3)).abs() < 0.02);

        assert!(Distortion::identity(centre, 0.0).is_err());
        assert!(bump.apply_point([10.0, 0.0, 0.0]).is_err());
        assert!(bump.add_control([10.0, 0.0, 0.0], [0.0; 3], 2).is_err());
        assert!(bump.add_control(centre, [f64::NAN, 0.0, 0.0], 2).is_err());
        assert!(bump.add_control(centre, [0.0; 3], 65).is_err());
    }
}
