//! Pictures of a reconstruction (SVG or PNG): the points, the recovered order, the chain, the
//! spline.
//!
//! 2-D data is drawn in its own XY plane; 3-D data is projected orthogonally onto its
//! best-fit plane (spanned by the two largest principal axes of the points), or onto XY on
//! request. The picture keeps the aspect ratio and puts +y up.

use std::path::Path;

use nalgebra::{Matrix3, SymmetricEigen};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::plot::{Dot, Rgb, Scene, Stroke, to_svg, write_picture};

use super::kohonen::{KohonenChain, Topology};
use super::spline::BSplineCurve;
use crate::geometry::vector::{dot, sub};

/// How 3-D points are flattened.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Projection {
    /// XY for 2-D data (all z = 0), the best-fit plane otherwise.
    #[default]
    Auto,
    /// Drop z.
    Xy,
    /// The plane of the two largest principal axes of the points.
    BestFitPlane,
}

/// Size and look of a plot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlotOptions {
    /// Width in pixels (800).
    pub width: u32,
    /// Height in pixels (800).
    pub height: u32,
    /// Flattening of 3-D data (auto).
    pub projection: Projection,
    /// Polyline vertices per spline segment (16).
    pub samples_per_segment: usize,
    /// A caption at the top (none).
    pub title: Option<String>,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions {
            width: 800,
            height: 800,
            projection: Projection::Auto,
            samples_per_segment: 16,
            title: None,
        }
    }
}

/// What to draw; every layer but the points is optional. Drawn back to front: true curve
/// (grey), chain (light blue), order polyline (orange), control polygon (dashed grey),
/// spline (blue), points (black).
#[derive(Clone, Copy, Debug, Default)]
pub struct PlotLayers<'a> {
    /// The input points.
    pub points: &'a [[f64; 3]],
    /// A recovered order (indices into `points`), drawn as a polyline.
    pub order: Option<&'a [usize]>,
    /// Whether the order polyline closes.
    pub closed: bool,
    /// The trained chain.
    pub chain: Option<&'a KohonenChain>,
    /// The fitted spline.
    pub curve: Option<&'a BSplineCurve>,
    /// More fitted splines (of other groups of the points), drawn alike.
    pub more_curves: &'a [BSplineCurve],
    /// Also draw the spline's control polygon.
    pub control_polygon: bool,
    /// The true curve as a polyline.
    pub truth: Option<&'a [[f64; 3]]>,
}

/// The picture as a [`Scene`], for [`crate::plot`] to write as SVG or PNG.
///
/// # Errors
/// [`Error::InvalidInput`] for neither points nor a curve, a non-finite coordinate, an order
/// index out of range, or a zero width or height.
pub fn plot_scene(layers: &PlotLayers<'_>, options: &PlotOptions) -> Result<Scene> {
    if layers.points.is_empty() && layers.curve.is_none() {
        return Err(Error::invalid("nothing to plot: no points and no curve"));
    }
    if options.width == 0 || options.height == 0 {
        return Err(Error::invalid(format!(
            "plot size {} × {} has a zero side",
            options.width, options.height
        )));
    }
    if let Some(order) = layers.order
        && let Some(&bad) = order.iter().find(|&&i| i >= layers.points.len())
    {
        return Err(Error::invalid(format!(
            "order index {bad} is out of range for {} points",
            layers.points.len()
        )));
    }
    let polyline =
        |c: &BSplineCurve| c.polyline(c.segments().max(1) * options.samples_per_segment.max(1));
    let spline = layers.curve.map(polyline);
    let more: Vec<[f64; 3]> = layers.more_curves.iter().flat_map(&polyline).collect();
    // Everything drawn is framed: points, truth, spline, and the control polygon and chain
    // when they are drawn (an approximating spline's control points often lie outside it).
    let control = layers
        .curve
        .filter(|_| layers.control_polygon)
        .map(|c| c.control.as_slice());
    let chain = layers.chain.map(|c| c.neurons.as_slice());
    let drawn: Vec<[f64; 3]> = [
        Some(layers.points),
        layers.truth,
        spline.as_deref(),
        Some(&more),
        control,
        chain,
    ]
    .into_iter()
    .flatten()
    .flatten()
    .copied()
    .collect();
    let frame = Frame::fit(&drawn, options.projection)?;
    let all: Vec<[f64; 2]> = drawn.iter().map(|&p| frame.flatten(p)).collect();
    if all.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
        return Err(Error::invalid(
            "a plotted point has a non-finite coordinate",
        ));
    }
    let view = View::new(&all, options.width as f64, options.height as f64);
    let to_pixels = |p: &[f64; 3]| view.pixel(frame.flatten(*p));
    let line = |points: &mut dyn Iterator<Item = &[f64; 3]>, color: Rgb, width: f64| {
        Stroke::new(points.map(to_pixels).collect(), color, width)
    };

    let mut scene = Scene::new(options.width, options.height);
    scene.title = options.title.clone();
    if let Some(truth) = layers.truth {
        scene
            .strokes
            .push(line(&mut truth.iter(), Rgb(0xbb, 0xbb, 0xbb), 3.0));
    }
    if let Some(chain) = layers.chain {
        let mut stroke = line(&mut chain.neurons.iter(), Rgb(0x88, 0xbb, 0xee), 1.0);
        stroke.closed = chain.topology == Topology::Closed;
        scene.strokes.push(stroke);
    }
    if let Some(order) = layers.order {
        let points = layers.points;
        let mut stroke = line(
            &mut order.iter().map(|&i| &points[i]),
            Rgb(0xee, 0x88, 0x33),
            1.5,
        );
        stroke.closed = layers.closed;
        scene.strokes.push(stroke);
    }
    if let (Some(curve), true) = (layers.curve, layers.control_polygon) {
        let mut stroke = line(&mut curve.control.iter(), Rgb(0x99, 0x99, 0x99), 1.0);
        stroke.closed = curve.closed;
        stroke.dash = Some([4.0, 3.0]);
        scene.strokes.push(stroke);
    }
    if let Some(spline) = &spline {
        scene
            .strokes
            .push(line(&mut spline.iter(), Rgb(0x22, 0x55, 0xcc), 2.0));
    }
    for curve in layers.more_curves {
        let mut stroke = line(&mut polyline(curve).iter(), Rgb(0x22, 0x55, 0xcc), 2.0);
        stroke.closed = curve.closed;
        scene.strokes.push(stroke);
    }
    for p in layers.points {
        scene.dots.push(Dot {
            center: to_pixels(p),
            radius: 2.5,
            color: Rgb(0, 0, 0),
        });
    }
    Ok(scene)
}

/// The SVG document of [`plot_scene`].
///
/// # Errors
/// As [`plot_scene`].
pub fn render_svg(layers: &PlotLayers<'_>, options: &PlotOptions) -> Result<String> {
    Ok(to_svg(&plot_scene(layers, options)?))
}

/// Renders the plot and writes it to `path` atomically: PNG for a `.png` path, SVG for
/// `.svg` (the PNG has no caption).
///
/// # Errors
/// As [`plot_scene`] and [`write_picture`].
pub fn write_plot(path: &Path, layers: &PlotLayers<'_>, options: &PlotOptions) -> Result<()> {
    write_picture(path, &plot_scene(layers, options)?)
}

/// An orthonormal plane frame: origin and two axes.
struct Frame {
    origin: [f64; 3],
    axes: [[f64; 3]; 2],
}

impl Frame {
    fn fit(points: &[[f64; 3]], projection: Projection) -> Result<Frame> {
        let planar = points.iter().all(|p| p[2] == 0.0);
        let xy = Frame {
            origin: [0.0; 3],
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        };
        match projection {
            Projection::Xy => return Ok(xy),
            Projection::Auto if planar => return Ok(xy),
            _ => {}
        }
        let n = points.len() as f64;
        let mut mean = [0.0; 3];
        for p in points {
            for k in 0..3 {
                mean[k] += p[k] / n;
            }
        }
        let mut covariance = Matrix3::<f64>::zeros();
        for p in points {
            let d = sub(*p, mean);
            for r in 0..3 {
                for c in 0..3 {
                    covariance[(r, c)] += d[r] * d[c];
                }
            }
        }
        if !covariance.iter().all(|c| c.is_finite()) {
            return Err(Error::invalid(
                "a plotted point has a non-finite coordinate",
            ));
        }
        let eigen = SymmetricEigen::new(covariance);
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        let axis = |i: usize| {
            let v = eigen.eigenvectors.column(order[i]);
            [v[0], v[1], v[2]]
        };
        Ok(Frame {
            origin: mean,
            axes: [axis(0), axis(1)],
        })
    }

    fn flatten(&self, p: [f64; 3]) -> [f64; 2] {
        let d = sub(p, self.origin);
        [dot(d, self.axes[0]), dot(d, self.axes[1])]
    }
}

/// Plane → pixels: uniform scale, 5 % margin, +y up.
struct View {
    lower: [f64; 2],
    scale: f64,
    offset: [f64; 2],
    height: f64,
}

impl View {
    fn new(points: &[[f64; 2]], width: f64, height: f64) -> View {
        let mut lower = [f64::INFINITY; 2];
        let mut upper = [f64::NEG_INFINITY; 2];
        for p in points {
            for k in 0..2 {
                lower[k] = lower[k].min(p[k]);
                upper[k] = upper[k].max(p[k]);
            }
        }
        let extent = [upper[0] - lower[0], upper[1] - lower[1]];
        let usable = [0.9 * width, 0.9 * height];
        let scale = (usable[0] / extent[0].max(1e-300)).min(usable[1] / extent[1].max(1e-300));
        let offset = [
            0.5 * (width - scale * extent[0]),
            0.5 * (height - scale * extent[1]),
        ];
        View {
            lower,
            scale,
            offset,
            height,
        }
    }

    fn pixel(&self, p: [f64; 2]) -> [f64; 2] {
        let x = self.offset[0] + self.scale * (p[0] - self.lower[0]);
        let y = self.offset[1] + self.scale * (p[1] - self.lower[1]);
        [x, self.height - y]
    }
}
