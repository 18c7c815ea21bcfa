//! Where pixels and keys sit: square tiles of [`TILE`] pixels, each with its own Cao En network
//! whose source sphere spans the tile and a [`MARGIN`] around it, and the windows that fade
//! one tile's network into its neighbours'.

/// Side of a tile in pixels (the root of each tile's quadtree of keys).
pub const TILE: u32 = 8;
/// Pixels beyond a tile's side over which its network fades out and the next one fades in.
pub const MARGIN: u32 = 2;
/// The angle a tile and its two margins span on each circle of the source point. A key at a
/// tile's corner is up to 9 pixels (202°) from the far end of the window, so there its
/// similarity wraps round (9 pixels look like 7); every key but the broadest has fallen to
/// nothing long before.
pub const SPAN: f64 = 1.5 * std::f64::consts::PI;

/// One tile: its pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Tile {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Tile {
    /// The tiles of a `width` × `height` picture, row by row (partial tiles at the right and
    /// bottom edges).
    pub fn cover(width: u32, height: u32) -> Vec<Tile> {
        let mut tiles = Vec::new();
        for y0 in (0..height).step_by(TILE as usize) {
            for x0 in (0..width).step_by(TILE as usize) {
                tiles.push(Tile {
                    x0,
                    y0,
                    x1: (x0 + TILE).min(width),
                    y1: (y0 + TILE).min(height),
                });
            }
        }
        tiles
    }

    /// The source point of the picture position (`x`, `y`) (pixel centres are at `i + ½`)
    /// with luminance `luminance`, for this tile's network, with luminance weight `gamma`:
    ///
    /// s = (√(1 − h²)/√2 · (cos α, sin α, cos β, sin β), h),  h = γ·(L − ½),
    ///
    /// α, β the position relative to the tile's centre times [`SPAN`] / (`TILE` + 2 `MARGIN`).
    pub fn source(&self, x: f64, y: f64, luminance: f64, gamma: f64) -> [f64; 5] {
        let scale = SPAN / f64::from(TILE + 2 * MARGIN);
        let alpha = scale * (x - f64::from(self.x0) - 0.5 * f64::from(TILE));
        let beta = scale * (y - f64::from(self.y0) - 0.5 * f64::from(TILE));
        let h = gamma * (luminance.clamp(0.0, 1.0) - 0.5);
        let r = (1.0 - h * h).sqrt() / std::f64::consts::SQRT_2;
        [
            r * alpha.cos(),
            r * alpha.sin(),
            r * beta.cos(),
            r * beta.sin(),
            h,
        ]
    }

    /// The pixels this tile's network speaks for: the tile and its margins, within the picture.
    pub fn window(&self, width: u32, height: u32) -> (u32, u32, u32, u32) {
        (
            self.x0.saturating_sub(MARGIN),
            self.y0.saturating_sub(MARGIN),
            (self.x1 + MARGIN).min(width),
            (self.y1 + MARGIN).min(height),
        )
    }

    /// The unnormalized weight of this tile's network at pixel (`x`, `y`): 1 inside the tile
    /// shrunk by [`MARGIN`], falling linearly towards 0 at the window's edge (⅛ at its last
    /// pixel). Two neighbours' weights
    /// add up to 1 across their shared margin.
    pub fn fade(&self, x: u32, y: u32) -> f64 {
        let ramp = |p: u32, lo: u32, hi: u32| {
            let p = f64::from(p) + 0.5;
            let m = f64::from(MARGIN);
            ((p - f64::from(lo) + m).min(f64::from(hi) + m - p) / (2.0 * m)).clamp(0.0, 1.0)
        };
        ramp(x, self.x0, self.x0 + TILE) * ramp(y, self.y0, self.y0 + TILE)
    }
}

/// The sharpness that makes a key's blending fall to `overlap` at `reach` pixels from it.
pub fn sharpness_for(reach: f64, overlap: f64) -> f64 {
    let angle = SPAN / f64::from(TILE + 2 * MARGIN) * reach;
    let similarity = 0.5 * (angle.cos() + 1.0);
    -overlap.ln() / (1.0 - similarity).max(1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fades of the tiles covering a picture add up to 1 wherever two tiles meet, the
    /// source points are unit vectors, and a tile's window never reaches round its circles.
    #[test]
    fn tiles_fade_into_each_other() {
        let (w, h) = (21, 13);
        let tiles = Tile::cover(w, h);
        assert_eq!(tiles.len(), 3 * 2);
        for y in MARGIN..h - MARGIN {
            for x in MARGIN..w - MARGIN {
                let sum: f64 = tiles.iter().map(|t| t.fade(x, y)).sum();
                let inner = x + MARGIN < w && y + MARGIN < h;
                if inner && x >= TILE - MARGIN && y < TILE {
                    assert!((sum - 1.0).abs() < 1e-12, "({x}, {y}): {sum}");
                }
                assert!(sum > 0.0);
            }
        }
        for t in &tiles {
            let (x0, y0, x1, y1) = t.window(w, h);
            assert!(x0 <= t.x0 && t.x1 <= x1 && y0 <= t.y0 && t.y1 <= y1);
            let s = t.source(f64::from(x0), f64::from(y1), 0.9, 1.0);
            let norm: f64 = s.iter().map(|v| v * v).sum();
            assert!((norm - 1.0).abs() < 1e-12);
            // The far corner of the window against the tile's opposite corner: over 90° apart.
            let a = t.source(f64::from(t.x0), f64::from(t.y0), 0.5, 0.0);
            let b = t.source(f64::from(x1), f64::from(y1), 0.5, 0.0);
            let dot: f64 = a.iter().zip(&b).map(|(p, q)| p * q).sum();
            assert!(dot < 0.0, "{dot}");
        }
        assert!(sharpness_for(1.0, 0.3) > sharpness_for(4.0, 0.3));
    }
}
