//! Oriented point sets: the control points (positions with outward unit normals, optionally
//! grouped into features) every implicit model is trained on.

use crate::error::{Error, Result};

/// Control points with outward unit normals and optional feature labels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointSet {
    /// Positions.
    pub positions: Vec<[f64; 3]>,
    /// Outward unit normals, one per position.
    pub normals: Vec<[f64; 3]>,
    /// Feature index of each point, when known.
    pub features: Option<Vec<u32>>,
}

impl PointSet {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Checks the set is usable for training and rescales normals to unit length.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the first offending point: no points, lengths that
    /// disagree, non-finite coordinates or normals, zero-length normals.
    pub fn validated(mut self) -> Result<Self> {
        if self.positions.is_empty() {
            return Err(Error::invalid("the point set is empty"));
        }
        if self.normals.len() != self.positions.len() {
            return Err(Error::invalid(format!(
                "{} positions but {} normals",
                self.positions.len(),
                self.normals.len()
            )));
        }
        if let Some(features) = &self.features
            && features.len() != self.positions.len()
        {
            return Err(Error::invalid(format!(
                "{} positions but {} feature labels",
                self.positions.len(),
                features.len()
            )));
        }
        for (i, (p, n)) in self
            .positions
            .iter()
            .zip(self.normals.iter_mut())
            .enumerate()
        {
            if p.iter().any(|c| !c.is_finite()) {
                return Err(Error::invalid(format!(
                    "point {i} has a non-finite coordinate {p:?}"
                )));
            }
            if n.iter().any(|c| !c.is_finite()) {
                return Err(Error::invalid(format!(
                    "point {i} has a non-finite normal {n:?}"
                )));
            }
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if len < 1e-12 {
                return Err(Error::invalid(format!(
                    "point {i} has a zero-length normal"
                )));
            }
            *n = n.map(|c| c / len);
        }
        Ok(self)
    }

    /// The points whose indices are listed, keeping normals and features.
    pub fn subset(&self, indices: &[usize]) -> PointSet {
        PointSet {
            positions: indices.iter().map(|&i| self.positions[i]).collect(),
            normals: indices.iter().map(|&i| self.normals[i]).collect(),
            features: self
                .features
                .as_ref()
                .map(|f| indices.iter().map(|&i| f[i]).collect()),
        }
    }
}
