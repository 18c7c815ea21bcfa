//! Scenes as SVG documents.

use std::fmt::Write as _;

use super::scene::Scene;

/// The SVG document of `scene`.
pub fn to_svg(scene: &Scene) -> String {
    let mut svg = String::new();
    let (w, h) = (scene.width, scene.height);
    let _ = writeln!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         viewBox=\"0 0 {w} {h}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>"
    );
    if let Some(title) = &scene.title {
        let escaped = title
            .replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;");
        let _ = writeln!(
            svg,
            "<text x=\"10\" y=\"20\" font-family=\"sans-serif\" font-size=\"14\">{escaped}</text>"
        );
    }
    for stroke in &scene.strokes {
        let tag = if stroke.closed { "polygon" } else { "polyline" };
        let dash = stroke.dash.map_or_else(String::new, |[on, off]| {
            format!(" stroke-dasharray=\"{on} {off}\"")
        });
        let _ = write!(
            svg,
            "<{tag} fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"{dash} points=\"",
            stroke.color.hex(),
            stroke.width
        );
        for [x, y] in &stroke.points {
            let _ = write!(svg, "{x:.2},{y:.2} ");
        }
        let _ = writeln!(svg, "\"/>");
    }
    for dot in &scene.dots {
        let [x, y] = dot.center;
        let _ = writeln!(
            svg,
            "<circle cx=\"{x:.2}\" cy=\"{y:.2}\" r=\"{}\" fill=\"{}\"/>",
            dot.radius,
            dot.color.hex()
        );
    }
    svg.push_str("</svg>\n");
    svg
}
