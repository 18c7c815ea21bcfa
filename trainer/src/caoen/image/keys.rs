//! Adaptive key placement (§12.5: "in regions of high frequency more target points should be
//! used"): each tile is the root of a quadtree, and the cell whose pixels stray most from
//! their mean colour is split, again and again, while the stream still fits the byte budget.
//! Every leaf is one key point at its cell's centre, so positions cost one bit per cell.

use std::collections::BinaryHeap;

use super::tiles::{TILE, Tile};

/// One quadtree leaf: the nominal cell `size` at (`x0`, `y0`), clipped to the picture.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Cell {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// Nominal side (a power of two up to [`TILE`]).
    pub size: u32,
}

impl Cell {
    /// The children of a split cell that lie in the picture, in stream order.
    pub fn children(&self, width: u32, height: u32) -> Vec<Cell> {
        let half = self.size / 2;
        [(0, 0), (half, 0), (0, half), (half, half)]
            .into_iter()
            .map(|(dx, dy)| Cell {
                x0: self.x0 + dx,
                y0: self.y0 + dy,
                size: half,
            })
            .filter(|c| c.x0 < width && c.y0 < height)
            .collect()
    }

    /// The cell's pixel rectangle `[x0, x1) × [y0, y1)` within the picture.
    pub fn rect(&self, width: u32, height: u32) -> (u32, u32, u32, u32) {
        (
            self.x0,
            self.y0,
            (self.x0 + self.size).min(width),
            (self.y0 + self.size).min(height),
        )
    }

    /// Whether the stream holds a split flag for this cell (cells of one pixel cannot split).
    pub fn has_flag(&self) -> bool {
        self.size > 1
    }
}

/// The quadtrees of every tile: split flags in stream order (depth first, tile by tile) and the
/// leaves in the same order.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadtrees {
    /// One flag per cell larger than a pixel: whether it is split.
    pub flags: Vec<bool>,
    /// The leaves of each tile, in stream order.
    pub leaves: Vec<Vec<Cell>>,
}

impl Quadtrees {
    /// Rebuilds the leaves from the flags (`flags` yields them in stream order); `None` when
    /// the flags run out.
    pub fn from_flags(
        tiles: &[Tile],
        width: u32,
        height: u32,
        flags: &mut impl Iterator<Item = bool>,
    ) -> Option<Quadtrees> {
        let mut all_flags = Vec::new();
        let mut leaves = Vec::with_capacity(tiles.len());
        for t in tiles {
            let mut mine = Vec::new();
            let mut stack = vec![Cell {
                x0: t.x0,
                y0: t.y0,
                size: TILE,
            }];
            while let Some(cell) = stack.pop() {
                let split = if cell.has_flag() {
                    let f = flags.next()?;
                    all_flags.push(f);
                    f
                } else {
                    false
                };
                if split {
                    stack.extend(cell.children(width, height).into_iter().rev());
                } else {
                    mine.push(cell);
                }
            }
            leaves.push(mine);
        }
        Some(Quadtrees {
            flags: all_flags,
            leaves,
        })
    }

    /// Number of key points.
    pub fn key_count(&self) -> usize {
        self.leaves.iter().map(Vec::len).sum()
    }
}

/// Sum of squared deviations from the mean colour over a cell (`pixels` row-major RGB).
fn spread(pixels: &[[f64; 3]], width: u32, height: u32, cell: &Cell) -> f64 {
    let (x0, y0, x1, y1) = cell.rect(width, height);
    let mut sum = [0.0; 3];
    let mut squares = 0.0;
    let mut n = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            let c = pixels[(y * width + x) as usize];
            for k in 0..3 {
                sum[k] += c[k];
                squares += c[k] * c[k];
            }
            n += 1.0;
        }
    }
    let spread = squares - sum.iter().map(|s| s * s).sum::<f64>() / n;
    // Rounding leaves a flat cell a spread of about 1e-16 per pixel; below FLAT it is flat.
    if spread > FLAT * n { spread } else { 0.0 }
}

/// Spread per pixel (squared colour difference, channels in [0, 1]) below which a cell is
/// flat and never split: far under the 8-bit step (1/255)² ≈ 1.5e-5.
const FLAT: f64 = 1e-10;

/// A cell waiting in the split queue, largest spread first.
struct Candidate {
    spread: f64,
    tile: usize,
    cell: Cell,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == std::cmp::Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.spread.total_cmp(&other.spread).then(
            (other.tile, other.cell.y0, other.cell.x0).cmp(&(
                self.tile,
                self.cell.y0,
                self.cell.x0,
            )),
        )
    }
}

/// Splits the cells of every tile, the most uneven first, while flags and keys still fit in
/// `budget_bits` with `key_bits` per key. Returns `None` when even one key per tile does not
/// fit.
pub fn place_keys(
    pixels: &[[f64; 3]],
    width: u32,
    height: u32,
    tiles: &[Tile],
    budget_bits: usize,
    key_bits: usize,
) -> Option<Quadtrees> {
    let mut used = tiles.len() * (key_bits + 1);
    if used > budget_bits {
        return None;
    }
    let mut split = std::collections::HashSet::new();
    let mut queue: BinaryHeap<Candidate> = tiles
        .iter()
        .enumerate()
        .map(|(tile, t)| {
            let cell = Cell {
                x0: t.x0,
                y0: t.y0,
                size: TILE,
            };
            Candidate {
                spread: spread(pixels, width, height, &cell),
                tile,
                cell,
            }
        })
        .collect();
    while let Some(top) = queue.pop() {
        if top.spread <= 0.0 || !top.cell.has_flag() {
            continue;
        }
        let children = top.cell.children(width, height);
        let cost =
            (children.len() - 1) * key_bits + children.iter().filter(|c| c.has_flag()).count();
        if used + cost > budget_bits {
            // A smaller split elsewhere may still fit.
            continue;
        }
        used += cost;
        split.insert((top.cell.x0, top.cell.y0, top.cell.size));
        for cell in children {
            queue.push(Candidate {
                spread: spread(pixels, width, height, &cell),
                tile: top.tile,
                cell,
            });
        }
    }
    let mut flags = Vec::new();
    for t in tiles {
        let mut stack = vec![Cell {
            x0: t.x0,
            y0: t.y0,
            size: TILE,
        }];
        while let Some(cell) = stack.pop() {
            if !cell.has_flag() {
                continue;
            }
            let s = split.contains(&(cell.x0, cell.y0, cell.size));
            flags.push(s);
            if s {
                stack.extend(cell.children(width, height).into_iter().rev());
            }
        }
    }
    Quadtrees::from_flags(tiles, width, height, &mut flags.into_iter())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keys gather where the picture changes: a picture flat but for one sharp corner gets its
    /// smallest cells at the corner, the flags rebuild the same leaves, and the budget holds.
    #[test]
    fn keys_gather_at_detail() {
        let (w, h) = (19, 16);
        let pixels: Vec<[f64; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if x >= 11 && y >= 5 {
                    [1.0, 0.5, 0.0]
                } else {
                    [0.2; 3]
                }
            })
            .collect();
        let tiles = Tile::cover(w, h);
        let budget = 1200;
        let trees = place_keys(&pixels, w, h, &tiles, budget, 24).unwrap();
        assert!(trees.flags.len() + 24 * trees.key_count() <= budget);
        let back =
            Quadtrees::from_flags(&tiles, w, h, &mut trees.flags.clone().into_iter()).unwrap();
        assert_eq!(back, trees);
        // The corner pixel's cell is the smallest there is; flat tiles stay whole.
        let smallest = trees.leaves.iter().flatten().map(|c| c.size).min().unwrap();
        assert!(smallest < TILE / 2);
        let corner = trees
            .leaves
            .iter()
            .flatten()
            .find(|c| (c.x0..c.x0 + c.size).contains(&11) && (c.y0..c.y0 + c.size).contains(&5))
            .unwrap();
        assert!(corner.size <= 2 * smallest, "{corner:?}");
        for t in [0, 3] {
            assert_eq!(trees.leaves[t].len(), 1, "tile {t}");
        }
        assert!(place_keys(&pixels, w, h, &tiles, 10, 24).is_none());
    }
}
