//! The tour behind [`refine_order`](super::refine_order): the order as a cycle (with a
//! dummy node closing an open order), its 2-opt and stretch-insertion moves.

use super::grid::NeuronGrid;
use super::ordering::Ordering;
use super::points::CurvePoints;
use super::refine::RefineOptions;
use crate::geometry::vector::distance;

/// A cyclic tour over the points (plus a dummy node for an open order).
pub(crate) struct Tour<'a> {
    points: &'a [[f64; 3]],
    /// The dummy node's index (n) when open.
    dummy: Option<usize>,
    nodes: Vec<usize>,
    position: Vec<usize>,
    /// k nearest points of every point, nearest first (the dummy first when open).
    neighbours: Vec<Vec<usize>>,
}

impl<'a> Tour<'a> {
    pub(crate) fn new(points: &'a CurvePoints, ordering: &Ordering, k: usize) -> Self {
        let data = points.points();
        let n = data.len();
        let dummy = (!ordering.closed).then_some(n);
        let mut nodes = ordering.order.clone();
        nodes.extend(dummy);
        let mut position = vec![0; nodes.len()];
        for (p, &v) in nodes.iter().enumerate() {
            position[v] = p;
        }
        let (lower, upper) = points.bounds();
        let grid = NeuronGrid::new(lower, upper, data);
        let mut found = Vec::new();
        let neighbours = (0..n)
            .map(|i| {
                grid.nearest_k(data[i], data, Some(i), k.min(n - 1), &mut found);
                dummy
                    .into_iter()
                    .chain(found.iter().map(|&(_, j)| j))
                    .collect()
            })
            .collect();
        Tour {
            points: data,
            dummy,
            nodes,
            position,
            neighbours,
        }
    }

    fn distance(&self, a: usize, b: usize) -> f64 {
        if Some(a) == self.dummy || Some(b) == self.dummy {
            0.0
        } else {
            distance(self.points[a], self.points[b])
        }
    }

    fn next(&self, v: usize) -> usize {
        let p = self.position[v] + 1;
        self.nodes[if p == self.nodes.len() { 0 } else { p }]
    }

    fn previous(&self, v: usize) -> usize {
        let p = self.position[v];
        self.nodes[if p == 0 { self.nodes.len() - 1 } else { p - 1 }]
    }

    pub(crate) fn length(&self) -> f64 {
        let mut total = 0.0;
        for (p, &v) in self.nodes.iter().enumerate() {
            total += self.distance(v, self.nodes[(p + 1) % self.nodes.len()]);
        }
        total
    }

    /// Reverses the stretch from `from` forward to `to` (or, equivalently for a cycle, the
    /// complementary stretch when that is shorter).
    fn reverse(&mut self, from: usize, to: usize) {
        let size = self.nodes.len();
        let (mut i, mut j) = (self.position[from], self.position[to]);
        let mut span = (j + size - i) % size + 1;
        if 2 * span > size {
            (i, j) = ((j + 1) % size, (i + size - 1) % size);
            span = size - span;
        }
        for _ in 0..span / 2 {
            self.nodes.swap(i, j);
            self.position[self.nodes[i]] = i;
            self.position[self.nodes[j]] = j;
            i = (i + 1) % size;
            j = (j + size - 1) % size;
        }
    }

    /// One pass of first-improvement 2-opt; returns the moves applied.
    pub(crate) fn two_opt_pass(&mut self, epsilon: f64) -> usize {
        let mut moves = 0;
        for a in 0..self.points.len() {
            for forward in [true, false] {
                let b = if forward {
                    self.next(a)
                } else {
                    self.previous(a)
                };
                let ab = self.distance(a, b);
                for index in 0..self.neighbours[a].len() {
                    let c = self.neighbours[a][index];
                    let ac = self.distance(a, c);
                    if ac >= ab {
                        break;
                    }
                    let d = if forward {
                        self.next(c)
                    } else {
                        self.previous(c)
                    };
                    if c == b || d == a {
                        continue;
                    }
                    let gain = ab + self.distance(c, d) - ac - self.distance(b, d);
                    if gain > epsilon {
                        if forward {
                            self.reverse(b, c);
                        } else {
                            self.reverse(a, d);
                        }
                        moves += 1;
                        break;
                    }
                }
            }
        }
        moves
    }

    /// One pass of stretch insertion; returns the moves applied.
    pub(crate) fn insertion_pass(&mut self, epsilon: f64, options: &RefineOptions) -> usize {
        let mut moves = 0;
        for start in 0..self.points.len() {
            for length in 1..=3 {
                let end_position = (self.position[start] + length - 1) % self.nodes.len();
                let end = self.nodes[end_position];
                if self.try_insertion(start, end, &[], epsilon) {
                    moves += 1;
                    break;
                }
            }
        }
        // Stretches between two long edges.
        let mut edges: Vec<(f64, usize)> = self
            .nodes
            .iter()
            .map(|&v| (self.distance(v, self.next(v)), v))
            .filter(|&(_, v)| Some(v) != self.dummy && Some(self.next(v)) != self.dummy)
            .collect();
        if edges.is_empty() {
            return moves;
        }
        let middle = edges.len() / 2;
        edges.select_nth_unstable_by(middle, |a, b| a.0.total_cmp(&b.0));
        let threshold = options.long_edge_factor * edges[middle].0;
        let mut long: Vec<(f64, usize)> = edges.into_iter().filter(|e| e.0 > threshold).collect();
        long.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        long.truncate(options.max_long_edges);
        // Each boundary edge (v, next v) is stored by v: the long edges and, for an open
        // order, the two edges at the dummy (the path's ends). A stretch starts after one
        // boundary and ends at the tail of another.
        let mut tails: Vec<usize> = long.iter().map(|&(_, v)| v).collect();
        if let Some(dummy) = self.dummy {
            tails.extend([dummy, self.previous(dummy)]);
        }
        let is_boundary = |v: usize, tour: &Tour<'_>| {
            let w = tour.next(v);
            Some(v) == tour.dummy || Some(w) == tour.dummy || tour.distance(v, w) > threshold
        };
        for &first in &tails {
            for &second in &tails {
                // The edges may have moved since they were collected: re-check.
                if first == second || !is_boundary(first, self) || !is_boundary(second, self) {
                    continue;
                }
                // Two long edges around a reversed stretch: in a thick noisy band the
                // stretch's true neighbours can lie beyond every point's k nearest, where
                // plain 2-opt looks.
                if self.try_reversal(first, second, epsilon) {
                    moves += 1;
                    continue;
                }
                if self.try_insertion(self.next(first), second, &tails, epsilon) {
                    moves += 1;
                }
            }
        }
        moves
    }

    /// Replaces the edges after `a` and after `c` by `a`–`c` and their successors' edge
    /// (reversing what lies between) when that shortens the tour.
    fn try_reversal(&mut self, a: usize, c: usize, epsilon: f64) -> bool {
        let (b, d) = (self.next(a), self.next(c));
        if c == b || d == a {
            return false;
        }
        let gain =
            self.distance(a, b) + self.distance(c, d) - self.distance(a, c) - self.distance(b, d);
        if gain > epsilon {
            self.reverse(b, c);
            return true;
        }
        false
    }

    /// Tries to move the stretch `start` … `end` (forward) between two neighbours elsewhere:
    /// after a point near one of its ends, or after one of `also` (the tails of long edges:
    /// in a thick noisy band a misplaced stretch's true place can lie beyond its ends' k
    /// nearest points). Applies the best improving placement found.
    fn try_insertion(&mut self, start: usize, end: usize, also: &[usize], epsilon: f64) -> bool {
        let size = self.nodes.len();
        let (i, j) = (self.position[start], self.position[end]);
        let span = (j + size - i) % size + 1;
        if span + 3 > size {
            return false;
        }
        let inside = |v: usize, tour: &Tour<'_>| (tour.position[v] + size - i) % size < span;
        if self.dummy.is_some_and(|d| inside(d, self)) {
            return false;
        }
        let (p, q) = (self.previous(start), self.next(end));
        let removal = self.distance(p, start) + self.distance(end, q) - self.distance(p, q);
        if removal <= epsilon {
            return false;
        }
        let mut best: Option<(f64, usize, bool)> = None;
        let mut consider = |a: usize, tour: &Tour<'_>| {
            let b = tour.next(a);
            if inside(a, tour) || inside(b, tour) {
                return;
            }
            let ab = tour.distance(a, b);
            let keep = tour.distance(a, start) + tour.distance(end, b) - ab;
            let flip = tour.distance(a, end) + tour.distance(start, b) - ab;
            let (cost, reversed) = if flip < keep {
                (flip, true)
            } else {
                (keep, false)
            };
            if removal - cost > epsilon && best.is_none_or(|(g, _, _)| removal - cost > g) {
                best = Some((removal - cost, a, reversed));
            }
        };
        for x in [start, end] {
            for index in 0..self.neighbours[x].len() {
                let c = self.neighbours[x][index];
                if self.distance(x, c) >= removal {
                    break;
                }
                consider(c, self);
                consider(self.previous(c), self);
            }
        }
        for &a in also {
            consider(a, self);
        }
        let Some((_, a, reversed)) = best else {
            return false;
        };
        let mut stretch: Vec<usize> = (0..span).map(|k| self.nodes[(i + k) % size]).collect();
        if reversed {
            stretch.reverse();
        }
        let mut rest: Vec<usize> = (0..size - span)
            .map(|k| self.nodes[(j + 1 + k) % size])
            .collect();
        let at = rest
            .iter()
            .position(|&v| v == a)
            .map_or(rest.len(), |p| p + 1);
        rest.splice(at..at, stretch);
        self.nodes = rest;
        for (p, &v) in self.nodes.iter().enumerate() {
            self.position[v] = p;
        }
        true
    }

    /// The point order: open orders start after the dummy; closed ones at the old start.
    pub(crate) fn into_order(self, ordering: &Ordering) -> Vec<usize> {
        let size = self.nodes.len();
        let (anchor, skip) = match self.dummy {
            Some(d) => (self.position[d] + 1, 1),
            None => (self.position[ordering.order[0]], 0),
        };
        (0..size - skip)
            .map(|k| self.nodes[(anchor + k) % size])
            .collect()
    }
}
