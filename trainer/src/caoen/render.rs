//! Depth-buffer rendering of Cao En surfaces (paper §10.3) with Lambert shading from the exact
//! normals, and the orthographic [`View`] shared with the ray marcher ([`super::raymarch`]).
//!
//! Each model's network is first turned into a screen network (paper §8): its targets are
//! replaced by their projections onto the screen axes α, β and the view direction, so the
//! same network evaluates screen coordinates and depth directly. Source points (an icosphere
//! or a torus grid) are mapped, and each source triangle whose screen edges are longer than
//! [`MAX_SAMPLE_GAP`] pixels is split in four at the midpoints of its source edges (the
//! paper's gap filling, stopped at a few pixels instead of below one). Each piece is then
//! rasterized: every pixel centre inside its screen triangle takes the interpolated depth and
//! source point if nearer; a piece too thin to hold a pixel centre draws its corners. Pieces
//! facing away from the camera (by their screen winding and the model's normals, outward or
//! inward) are culled: a closed surface hides them, and a sliver at a fold seen from behind
//! would otherwise win a pixel by its interpolated depth and show as a dark speck. A last
//! pass fills isolated empty pixels between two filled neighbours.
//!
//! Shading is deferred: only the source point that wins a pixel gets its exact unit normal
//! n (ambient + diffuse·max(0, n·l)), so a picture costs one normal per pixel however many
//! surfaces overlap there, and the position network runs only at the pieces' corners. Inside
//! a piece of at most 3 pixels the surface departs from the flat triangle by well under a
//! pixel wherever the mapping is smooth on that scale.

use image::RgbImage;

use super::network::CaoEnNetwork;
use super::{icosphere, on_domain, torus_grid};
use crate::error::{Error, Result};
use crate::geometry::vector::{cross, inner};
use crate::plot::{MAX_SIDE, Rgb};

/// Largest screen edge, in pixels, of a rasterized piece.
pub const MAX_SAMPLE_GAP: f64 = 3.0;
/// Deepest subdivision of one source triangle (4¹² pieces).
const MAX_DEPTH: u32 = 12;
/// Ambient share of the shading.
const AMBIENT: f64 = 0.2;

/// An orthographic camera: what is seen, from where, at what scale, and the light.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct View {
    /// The point at the centre of the picture.
    pub centre: [f64; 3],
    /// Unit direction the camera looks along (into the scene).
    pub direction: [f64; 3],
    /// Unit screen-right axis α.
    pub right: [f64; 3],
    /// Unit screen-up axis β.
    pub up: [f64; 3],
    /// Pixels per unit length.
    pub scale: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Unit direction towards the light.
    pub light: [f64; 3],
}

impl View {
    /// A camera framing every point of `points` (their centroid, and 1.05 times the largest
    /// distance from it), as [`View::framing`].
    ///
    /// # Errors
    /// As [`View::framing`].
    pub fn framing_points(
        points: &[[f64; 3]],
        direction: [f64; 3],
        up: [f64; 3],
        width: u32,
        height: u32,
    ) -> Result<View> {
        let count = points.len().max(1) as f64;
        let centre = points
            .iter()
            .fold([0.0; 3], |c, p| [0, 1, 2].map(|k| c[k] + p[k] / count));
        let radius = points
            .iter()
            .map(|p| {
                (0..3)
                    .map(|k| (p[k] - centre[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max);
        View::framing(
            centre,
            1.05 * radius.max(1e-9),
            direction,
            up,
            width,
            height,
        )
    }

    /// A camera looking along `direction` with `up` roughly up, framing the sphere of
    /// `radius` around `centre` in a `width` × `height` picture; the light comes from over
    /// the viewer's left shoulder.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a zero or non-finite direction, `up` parallel to it, a
    /// non-positive radius, or a side outside 1 … [`MAX_SIDE`].
    pub fn framing(
        centre: [f64; 3],
        radius: f64,
        direction: [f64; 3],
        up: [f64; 3],
        width: u32,
        height: u32,
    ) -> Result<View> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(Error::invalid(format!(
                "a picture of {width} × {height} pixels: each side must be 1 to {MAX_SIDE}"
            )));
        }
        let unit = |v: [f64; 3], what: &str| -> Result<[f64; 3]> {
            let r = inner(&v, &v).sqrt();
            if r > 1e-12 && r.is_finite() {
                Ok(v.map(|c| c / r))
            } else {
                Err(Error::invalid(format!("the view's {what} is degenerate")))
            }
        };
        if !(radius > 0.0 && radius.is_finite()) || centre.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(format!(
                "a view needs a finite centre and a positive radius, got {radius}"
            )));
        }
        let direction = unit(direction, "direction")?;
        let right = unit(cross(direction, up), "up (parallel to the direction)")?;
        let up = cross(right, direction);
        let light = unit(
            [0, 1, 2].map(|k| -direction[k] + 0.6 * up[k] - 0.5 * right[k]),
            "light",
        )?;
        Ok(View {
            centre,
            direction,
            right,
            up,
            scale: 0.5 * f64::from(width.min(height)) / radius,
            width,
            height,
            light,
        })
    }

    /// Screen x, y (pixels, y down) and depth of a point.
    pub fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let d = [0, 1, 2].map(|k| p[k] - self.centre[k]);
        [
            0.5 * f64::from(self.width) + self.scale * inner(&d, &self.right),
            0.5 * f64::from(self.height) - self.scale * inner(&d, &self.up),
            inner(&d, &self.direction),
        ]
    }

    /// The shade of a surface of `color` with unit normal `n` (Lambert, plus ambient).
    pub fn shade(&self, n: [f64; 3], color: Rgb) -> image::Rgb<u8> {
        let intensity = AMBIENT + (1.0 - AMBIENT) * inner(&n, &self.light).max(0.0);
        let scale = |c: u8| (f64::from(c) * intensity).round().clamp(0.0, 255.0) as u8;
        image::Rgb([scale(color.0), scale(color.1), scale(color.2)])
    }
}

/// A rendered picture with its depth buffer.
#[derive(Clone, Debug)]
pub struct Rendering {
    /// The shaded picture on a white background.
    pub image: RgbImage,
    /// Depth along the view direction per pixel, row-major; +∞ where nothing was drawn.
    pub depth: Vec<f64>,
    /// Which model drew each pixel (`None`: background).
    pub model: Vec<Option<usize>>,
    /// The source point behind each drawn pixel (deferred shading; empty for pictures shaded
    /// as they are drawn).
    sources: Vec<[f64; 4]>,
}

impl Rendering {
    /// A blank picture for `view`.
    pub(crate) fn new(view: &View) -> Self {
        let pixels = view.width as usize * view.height as usize;
        Rendering {
            image: RgbImage::from_pixel(view.width, view.height, image::Rgb([0xff; 3])),
            depth: vec![f64::INFINITY; pixels],
            model: vec![None; pixels],
            sources: Vec::new(),
        }
    }

    /// Records source point `x` (up to 4 coordinates) at screen point `s` for deferred
    /// shading if nearer than what is there.
    fn record(&mut self, s: [f64; 3], model: usize, x: [f64; 4]) {
        let (w, h) = (self.image.width(), self.image.height());
        if !(s[0] >= 0.0 && s[1] >= 0.0 && s[0] < f64::from(w) && s[1] < f64::from(h)) {
            return;
        }
        let i = s[1] as usize * w as usize + s[0] as usize;
        if s[2] < self.depth[i] {
            self.depth[i] = s[2];
            self.model[i] = Some(model);
            self.sources[i] = x;
        }
    }

    /// Rasterizes a screen triangle with source points `x`: every pixel centre inside takes
    /// the interpolated depth and source point if nearer. A triangle facing away (its signed
    /// screen area positive if `back_is_positive`, negative otherwise) is culled. Returns
    /// whether it held a centre or was culled.
    fn raster(
        &mut self,
        s: &[[f64; 3]; 3],
        x: &[[f64; 4]; 3],
        model: usize,
        back_is_positive: bool,
    ) -> bool {
        let (w, h) = (self.image.width() as i64, self.image.height() as i64);
        let low = |k: usize| s.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let high = |k: usize| s.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        let (x0, x1) = (
            ((low(0) - 0.5).ceil() as i64).max(0),
            ((high(0) - 0.5).floor() as i64).min(w - 1),
        );
        let (y0, y1) = (
            ((low(1) - 0.5).ceil() as i64).max(0),
            ((high(1) - 0.5).floor() as i64).min(h - 1),
        );
        let area =
            (s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) - (s[1][1] - s[0][1]) * (s[2][0] - s[0][0]);
        if area == 0.0 || !area.is_finite() || x0 > x1 || y0 > y1 {
            return false;
        }
        if (area > 0.0) == back_is_positive {
            return true;
        }
        let mut any = false;
        for py in y0..=y1 {
            for px in x0..=x1 {
                let c = [px as f64 + 0.5, py as f64 + 0.5];
                let edge = |a: [f64; 3], b: [f64; 3]| {
                    ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / area
                };
                let l = [edge(s[1], s[2]), edge(s[2], s[0]), edge(s[0], s[1])];
                if l.iter().any(|&v| v < -1e-9) {
                    continue;
                }
                any = true;
                let depth = l[0] * s[0][2] + l[1] * s[1][2] + l[2] * s[2][2];
                let i = py as usize * w as usize + px as usize;
                if depth < self.depth[i] {
                    self.depth[i] = depth;
                    self.model[i] = Some(model);
                    self.sources[i] =
                        [0, 1, 2, 3].map(|k| l[0] * x[0][k] + l[1] * x[1][k] + l[2] * x[2][k]);
                }
            }
        }
        any
    }

    /// Draws at screen point `s` if nearer than what is there; returns whether it did.
    pub(crate) fn splat(&mut self, s: [f64; 3], model: usize, color: image::Rgb<u8>) -> bool {
        let (w, h) = (self.image.width(), self.image.height());
        if !(s[0] >= 0.0 && s[1] >= 0.0 && s[0] < f64::from(w) && s[1] < f64::from(h)) {
            return false;
        }
        let (x, y) = (s[0] as u32, s[1] as u32);
        let i = y as usize * w as usize + x as usize;
        if s[2] < self.depth[i] {
            self.depth[i] = s[2];
            self.model[i] = Some(model);
            self.image.put_pixel(x, y, color);
            true
        } else {
            false
        }
    }

    /// Number of pixels drawn.
    pub fn covered(&self) -> usize {
        self.model.iter().filter(|m| m.is_some()).count()
    }

    /// Fills every empty pixel whose two opposite neighbours (left/right or above/below) are
    /// drawn, with the nearer of them.
    fn fill_gaps(&mut self) {
        let (w, h) = (self.image.width() as usize, self.image.height() as usize);
        let mut fills = Vec::new();
        for y in 1..h.saturating_sub(1) {
            for x in 1..w.saturating_sub(1) {
                let i = y * w + x;
                if self.model[i].is_some() {
                    continue;
                }
                let nearer = [(i - 1, i + 1), (i - w, i + w)]
                    .into_iter()
                    .filter(|&(a, b)| self.model[a].is_some() && self.model[b].is_some())
                    .flat_map(|(a, b)| [a, b])
                    .min_by(|&a, &b| self.depth[a].total_cmp(&self.depth[b]));
                if let Some(from) = nearer {
                    fills.push((i, from));
                }
            }
        }
        for (i, from) in fills {
            self.depth[i] = self.depth[from];
            self.model[i] = self.model[from];
            let (fx, fy) = ((from % w) as u32, (from / w) as u32);
            let color = *self.image.get_pixel(fx, fy);
            self.image.put_pixel((i % w) as u32, (i / w) as u32, color);
        }
    }
}

/// A source triangle awaiting drawing: its source points, their screen points, its depth
/// of subdivision.
type Piece = ([Vec<f64>; 3], [[f64; 3]; 3], u32);

/// Renders the surfaces of `models` (sphere or torus networks with p = 3, each with its
/// colour) into a depth buffer; `subdivisions` sets the starting source grid (an icosphere of
/// that level, or a torus grid of 10·2ˢ × 5·2ˢ), refined per triangle to
/// [`MAX_SAMPLE_GAP`].
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid network, one with p ≠ 3 or another domain than
/// the sphere (m = 3) and the torus, or `subdivisions` above 6.
pub fn depth_buffer_image(
    models: &[(&CaoEnNetwork, Rgb)],
    view: &View,
    subdivisions: usize,
) -> Result<Rendering> {
    if subdivisions > 6 {
        return Err(Error::invalid(format!(
            "at most 6 subdivisions for the starting grid, got {subdivisions}"
        )));
    }
    let mut picture = Rendering::new(view);
    picture.sources = vec![[0.0; 4]; picture.depth.len()];
    for (index, &(network, _)) in models.iter().enumerate() {
        network.validate()?;
        let (m, p) = (network.source_dimension(), network.target_dimension());
        let (sources, triangles) = match (network.domain, m, p) {
            (0, 3, 3) => {
                let sphere = icosphere(subdivisions)?;
                let sources: Vec<Vec<f64>> = sphere.positions.iter().map(|x| x.to_vec()).collect();
                (sources, sphere.triangles)
            }
            (1, 4, 3) => {
                let grid = torus_grid(10 << subdivisions, 5 << subdivisions)?;
                (grid.sources, grid.triangles)
            }
            _ => {
                return Err(Error::invalid(format!(
                    "model {index}: depth-buffer rendering needs a sphere (m = 3) or torus \
                     network with p = 3, got domain {} with m = {m}, p = {p}",
                    network.domain
                )));
            }
        };
        let screen = screen_network(network, view);
        let offset = view.project([0.0; 3]);
        let to_screen = |x: &[f64]| -> [f64; 3] {
            let y = screen.position(x);
            [offset[0] + y[0], offset[1] + y[1], offset[2] + y[2]]
        };
        let four = |x: &[f64]| -> [f64; 4] {
            let mut out = [0.0; 4];
            out[..x.len()].copy_from_slice(x);
            out
        };
        let mapped: Vec<[f64; 3]> = sources.iter().map(|x| to_screen(x)).collect();
        let back_is_positive = normals_point_out(network, &sources);
        let mut stack: Vec<Piece> = triangles
            .iter()
            .map(|t| {
                (
                    t.map(|v| sources[v as usize].clone()),
                    t.map(|v| mapped[v as usize]),
                    0,
                )
            })
            .collect();
        while let Some((x, s, depth)) = stack.pop() {
            let gap = (0..3)
                .map(|k| {
                    let (a, b) = (s[k], s[(k + 1) % 3]);
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
                })
                .fold(0.0, f64::max);
            let on_screen = s.iter().any(|p| {
                p[0] > -2.0
                    && p[1] > -2.0
                    && p[0] < f64::from(view.width) + 2.0
                    && p[1] < f64::from(view.height) + 2.0
            });
            if gap <= MAX_SAMPLE_GAP || depth >= MAX_DEPTH || (!on_screen && gap < 4.0) {
                let corners = [four(&x[0]), four(&x[1]), four(&x[2])];
                if !picture.raster(&s, &corners, index, back_is_positive) {
                    for k in 0..3 {
                        picture.record(s[k], index, corners[k]);
                    }
                }
                continue;
            }
            let middle = |a: &[f64], b: &[f64]| -> Vec<f64> {
                let sum: Vec<f64> = a.iter().zip(b).map(|(p, q)| p + q).collect();
                on_domain(network.domain, &sum)
            };
            let [a, b, c] = &x;
            let (ab, bc, ca) = (middle(a, b), middle(b, c), middle(c, a));
            let (sab, sbc, sca) = (to_screen(&ab), to_screen(&bc), to_screen(&ca));
            let next = depth + 1;
            stack.push(([a.clone(), ab.clone(), ca.clone()], [s[0], sab, sca], next));
            stack.push(([b.clone(), bc.clone(), ab.clone()], [s[1], sbc, sab], next));
            stack.push(([c.clone(), ca.clone(), bc.clone()], [s[2], sca, sbc], next));
            stack.push(([ab, bc, ca], [sab, sbc, sca], next));
        }
    }
    picture.shade_deferred(models, view);
    picture.fill_gaps();
    Ok(picture)
}

/// Whether the network's exact normals point away from its surface's centroid at most of
/// `sources`: then a piece whose screen triangle has positive signed area (the screen's y
/// axis points down) faces away from the camera. A closed surface hides such pieces behind
/// the ones facing the camera; culling them keeps a fold or a sliver seen from behind from
/// winning a pixel by its interpolated depth.
fn normals_point_out(network: &CaoEnNetwork, sources: &[Vec<f64>]) -> bool {
    let positions: Vec<Vec<f64>> = sources.iter().map(|x| network.position(x)).collect();
    let count = positions.len().max(1) as f64;
    let centre = [0, 1, 2].map(|k| positions.iter().map(|p| p[k]).sum::<f64>() / count);
    let outward: f64 = sources
        .iter()
        .zip(&positions)
        .filter_map(|(x, p)| {
            let n = network.normal(x)?;
            Some((0..3).map(|k| n[k] * (p[k] - centre[k])).sum::<f64>())
        })
        .sum();
    outward >= 0.0
}

impl Rendering {
    /// Shades every drawn pixel from the exact normal at its source point (projected back
    /// onto the model's domain), on all threads.
    fn shade_deferred(&mut self, models: &[(&CaoEnNetwork, Rgb)], view: &View) {
        use rayon::prelude::*;
        let width = self.image.width() as usize;
        let colors: Vec<(usize, image::Rgb<u8>)> = self
            .model
            .par_iter()
            .zip(&self.sources)
            .enumerate()
            .filter_map(|(i, (model, x))| {
                let (network, color) = models[(*model)?];
                let m = network.source_dimension().min(4);
                let point = on_domain(network.domain, &x[..m]);
                let n = network.normal(&point).unwrap_or([0.0; 3]);
                Some((i, view.shade(n, color)))
            })
            .collect();
        for (i, color) in colors {
            self.image
                .put_pixel((i % width) as u32, (i / width) as u32, color);
        }
    }
}

/// The paper's projection network (§8): targets replaced by (α·t, −β·t, d·t) scaled to
/// pixels, so the network's output is the screen position relative to the projected origin.
fn screen_network(network: &CaoEnNetwork, view: &View) -> CaoEnNetwork {
    let targets = network
        .targets
        .iter()
        .map(|t| {
            vec![
                view.scale * inner(t, &view.right),
                -view.scale * inner(t, &view.up),
                inner(t, &view.direction),
            ]
        })
        .collect();
    CaoEnNetwork {
        targets,
        ..network.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::from_key_points;
    use crate::caoen::support::{axes, fibonacci, fitted};
    use neurosurf_core::caoen::{Blending, Domain};

    /// The paper's Fig. 2 network with q = 1: exactly the unit sphere.
    fn unit_sphere() -> CaoEnNetwork {
        from_key_points(
            Domain::Sphere,
            Blending::Power,
            false,
            &axes(),
            &axes(),
            1.0,
        )
        .unwrap()
    }

    /// The paper's Fig. 2 network with q = 1 is exactly the unit sphere: its picture is a
    /// disc of πr² pixels (within 2 %: silhouette pixels count when any sample lands in them)
    /// with no hole inside.
    #[test]
    fn unit_sphere_renders_a_full_disc() {
        let sphere = unit_sphere();
        let view =
            View::framing([0.0; 3], 1.25, [0.3, -0.2, -1.0], [0.0, 1.0, 0.0], 200, 200).unwrap();
        let picture = depth_buffer_image(&[(&sphere, Rgb(200, 80, 40))], &view, 2).unwrap();
        let r = view.scale;
        let expected = std::f64::consts::PI * r * r;
        let covered = picture.covered() as f64;
        println!("disc: {covered} pixels, πr² = {expected:.0}");
        assert!((covered / expected - 1.0).abs() < 0.02);
        for y in 0..200_u32 {
            for x in 0..200_u32 {
                let d = ((f64::from(x) + 0.5 - 100.0).powi(2)
                    + (f64::from(y) + 0.5 - 100.0).powi(2))
                .sqrt();
                let i = (y * 200 + x) as usize;
                if d < r - 1.0 {
                    assert!(picture.model[i].is_some(), "hole at {x}, {y}");
                    // Depth of the sphere's front: −√(1 − ρ²) in view units.
                    let rho = d / r;
                    assert!((picture.depth[i] + (1.0 - rho * rho).sqrt()).abs() < 0.05);
                }
                if d > r + 1.5 {
                    assert!(picture.model[i].is_none());
                }
            }
        }
        // Lit from over the left shoulder: the upper left is brighter than the lower right.
        let (a, b) = (
            picture.image.get_pixel(70, 70),
            picture.image.get_pixel(130, 130),
        );
        assert!(a[0] > b[0]);
    }

    /// On the coordinate great circles a key's sᵢ is exactly 0, the kink of F(s) = s: the
    /// normal there is still x, and the picture has no dark dotted circles (each interior
    /// pixel is within a few levels of its neighbours).
    #[test]
    fn unit_sphere_is_shaded_smoothly_across_the_coordinate_circles() {
        let sphere = unit_sphere();
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            for t in [0.0, 0.4, 1.3, 2.9, 4.4] {
                let mut x = [0.0; 3];
                (x[a], x[b]) = (f64::cos(t), f64::sin(t));
                let n = sphere.normal(&x).expect("a normal");
                let off: f64 = (0..3).map(|k| (n[k] - x[k]).abs()).sum();
                assert!(off < 1e-12, "{x:?}: {n:?}");
            }
        }
        let view =
            View::framing([0.0; 3], 1.25, [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], 160, 160).unwrap();
        let picture = depth_buffer_image(&[(&sphere, Rgb(200, 80, 40))], &view, 2).unwrap();
        let r = view.scale;
        let red = |x: u32, y: u32| i32::from(picture.image.get_pixel(x, y)[0]);
        for y in 1..159_u32 {
            for x in 1..159_u32 {
                let d = ((f64::from(x) + 0.5 - 80.0).powi(2) + (f64::from(y) + 0.5 - 80.0).powi(2))
                    .sqrt();
                if d < r - 3.0 {
                    let step = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
                        .map(|(u, v)| (red(u, v) - red(x, y)).abs())
                        .into_iter()
                        .max()
                        .unwrap();
                    assert!(step <= 12, "a step of {step} at {x}, {y}");
                }
            }
        }
    }

    /// A small sphere in front of a large one hides it where they overlap, whatever order
    /// they are drawn in.
    #[test]
    fn nearer_surfaces_win_the_depth_test() {
        let keys = fibonacci(26);
        let ball = |centre: [f64; 3], radius: f64| {
            let targets: Vec<Vec<f64>> = keys
                .iter()
                .map(|k| (0..3).map(|j| centre[j] + radius * k[j]).collect())
                .collect();
            fitted(&keys, &targets, Blending::Exponential, true, 6.0)
        };
        let (back, front) = (ball([0.0; 3], 1.0), ball([0.3, 0.0, 1.2], 0.4));
        let view =
            View::framing([0.0; 3], 1.5, [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], 120, 120).unwrap();
        let (red, blue) = (Rgb(200, 0, 0), Rgb(0, 0, 200));
        let one = depth_buffer_image(&[(&back, red), (&front, blue)], &view, 2).unwrap();
        let two = depth_buffer_image(&[(&front, blue), (&back, red)], &view, 2).unwrap();
        let swapped: Vec<Option<usize>> = two.model.iter().map(|m| m.map(|i| 1 - i)).collect();
        let differ = one
            .model
            .iter()
            .zip(&swapped)
            .filter(|(a, b)| a != b)
            .count();
        assert!(differ <= 2, "{differ} pixels depend on the drawing order");
        // The small sphere's centre projects to (60 + 0.3·40, 60): blue; far left: red.
        let at = |x: usize, y: usize| one.model[y * 120 + x];
        assert_eq!(at(72, 60), Some(1));
        assert_eq!(at(25, 60), Some(0));
        assert!(one.depth[60 * 120 + 72] < -1.0);
    }

    #[test]
    fn bad_views_and_models_are_errors() {
        assert!(View::framing([0.0; 3], 1.0, [0.0, 0.0, 1.0], [0.0, 0.0, 2.0], 10, 10).is_err());
        assert!(View::framing([0.0; 3], 0.0, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 10, 10).is_err());
        assert!(View::framing([0.0; 3], 1.0, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 0, 10).is_err());
        let view = View::framing([0.0; 3], 1.0, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 8, 8).unwrap();
        let sphere = unit_sphere();
        assert!(depth_buffer_image(&[(&sphere, Rgb::WHITE)], &view, 7).is_err());
        let mut flat = sphere.clone();
        flat.targets.iter_mut().for_each(|t| t.truncate(2));
        assert!(depth_buffer_image(&[(&flat, Rgb::WHITE)], &view, 1).is_err());
    }
}
