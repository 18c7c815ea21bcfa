//! The demo's `index.html`: one static page (no script, no server) with the pictures,
//! referenced by relative file names in the same folder, the paper's Tables 2–4 beside this
//! machine's times, its Table 5 (network against RBF on the torus) measured again, the body's
//! per-module training (Fig. 9), the animation's frames, and the fixed-vs-float accuracy
//! tables.

use std::fmt::Write as _;
use std::path::Path;

use super::DemoReport;
use super::pictures::Picture;
use super::table5::{TABLE5_DIAMETER, TABLE5_HELD_OUT, Table5Row};
use crate::error::Result;
use crate::io::write_atomic;

/// The report's file name inside the output folder.
pub const INDEX: &str = "index.html";

/// Escapes text for HTML.
fn esc(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn figure(out: &mut String, p: &Picture) {
    let _ = writeln!(
        out,
        "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}<br><small>{}×{}, {} ray(s)/pixel, \
         {:.2} s</small></figcaption></figure>",
        esc(&p.file),
        esc(&p.caption),
        esc(&p.caption),
        p.stats.width,
        p.stats.height,
        p.stats.samples,
        p.stats.seconds
    );
}

fn seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else {
        format!("{:.1} ms", 1e3 * s)
    }
}

/// The paper's Table 5 beside this run's: the torus by one network module and by the RBF.
fn table5(out: &mut String, rows: &[Table5Row]) {
    let seeds = rows.first().map_or_else(String::new, |r| {
        let s: Vec<String> = r.seeds.iter().map(u64::to_string).collect();
        s.join(", ")
    });
    let _ = write!(
        out,
        "<h2>The network against an RBF network (Table 5)</h2>\n<p>The torus R = 1, r = 0.4 \
         learned from n control points by one network module (Table 1's settings; the paper's \
         procedure alone, without off-surface or sign points) and by the \
         multiquadric RBF interpolant (two-sided off-surface points); seed {seeds}, one thread. The paper: a C program on a \
         1.7 GHz Pentium IV (in parentheses). Fidelity: median distance in % of the diameter \
         D = {TABLE5_DIAMETER} / median normal error on {TABLE5_HELD_OUT} held-out points of \
         the true torus (the paper gives none).</p>\n<table><tr><th>points</th>\
         <th>network iterations (+ coarse)</th><th>network time</th><th>RBF time</th>\
         <th>network fidelity</th><th>RBF fidelity</th><th class=l>training</th></tr>\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td>{:.0}{} (+ {:.0})</td><td>{}{}</td><td>{}{}</td>\
             <td>{:.3} % / {:.2}°</td><td>{:.3} % / {:.2}°</td><td class=l>{}</td></tr>",
            r.points,
            r.iterations,
            r.beside_paper(|p| p.iterations.to_string()),
            r.coarse_iterations,
            seconds(r.network_seconds),
            r.beside_paper(|p| seconds(p.network_seconds)),
            seconds(r.rbf_seconds),
            r.beside_paper(|p| seconds(p.rbf_seconds)),
            r.network_distance_percent,
            r.network_angle_degrees,
            r.rbf_distance_percent,
            r.rbf_angle_degrees,
            r.outcome
        );
    }
    out.push_str("</table>\n");
}

/// Renders the page for `report`.
pub fn html(report: &DemoReport) -> String {
    let mut o = String::new();
    o.push_str(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n\
         <title>neurosurf demo: Carcenac's modular neural implicit surfaces</title>\n<style>\n\
         body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em;color:#222}\n\
         table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.2em .5em;\
         text-align:right}th{background:#eee}td.l,th.l{text-align:left}\n\
         figure{display:inline-block;margin:.5em;vertical-align:top;text-align:center}\n\
         figcaption{max-width:16em;font-size:.9em}\n</style></head><body>\n\
         <h1>neurosurf demo</h1>\n<p>Carcenac (2004), <i>An implicit surface modeling technique \
         based on a modular neural network architecture</i>: implicit surfaces Φ = 0 learned by binary \
         trees of small MLP modules from control points with normals (Levenberg–Marquardt, \
         Table 1's parameters), rendered by the §6 ray caster through the core in f32. \
         Everything here was computed by <code>neurosurf demo</code>; the numbers are this \
         run's.</p>\n",
    );
    if let Some(tour) = &report.tour {
        o.push_str("<h2>Pictures</h2>\n");
        for p in &tour.pictures {
            if !p.file.starts_with("frame-") {
                figure(&mut o, p);
            }
        }
        o.push_str(
            "<h2>Gradual memorization of the head (Fig. 6)</h2>\n<p>The head after each of \
             its modules: a leaf learns the bare head, a node blends the nose in, the root the \
             mouth.</p>\n",
        );
        for p in &tour.memorization {
            figure(&mut o, p);
        }
        let a = &tour.animation;
        let _ = write!(
            o,
            "<h2>Animation (Table 4, Fig. 10)</h2>\n<p>{} frames raising and flexing both \
             arms and the right leg; frame 0 is learned cold, every later frame starts from \
             the previous frame's weights. Incremental frames took {} on average ({} to {}), \
             {:.0} LM iterations on average against {} for the cold start; training {}. The \
             last frame's median distance to its true body: {:.3} % of the diameter, median \
             normal error {:.2}°; measured both ways against its true surface: {}.</p>\n",
            a.frames,
            seconds(a.seconds.average),
            seconds(a.seconds.min),
            seconds(a.seconds.max),
            a.iterations.average,
            a.cold_iterations,
            a.outcome,
            a.last_fidelity.median_distance_percent,
            a.last_fidelity.median_angle_degrees,
            esc(&a.last_two_sided.to_string())
        );
        for p in &tour.pictures {
            if p.file.starts_with("frame-") {
                figure(&mut o, p);
            }
        }
        o.push_str(
            "<h2>Computing times beside the paper's (Tables 2–4)</h2>\n<p>The paper: a C \
             program on a 500 MHz Pentium III. Here: this machine, all cores, the times of \
             this run.</p>\n<table><tr><th class=l>table</th><th class=l>what</th>\
             <th>paper</th><th>here</th><th>speed-up</th><th class=l>note</th></tr>\n",
        );
        for t in &tour.timings {
            let _ = writeln!(
                o,
                "<tr><td class=l>{}</td><td class=l>{}</td><td>{} s</td><td>{}</td>\
                 <td>{:.0}×</td><td class=l>{}</td></tr>",
                esc(&t.table),
                esc(&t.what),
                t.paper_seconds,
                seconds(t.seconds),
                t.paper_seconds / t.seconds.max(1e-9),
                esc(&t.note)
            );
        }
        o.push_str("</table>\n");
        table5(&mut o, &tour.table5);
        let b = &tour.body;
        let _ = write!(
            o,
            "<h2>The body (Table 3, Fig. 8–9)</h2>\n<p>{} control points in {} features \
             ({}), tree <code>{}</code>: {} LM iterations in {}, training {}. \
             On {} held-out points of the true body: median distance {:.3} % of the diameter \
             D = {:.2}, RMS {:.3} %, median normal error {:.2}°. Both ways against the true \
             surface: {}.</p>\n<table><tr>\
             <th>module</th><th class=l>learns</th><th>points</th><th>iterations</th>\
             <th>time</th><th>final E<sub>s</sub></th></tr>\n",
            b.control_points,
            b.features.len(),
            esc(&b.features.join(", ")),
            esc(&b.tree),
            b.iterations,
            seconds(b.seconds),
            b.outcome,
            b.fidelity.points,
            b.fidelity.median_distance_percent,
            b.fidelity.diameter,
            b.fidelity.rms_distance_percent,
            b.fidelity.median_angle_degrees,
            esc(&b.two_sided.to_string())
        );
        for m in &b.modules {
            let _ = writeln!(
                o,
                "<tr><td>{}</td><td class=l>{}</td><td>{}</td><td>{}</td><td>{}</td>\
                 <td>{:.2e}</td></tr>",
                m.module,
                esc(&m.what),
                m.points,
                m.iterations,
                seconds(m.seconds),
                m.error
            );
        }
        o.push_str("</table>\n");
        if let Some(w) = &tour.woody {
            let _ = writeln!(
                o,
                "<h2>A body from a mesh: woody.obj</h2>\n<p>The flat gingerbread man, extruded \
                 into a slab 1.6 thick and stood up, {} control points split automatically into \
                 {} features (principal-axis bisection, then capacity-constrained k-means), \
                 balanced tree <code>{}</code>: {} iterations in {} (at most {} per module: the \
                 slab's sharp edges keep E<sub>s</sub> above 10<sup>−5</sup>; training {}). \
                 Median distance to the slab {:.3} % of D, RMS {:.2} %, median normal error \
                 {:.2}°. Both ways: {}.</p>",
                w.control_points,
                w.features,
                esc(&w.tree),
                w.iterations,
                seconds(w.seconds),
                super::WOODY_ITERATIONS,
                w.outcome,
                w.fidelity.median_distance_percent,
                w.fidelity.rms_distance_percent,
                w.fidelity.median_angle_degrees,
                esc(&w.two_sided.to_string())
            );
        }
    }
    o.push_str(
        "<h2>Fixed point against floating point</h2>\n<p>Each model measured on 2000 \
         held-out points of its true surface: distance |Φ|/|∇Φ| in % of the diameter, angle \
         between −∇Φ and the true normal; f64 is the trainer's reference, f32 and Q16.16 the \
         core evaluating the stored blob.</p>\n<table><tr><th class=l>model</th><th>points</th>\
         <th>train</th><th class=l>scalar</th><th>median %D</th><th>max %D</th>\
         <th>median angle</th><th>max |ΔΦ| vs f64</th></tr>\n",
    );
    for m in &report.models {
        for (precision, f) in &m.fidelity {
            let deviation = m
                .max_field_deviation
                .iter()
                .find(|(p, _)| p == precision)
                .map_or_else(|| "reference".to_string(), |(_, d)| format!("{d:.2e}"));
            let _ = writeln!(
                o,
                "<tr><td class=l>{}</td><td>{}</td><td>{}</td><td class=l>{}</td><td>{:.4}</td>\
                 <td>{:.4}</td><td>{:.3}°</td><td>{}</td></tr>",
                esc(&m.name),
                m.control_points,
                seconds(m.seconds),
                precision.name(),
                f.median_distance_percent,
                f.max_distance_percent,
                f.median_angle_degrees,
                deviation
            );
        }
    }
    o.push_str(
        "</table>\n<table><tr><th class=l>model</th><th class=l>scalar</th>\
                <th>max |Δ| vs f64</th><th>RMS |Δ|</th><th>median angle</th></tr>\n",
    );
    for d in &report.parametric {
        for (precision, dev) in &d.deviation {
            let _ = writeln!(
                o,
                "<tr><td class=l>{}</td><td class=l>{}</td><td>{:.2e}</td><td>{:.2e}</td>\
                 <td>{:.2e}°</td></tr>",
                esc(&d.name),
                precision.name(),
                dev.field_max.unwrap_or(f64::NAN),
                dev.field_rms.unwrap_or(f64::NAN),
                dev.normal_median_degrees.unwrap_or(f64::NAN)
            );
        }
    }
    o.push_str("</table>\n</body></html>\n");
    o
}

/// Writes `index.html` into the report's folder and returns its path.
///
/// # Errors
/// I/O errors.
pub fn write_index(report: &DemoReport, dir: &Path) -> Result<std::path::PathBuf> {
    let path = dir.join(INDEX);
    write_atomic(&path, html(report).as_bytes())?;
    Ok(path)
}
