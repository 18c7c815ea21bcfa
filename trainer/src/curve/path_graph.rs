//! Paths along scattered points: the graph of each point's nearest points, and shortest
//! path lengths through it (Dijkstra), which measure distances along a surface the points
//! sample rather than through space.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::num::NonZeroUsize;

use kiddo::ImmutableKdTree;

use super::groups::nearest;

/// Each point's `count` nearest points with their distances, listed both ways (j lists i
/// whenever i lists j); `None` when the points can't be put in a tree.
pub(crate) fn neighbour_graph(points: &[[f64; 3]], count: usize) -> Option<Vec<Vec<(usize, f64)>>> {
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(points).ok()?;
    let mut graph = nearest(&tree, points, NonZeroUsize::new(count + 1)?);
    list_both_ways(&mut graph);
    Some(graph)
}

/// Adds (i, d) to j's list wherever i lists (j, d) and j does not list i.
pub(crate) fn list_both_ways(graph: &mut [Vec<(usize, f64)>]) {
    for i in 0..graph.len() {
        for k in 0..graph[i].len() {
            let (j, d) = graph[i][k];
            if j != i && !graph[j].iter().any(|&(m, _)| m == i) {
                graph[j].push((i, d));
            }
        }
    }
}

/// Path lengths through `graph` from the nearest of `sources` to every point; ∞ where no
/// path leads.
pub(crate) fn shortest_paths(graph: &[Vec<(usize, f64)>], sources: &[usize]) -> Vec<f64> {
    lengths_of_cheapest_paths(graph, sources, |step| step)
}

/// Lengths along the paths through `graph` from the nearest of `sources` that minimize the
/// sum of their squared steps; ∞ where no path leads.
///
/// Squared steps make a path through dense points cheaper than one that jumps: two steps
/// of ½ cost half of one step of 1. In a noisy band the plain shortest path takes the few
/// points that noise carries into a gap as stepping stones (across the mouth of a 'C',
/// between two arms), while this one stays where the points are dense, along the band. The
/// length returned is the path's own, in data units, so distances along the band stay
/// comparable however dense it is.
pub(crate) fn dense_paths(graph: &[Vec<(usize, f64)>], sources: &[usize]) -> Vec<f64> {
    lengths_of_cheapest_paths(graph, sources, |step| step * step)
}

/// Dijkstra's algorithm over steps costing `cost(length)` (non-negative, growing with the
/// length): the length of each point's cheapest path from the nearest source.
fn lengths_of_cheapest_paths(
    graph: &[Vec<(usize, f64)>],
    sources: &[usize],
    cost: impl Fn(f64) -> f64,
) -> Vec<f64> {
    let mut cheapest = vec![f64::INFINITY; graph.len()];
    let mut length = vec![f64::INFINITY; graph.len()];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        cheapest[s] = 0.0;
        length[s] = 0.0;
        heap.push(Reverse((0.0_f64.to_bits(), s)));
    }
    // Non-negative floats order like their bits.
    while let Some(Reverse((bits, i))) = heap.pop() {
        let c = f64::from_bits(bits);
        if c > cheapest[i] {
            continue;
        }
        for &(j, step) in &graph[i] {
            let through = c + cost(step);
            if through < cheapest[j] {
                cheapest[j] = through;
                length[j] = length[i] + step;
                heap.push(Reverse((through.to_bits(), j)));
            }
        }
    }
    length
}
