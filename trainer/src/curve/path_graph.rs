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
    for i in 0..graph.len() {
        for k in 0..graph[i].len() {
            let (j, d) = graph[i][k];
            if j != i && !graph[j].iter().any(|&(m, _)| m == i) {
                graph[j].push((i, d));
            }
        }
    }
    Some(graph)
}

/// Path lengths through `graph` from the nearest of `sources` to every point; ∞ where no
/// path leads.
pub(crate) fn shortest_paths(graph: &[Vec<(usize, f64)>], sources: &[usize]) -> Vec<f64> {
    let mut distance = vec![f64::INFINITY; graph.len()];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        distance[s] = 0.0;
        heap.push(Reverse((0.0_f64.to_bits(), s)));
    }
    // Non-negative floats order like their bits.
    while let Some(Reverse((bits, i))) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > distance[i] {
            continue;
        }
        for &(j, step) in &graph[i] {
            let through = d + step;
            if through < distance[j] {
                distance[j] = through;
                heap.push(Reverse((through.to_bits(), j)));
            }
        }
    }
    distance
}
