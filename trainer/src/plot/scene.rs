//! What a picture shows: strokes (polylines) and dots, in pixel coordinates with +y down.

/// An sRGB colour.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// White, the background.
    pub const WHITE: Rgb = Rgb(0xff, 0xff, 0xff);

    /// `#rrggbb`.
    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }
}

/// A polyline of constant width.
#[derive(Clone, Debug, PartialEq)]
pub struct Stroke {
    /// Vertices in pixels.
    pub points: Vec<[f64; 2]>,
    /// Whether the last vertex joins the first.
    pub closed: bool,
    /// Colour.
    pub color: Rgb,
    /// Width in pixels.
    pub width: f64,
    /// Dash and gap lengths in pixels, when dashed.
    pub dash: Option<[f64; 2]>,
}

impl Stroke {
    /// An open, solid polyline.
    pub fn new(points: Vec<[f64; 2]>, color: Rgb, width: f64) -> Self {
        Stroke {
            points,
            closed: false,
            color,
            width,
            dash: None,
        }
    }

    /// The segments, including the closing one.
    pub fn segments(&self) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
        let closing = self
            .closed
            .then(|| Some((*self.points.last()?, *self.points.first()?)))
            .flatten();
        self.points.windows(2).map(|w| (w[0], w[1])).chain(closing)
    }
}

/// A filled disc.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Dot {
    /// Centre in pixels.
    pub center: [f64; 2],
    /// Radius in pixels.
    pub radius: f64,
    /// Colour.
    pub color: Rgb,
}

/// A picture: a white canvas, strokes drawn in order, then dots, then the caption.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Polylines, back to front.
    pub strokes: Vec<Stroke>,
    /// Discs, drawn over the strokes.
    pub dots: Vec<Dot>,
    /// A caption at the top left (SVG only: the raster writer has no font).
    pub title: Option<String>,
}

impl Scene {
    /// An empty `width` × `height` scene.
    pub fn new(width: u32, height: u32) -> Self {
        Scene {
            width,
            height,
            strokes: Vec::new(),
            dots: Vec::new(),
            title: None,
        }
    }
}
