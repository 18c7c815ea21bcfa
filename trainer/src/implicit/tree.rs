//! Module trees: which features are blended with which (`--tree "((0,1),2)"`), parsed from
//! text or built automatically by spatial proximity.

use std::fmt;
use std::str::FromStr;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use neurosurf_core::implicit::ModuleKind;

use crate::error::{Error, Result};

/// A binary tree whose leaves are feature indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TreeSpec {
    /// A leaf module learning feature `n`.
    Leaf(u32),
    /// A node module blending two subtrees.
    Node(Box<TreeSpec>, Box<TreeSpec>),
}

impl TreeSpec {
    /// A node over two subtrees.
    pub fn node(left: TreeSpec, right: TreeSpec) -> Self {
        TreeSpec::Node(Box::new(left), Box::new(right))
    }

    /// Module kinds in post-order (the blob's tree).
    pub fn post_order(&self) -> Vec<ModuleKind> {
        let mut out = Vec::new();
        self.visit(&mut |t| {
            out.push(match t {
                TreeSpec::Leaf(_) => ModuleKind::Leaf,
                TreeSpec::Node(..) => ModuleKind::Node,
            })
        });
        out
    }

    /// For every module in post-order, its feature if it is a leaf.
    pub fn post_order_features(&self) -> Vec<Option<u32>> {
        let mut out = Vec::new();
        self.visit(&mut |t| {
            out.push(match t {
                TreeSpec::Leaf(f) => Some(*f),
                TreeSpec::Node(..) => None,
            })
        });
        out
    }

    fn visit(&self, f: &mut dyn FnMut(&TreeSpec)) {
        if let TreeSpec::Node(l, r) = self {
            l.visit(f);
            r.visit(f);
        }
        f(self);
    }

    /// Height (a leaf has height 1).
    pub fn height(&self) -> usize {
        match self {
            TreeSpec::Leaf(_) => 1,
            TreeSpec::Node(l, r) => 1 + l.height().max(r.height()),
        }
    }

    /// Checks that the leaves are exactly the features 0..`count`, each once.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming a missing, repeated or unknown feature.
    pub fn check_features(&self, count: usize) -> Result<()> {
        let mut seen = vec![false; count];
        for f in self.post_order_features().into_iter().flatten() {
            let slot = seen.get_mut(f as usize).ok_or_else(|| {
                Error::invalid(format!(
                    "tree names feature {f}, but the points have features 0..{count}"
                ))
            })?;
            if *slot {
                return Err(Error::invalid(format!("tree names feature {f} twice")));
            }
            *slot = true;
        }
        if let Some(missing) = seen.iter().position(|s| !s) {
            return Err(Error::invalid(format!(
                "tree does not name feature {missing}"
            )));
        }
        Ok(())
    }

    /// A balanced tree over features with the given centroids and point counts: split the
    /// features along the principal axis of their centroids into two halves of (nearly) equal
    /// feature count, recursively. Neighbouring features are blended first, and the tree is as
    /// shallow as possible (the paper's Fig. 8 rationale: few node modules over many points).
    pub fn balanced(centroids: &[[f64; 3]]) -> Result<Self> {
        if centroids.is_empty() {
            return Err(Error::invalid("cannot build a tree over zero features"));
        }
        let ids: Vec<u32> = (0..centroids.len() as u32).collect();
        Ok(split(centroids, ids))
    }
}

fn split(centroids: &[[f64; 3]], mut ids: Vec<u32>) -> TreeSpec {
    if ids.len() == 1 {
        return TreeSpec::Leaf(ids[0]);
    }
    let axis = principal_axis(ids.iter().map(|&i| centroids[i as usize]));
    ids.sort_by(|&a, &b| {
        let pa = axis.dot(&Vector3::from(centroids[a as usize]));
        let pb = axis.dot(&Vector3::from(centroids[b as usize]));
        pa.total_cmp(&pb).then(a.cmp(&b))
    });
    let right = ids.split_off(ids.len() / 2);
    TreeSpec::node(split(centroids, ids), split(centroids, right))
}

/// The direction of largest spread of some points (x axis when they do not spread).
pub(crate) fn principal_axis(points: impl Iterator<Item = [f64; 3]> + Clone) -> Vector3<f64> {
    let n = points.clone().count().max(1) as f64;
    let mean = points
        .clone()
        .fold(Vector3::zeros(), |a, p| a + Vector3::from(p))
        / n;
    let cov = points.fold(Matrix3::zeros(), |a, p| {
        let d = Vector3::from(p) - mean;
        a + d * d.transpose()
    });
    let eigen = SymmetricEigen::new(cov);
    let i = eigen.eigenvalues.imax();
    let axis = eigen.eigenvectors.column(i).into_owned();
    if axis.norm() > 0.0 {
        axis
    } else {
        Vector3::x()
    }
}

impl fmt::Display for TreeSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TreeSpec::Leaf(n) => write!(f, "{n}"),
            TreeSpec::Node(l, r) => write!(f, "({l},{r})"),
        }
    }
}

impl FromStr for TreeSpec {
    type Err = Error;

    /// Parses `"((0,1),2)"`: a feature index, or `(left,right)`; whitespace is ignored.
    fn from_str(text: &str) -> Result<Self> {
        let chars: Vec<char> = text.chars().filter(|c| !c.is_whitespace()).collect();
        let mut pos = 0;
        let tree = parse(&chars, &mut pos)?;
        if pos != chars.len() {
            return Err(Error::invalid(format!(
                "tree spec {text:?}: unexpected {:?} after a complete tree",
                chars[pos..].iter().collect::<String>()
            )));
        }
        Ok(tree)
    }
}

fn parse(chars: &[char], pos: &mut usize) -> Result<TreeSpec> {
    let text: String = chars.iter().collect();
    let fail = |what: &str, at: usize| {
        Error::invalid(format!("tree spec {text:?}: {what} at position {at}"))
    };
    match chars.get(*pos) {
        Some('(') => {
            *pos += 1;
            let left = parse(chars, pos)?;
            if chars.get(*pos) != Some(&',') {
                return Err(fail("expected ','", *pos));
            }
            *pos += 1;
            let right = parse(chars, pos)?;
            if chars.get(*pos) != Some(&')') {
                return Err(fail("expected ')'", *pos));
            }
            *pos += 1;
            Ok(TreeSpec::node(left, right))
        }
        Some(c) if c.is_ascii_digit() => {
            let start = *pos;
            while chars.get(*pos).is_some_and(|c| c.is_ascii_digit()) {
                *pos += 1;
            }
            let digits: String = chars[start..*pos].iter().collect();
            digits
                .parse()
                .map(TreeSpec::Leaf)
                .map_err(|_| fail("feature index too large", start))
        }
        Some(_) => Err(fail("expected a feature index or '('", *pos)),
        None => Err(fail("unexpected end", *pos)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints() {
        let t: TreeSpec = " ((0, 1), 2) ".parse().unwrap();
        assert_eq!(t.to_string(), "((0,1),2)");
        assert_eq!(
            t.post_order(),
            [
                ModuleKind::Leaf,
                ModuleKind::Leaf,
                ModuleKind::Node,
                ModuleKind::Leaf,
                ModuleKind::Node
            ]
        );
        assert_eq!(
            t.post_order_features(),
            [Some(0), Some(1), None, Some(2), None]
        );
        assert_eq!(t.height(), 3);
        t.check_features(3).unwrap();
    }

    #[test]
    fn rejects_malformed_specs_with_position() {
        for bad in [
            "",
            "(0,1",
            "(0 1)",
            "((0,1),)",
            "(0,1))",
            "x",
            "(0,99999999999)",
        ] {
            let err = bad.parse::<TreeSpec>().unwrap_err().to_string();
            assert!(err.contains("tree spec"), "{bad}: {err}");
        }
    }

    #[test]
    fn feature_coverage_is_checked() {
        let t: TreeSpec = "((0,1),1)".parse().unwrap();
        assert!(
            t.check_features(2)
                .unwrap_err()
                .to_string()
                .contains("twice")
        );
        let t: TreeSpec = "(0,2)".parse().unwrap();
        assert!(
            t.check_features(3)
                .unwrap_err()
                .to_string()
                .contains("feature 1")
        );
        assert!(
            t.check_features(2)
                .unwrap_err()
                .to_string()
                .contains("feature 2")
        );
    }

    #[test]
    fn balanced_tree_pairs_neighbours() {
        // Four features on a line: 0 and 3 near each other, 1 and 2 near each other.
        let c = [
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [11.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
        ];
        let t = TreeSpec::balanced(&c).unwrap();
        assert_eq!(t.height(), 3);
        assert_eq!(t.to_string(), "((0,3),(1,2))");
        let t = TreeSpec::balanced(&c[..3]).unwrap();
        t.check_features(3).unwrap();
        assert_eq!(t.height(), 3);
    }
}
