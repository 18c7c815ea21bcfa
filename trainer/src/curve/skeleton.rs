//! A band's order along a tree of its cluster centres: the band is covered by centres
//! a few noise deviations apart, each moved to the mean of its points (the band's middle
//! there), the centres are joined by the spanning tree that prefers short links through
//! dense points, and the tree's longest path is the band.
//!
//! A path through the points themselves steps from point to point, and noise that carries a
//! few points into the mouth of a 'C' or between the turns of a helix gives it stepping
//! stones. A centre stands for the points around it (centres of a few stray points are
//! dropped), and a link is judged by the points along it: a link across a gap, however
//! short, has next to none somewhere along it, and the tree takes it only when nothing else
//! joins the two sides. Where the band is as wide as
//! the centres are apart, the tree grows short side branches across it; its longest path
//! runs along the band, and the points of a side branch find their feet on that path. The
//! tree of a closed band leaves out its weakest link, and its longest path runs round the
//! ring from there.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::principal::{Polyline, ordered_by_place};
use crate::geometry::vector::distance;

/// The centres lie at least this many noise deviations apart: wide enough that the means
/// of their points lie near the band's middle, narrow enough for the band's bends.
const SPACING: f64 = 2.0;

/// Rounds of moving each centre to the mean of the points nearest it.
const MEANS: usize = 2;

/// Path vertices on each side that [`smoothed`] averages over.
const SMOOTHING: usize = 2;

/// Centres holding fewer than this share of the median centre's points are dropped: on a
/// helix at σ = 5 %, a centre of noise between two turns linked them through support at
/// its links' middles.
const STRAY: f64 = 0.25;

/// Each centre is linked to this many nearest centres before the tree is chosen.
const LINKS: usize = 16;

/// A link's support is the least count of points within this many noise deviations of the
/// points a quarter, half and three quarters along it.
const SUPPORT_REACH: f64 = 1.0;

/// The centres of `points`, at least `spacing` apart (greedily, in the points' order),
/// each moved [`MEANS`] times to the mean of the points nearest it, without those holding
/// fewer than [`STRAY`] times the median centre's points.
fn centres(points: &[[f64; 3]], tree: &ImmutableKdTree<f64, 3>, spacing: f64) -> Vec<[f64; 3]> {
    let mut covered = vec![false; points.len()];
    let mut centres = Vec::new();
    for (i, p) in points.iter().enumerate() {
        if covered[i] {
            continue;
        }
        centres.push(*p);
        for near in tree
            .query(p)
            .within::<SquaredEuclidean<f64>>(spacing * spacing)
            .unsorted()
            .execute()
            .iter()
        {
            covered[near.item as usize] = true;
        }
    }
    let mut counts = vec![0usize; centres.len()];
    for _ in 0..MEANS {
        let Ok(index) = ImmutableKdTree::<f64, 3>::new_from_slice(&centres) else {
            break;
        };
        let mut sums = vec![([0.0; 3], 0usize); centres.len()];
        for p in points {
            let c = index
                .query(p)
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute()
                .item as usize;
            for k in 0..3 {
                sums[c].0[k] += p[k];
            }
            sums[c].1 += 1;
        }
        for (centre, (sum, count)) in centres.iter_mut().zip(&sums) {
            if *count > 0 {
                *centre = sum.map(|s| s / *count as f64);
            }
        }
        counts = sums.iter().map(|s| s.1).collect();
    }
    // Centres of a few stray points (noise carried far out, between two turns) would join
    // what the band keeps apart.
    let mut sorted = counts.clone();
    sorted.sort_unstable();
    let typical = sorted.get(sorted.len() / 2).copied().unwrap_or(0) as f64;
    centres
        .into_iter()
        .zip(counts)
        .filter(|&(_, count)| count as f64 >= STRAY * typical)
        .map(|(c, _)| c)
        .collect()
}

/// The spanning forest of the centres' links ([`LINKS`] nearest each) that minimizes the
/// sum of each link's length over its support (see [`SUPPORT_REACH`], `reach` here; one at
/// least), as adjacency lists with each link's length, and a centre of its largest tree.
fn spanning_tree(
    centres: &[[f64; 3]],
    tree: &ImmutableKdTree<f64, 3>,
    reach: f64,
) -> Option<(Links, usize)> {
    let index = ImmutableKdTree::<f64, 3>::new_from_slice(centres).ok()?;
    let count = std::num::NonZeroUsize::new((LINKS + 1).min(centres.len()))?;
    let mut links: Vec<(f64, usize, usize, f64)> = Vec::new();
    for (i, c) in centres.iter().enumerate() {
        for near in index
            .query(c)
            .nearest_n::<SquaredEuclidean<f64>>(count)
            .execute()
        {
            let j = near.item as usize;
            if j == i {
                continue;
            }
            let length = distance(*c, centres[j]);
            let support = [0.25, 0.5, 0.75]
                .iter()
                .map(|&t| {
                    let at = [0, 1, 2].map(|k| c[k] + t * (centres[j][k] - c[k]));
                    tree.query(&at)
                        .within::<SquaredEuclidean<f64>>(reach * reach)
                        .unsorted()
                        .execute()
                        .len()
                })
                .min()
                .unwrap_or(0)
                .max(1);
            links.push((length / support as f64, i, j, length));
        }
    }
    links.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Kruskal's algorithm over a union-find forest.
    let mut parent: Vec<usize> = (0..centres.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut adjacent = vec![Vec::new(); centres.len()];
    for (_, i, j, length) in links {
        let (a, b) = (root(&mut parent, i), root(&mut parent, j));
        if a != b {
            parent[a] = b;
            adjacent[i].push((j, length));
            adjacent[j].push((i, length));
        }
    }
    let mut sizes = vec![0usize; centres.len()];
    for i in 0..centres.len() {
        sizes[root(&mut parent, i)] += 1;
    }
    let largest = (0..centres.len()).max_by_key(|&i| sizes[i])?;
    Some((adjacent, largest))
}

/// Each node's neighbours in a tree, with the length of the link to each.
type Links = Vec<Vec<(usize, f64)>>;

/// The distance along `tree` from `from` to every node, and each node's predecessor.
fn along_tree(tree: &Links, from: usize) -> (Vec<f64>, Vec<usize>) {
    let mut reached = vec![f64::INFINITY; tree.len()];
    let mut before = vec![usize::MAX; tree.len()];
    reached[from] = 0.0;
    let mut stack = vec![from];
    while let Some(i) = stack.pop() {
        for &(j, length) in &tree[i] {
            if reached[j].is_infinite() {
                reached[j] = reached[i] + length;
                before[j] = i;
                stack.push(j);
            }
        }
    }
    (reached, before)
}

/// The index of the largest finite value.
fn farthest(values: &[f64]) -> Option<usize> {
    values
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| i)
}

/// `path` with each inner vertex the mean of itself and [`SMOOTHING`] vertices on each side
/// (fewer near the ends, which stay): the centres across the band make the path zig-zag.
fn smoothed(path: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = path.len();
    (0..n)
        .map(|i| {
            let reach = SMOOTHING.min(i).min(n - 1 - i);
            let window = &path[i - reach..=i + reach];
            let mut mean = [0.0; 3];
            for p in window {
                for k in 0..3 {
                    mean[k] += p[k] / window.len() as f64;
                }
            }
            mean
        })
        .collect()
}

/// A band's points (with noise of deviation `noise` across it) ordered along the
/// longest path of the largest tree of their centres (see the module documentation),
/// [`smoothed`]: each point's place is its foot's arc length on that path, extended
/// straight past its ends. Returns
/// the order, each ordered point's place from 0 to 1, and the band's length; `None` for a
/// band too short for three centres.
pub(crate) fn skeleton_order(
    points: &[[f64; 3]],
    noise: f64,
) -> Option<(Vec<usize>, Vec<f64>, f64)> {
    if !(noise > 0.0 && noise.is_finite()) {
        return None;
    }
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(points).ok()?;
    let centres = centres(points, &tree, SPACING * noise);
    if centres.len() < 3 {
        return None;
    }
    let (links, member) = spanning_tree(&centres, &tree, SUPPORT_REACH * noise)?;
    let start = farthest(&along_tree(&links, member).0)?;
    let (reached, before) = along_tree(&links, start);
    let mut at = farthest(&reached)?;
    let mut path = vec![centres[at]];
    while at != start {
        at = before[at];
        path.push(centres[at]);
    }
    let path = smoothed(&path);
    let line = Polyline::new(path, false);
    let reach = SPACING * noise;
    ordered_by_place(
        points
            .iter()
            .enumerate()
            .map(|(i, p)| (line.foot(*p, reach).0, i))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::skeleton_order;
    use crate::curve::samples::gaussian;

    /// A hairpin band (arms 3 long, 1.2 apart, σ = 0.15: the arms 8 deviations apart) with
    /// stray points scattered between its arms is ordered along it: no step between
    /// consecutive points jumps along the hairpin, and its ends are the order's ends.
    #[test]
    fn a_band_with_strays_between_its_arms_is_ordered_along_it() {
        let (arm, bend, sigma) = (3.0, std::f64::consts::PI * 0.6, 0.15);
        let length = 2.0 * arm + bend;
        let at = |s: f64| {
            if s < arm {
                [arm - s, 0.6]
            } else if s < arm + bend {
                let a = (s - arm) / 0.6;
                [-0.6 * a.sin(), 0.6 * a.cos()]
            } else {
                [s - arm - bend, -0.6]
            }
        };
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut points = Vec::new();
        let mut truth = Vec::new();
        for _ in 0..800 {
            let s = rng.random::<f64>() * length;
            let p = at(s);
            let noise = [gaussian(&mut rng), gaussian(&mut rng)];
            points.push([p[0] + sigma * noise[0], p[1] + sigma * noise[1], 0.0]);
            truth.push(Some(s / length));
        }
        for _ in 0..16 {
            let (x, y) = (rng.random::<f64>() * 3.0, rng.random::<f64>() * 0.6 - 0.3);
            points.push([x, y, 0.0]);
            truth.push(None);
        }
        let (order, places, _) = skeleton_order(&points, sigma).expect("an order");
        assert_eq!(order.len(), points.len());
        assert!(places.windows(2).all(|w| w[0] <= w[1]));
        let along: Vec<f64> = order.iter().filter_map(|&i| truth[i]).collect();
        // A step to the other arm skips at least the stretch round the bend from the tips
        // (a quarter of the length); noise along the band moves a point by 2 % per σ.
        let jumps = along
            .windows(2)
            .filter(|w| (w[1] - w[0]).abs() > 0.1)
            .count();
        assert_eq!(jumps, 0, "steps across the hairpin's arms");
        let (first, last) = (
            along[..40].iter().sum::<f64>(),
            along[along.len() - 40..].iter().sum::<f64>(),
        );
        let (first, last) = (first / 40.0, last / 40.0);
        assert!(
            first.min(last) < 0.05 && first.max(last) > 0.95,
            "ends at {first} and {last}"
        );
    }

    /// Too few points for three centres, or no noise to space them by: no order.
    #[test]
    fn a_band_without_noise_or_length_has_no_order() {
        let points: Vec<[f64; 3]> = (0..50).map(|i| [i as f64 * 0.01, 0.0, 0.0]).collect();
        assert!(skeleton_order(&points, 0.0).is_none());
        assert!(skeleton_order(&points, f64::NAN).is_none());
        assert!(skeleton_order(&points, 10.0).is_none());
    }
}
