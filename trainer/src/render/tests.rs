//! The renderer and the mesher on an analytic sphere and on trained models (a sphere, the
//! torus of the foundation's tests).

use std::path::Path;

use super::*;
use crate::implicit::{self, FitRequest, ImplicitOptions, Trained};
use crate::io::{Mesh, read_mesh, write_mesh};
use crate::sample::{Shape, sample_shape};
use neurosurf_core::scalar::ScalarKind;

/// Hits must be within this ray length of the exact sphere: 10⁻⁵ of the scene size (3.75
/// here), the guaranteed search's shortest segment, which bounds its error at grazing rays
/// (Newton's tolerance is 10⁻⁶ of the size).
const HIT_TOLERANCE: f64 = 1e-5 * 3.75;

fn train(shape: &Shape, count: usize, seed: u64) -> Trained {
    let points = sample_shape(shape, count, seed).unwrap();
    implicit::fit(
        points,
        &FitRequest::default(),
        &ImplicitOptions::default(),
        &|_| {},
    )
    .unwrap()
}

fn torus() -> Trained {
    train(
        &Shape::Torus {
            major: 1.0,
            minor: 0.4,
        },
        96,
        11,
    )
}

fn camera_for<F: Field>(field: &F, size: u32, view: View) -> Camera {
    Camera::orbit(&bounds_of(field.regions()).unwrap(), &view, size, size).unwrap()
}

/// Every edge of `mesh` is shared by exactly two triangles, once in each direction.
fn assert_watertight(mesh: &Mesh) {
    let report = mesh.edge_report();
    assert_eq!(
        report.not_shared_by_two, 0,
        "{} of {} edges are not shared by two triangles",
        report.not_shared_by_two, report.edges
    );
    assert_eq!(
        report.same_way, 0,
        "{} edges are traversed twice the same way",
        report.same_way
    );
    assert!(report.is_closed());
}

#[test]
fn analytic_sphere_is_hit_everywhere_and_accurately() {
    let sphere = SphereField::new([0.2, -0.1, 0.3], 1.5, 5.0).unwrap();
    let camera = camera_for(&sphere, 48, View::default());
    for method in [Method::Punctual, Method::Guaranteed] {
        let tracer = Tracer::new(&sphere, method, &RenderOptions::default()).unwrap();
        let hits = hit_map(&tracer, &camera);
        let mut worst = 0.0_f64;
        let mut count = 0;
        for (i, hit) in hits.iter().enumerate() {
            let (o, d) = camera.ray((i % 48) as f64 + 0.5, (i / 48) as f64 + 0.5);
            match (sphere.exact_hit(o, d), hit) {
                (Some(exact), Some(t)) => {
                    worst = worst.max((exact - t).abs());
                    count += 1;
                }
                (None, None) => {}
                (exact, found) => panic!("{method:?} pixel {i}: exact {exact:?}, found {found:?}"),
            }
        }
        eprintln!("{method:?}: {count} hits, worst |t − t_exact| = {worst:.2e}");
        assert!(count > 200, "{count}");
        assert!(worst <= HIT_TOLERANCE, "{method:?}: {worst}");
    }
}

#[test]
fn trained_sphere_in_f32_is_hit_where_the_true_sphere_is() {
    let trained = train(&Shape::Sphere { radius: 1.0 }, 64, 3);
    let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).unwrap();
    let regions = Region::of_network(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
    let field = CoreField::new(&blob, regions).unwrap();
    let exact = SphereField::new([0.0; 3], 1.0, 5.0).unwrap();
    let camera = camera_for(&field, 40, View::default());
    let tracer = Tracer::new(&field, Method::Punctual, &RenderOptions::default()).unwrap();
    let hits = hit_map(&tracer, &camera);
    let (mut worst, mut both, mut disagree) = (0.0_f64, 0, 0);
    for (i, hit) in hits.iter().enumerate() {
        let (o, d) = camera.ray((i % 40) as f64 + 0.5, (i / 40) as f64 + 0.5);
        match (exact.exact_hit(o, d), hit) {
            (Some(e), Some(t)) => {
                // Only where the ray meets the sphere well inside its silhouette.
                let grazing =
                    crate::geometry::vector::distance_to_line([0.0; 3], o, add3(o, d)) > 0.95;
                if !grazing {
                    // How far the hit point is from the true sphere (radially).
                    let hit = add3(o, [d[0] * t, d[1] * t, d[2] * t]);
                    let off = (crate::geometry::vector::norm(hit) - 1.0).abs();
                    if off > 0.05 && worst <= 0.05 {
                        let samples: Vec<String> = (0..40)
                            .map(|k| {
                                let s = e - 1.0 + 0.05 * f64::from(k);
                                format!(
                                    "{:.2}",
                                    field.value(add3(o, [d[0] * s, d[1] * s, d[2] * s]))
                                )
                            })
                            .collect();
                        eprintln!("pixel {i}: exact {e} found {t}: {}", samples.join(" "));
                    }
                    worst = worst.max(off);
                }
                both += 1;
            }
            (None, None) => {}
            _ => disagree += 1,
        }
    }
    eprintln!("trained sphere: {both} hits, {disagree} silhouette disagreements, worst {worst:.4}");
    // Away from the silhouette, every hit point is within 2 % of the radius of the true
    // sphere (64 control points).
    assert!(worst < 0.02, "{worst}");
    assert!(disagree * 50 < both, "{disagree} of {both}");
}

fn add3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[test]
fn guaranteed_misses_nothing_dense_sampling_finds_on_the_torus() {
    let trained = torus();
    let field = NetworkField::new(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE).unwrap();
    let mut total_punctual_missed = 0;
    for view in [
        View::default(),
        View {
            azimuth: 0.0,
            elevation: 5.0,
            ..View::default()
        },
        View {
            azimuth: 60.0,
            elevation: 70.0,
            ..View::default()
        },
    ] {
        let camera = camera_for(&field, 48, view);
        let c = compare_methods(&field, &camera, &RenderOptions::default(), 0.002).unwrap();
        eprintln!("{view:?}: {c:?}");
        assert!(c.dense_hits > 100, "{c:?}");
        assert_eq!(c.guaranteed_missed, 0, "{c:?}");
        // The guaranteed depths match dense sampling to its step.
        assert!(c.guaranteed_max_depth_error <= c.dense_step, "{c:?}");
        total_punctual_missed += c.punctual_missed;
    }
    eprintln!("punctual missed {total_punctual_missed} pixels over the three views");
}

#[test]
fn png_of_the_torus_decodes() {
    let trained = torus();
    let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).unwrap();
    let regions = Region::of_network(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
    let field = CoreField::new(&blob, regions).unwrap();
    let camera = camera_for(&field, 64, View::default());
    let full_options = RenderOptions {
        adaptive: false,
        ..RenderOptions::default()
    };
    let full = render(&field, &camera, &full_options, &|_, _| {}).unwrap();
    assert_eq!(full.stats.rays, 64 * 64 * 4);
    assert_eq!(full.stats.supersampled, 64 * 64);
    assert!(full.stats.hits > 1000, "{:?}", full.stats);
    // Adaptive: a ray per centre, the 4 sub-pixel rays only at edges; the picture differs
    // from the full one only where the centre stands for a smooth pixel.
    let rendered = render(&field, &camera, &RenderOptions::default(), &|_, _| {}).unwrap();
    let stats = &rendered.stats;
    assert_eq!(stats.rays, 64 * 64 + 4 * stats.supersampled, "{stats:?}");
    assert!(
        stats.supersampled > 100 && stats.supersampled < 64 * 64 / 2,
        "{stats:?}"
    );
    let differences: Vec<i32> = full
        .image
        .as_raw()
        .iter()
        .zip(rendered.image.as_raw())
        .map(|(&a, &b)| (i32::from(a) - i32::from(b)).abs())
        .collect();
    let mean = differences.iter().sum::<i32>() as f64 / differences.len() as f64;
    let worst = differences.iter().max().copied().unwrap_or(0);
    assert!(mean < 0.5 && worst <= 12, "mean {mean}, worst {worst}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("torus.png");
    write_png(&path, &rendered.image).unwrap();
    let back = image::open(&path).unwrap().to_rgb8();
    assert_eq!(back, rendered.image);
    // The guaranteed mode refuses a field without interval bounds.
    let options = RenderOptions {
        method: Method::Guaranteed,
        ..RenderOptions::default()
    };
    let e = render(&field, &camera, &options, &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("interval"), "{e}");
    let options = RenderOptions {
        samples: 3,
        ..RenderOptions::default()
    };
    let e = render(&field, &camera, &options, &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("square"), "{e}");
}

#[test]
fn sphere_mesh_is_watertight_and_on_the_sphere() {
    let sphere = SphereField::new([0.1, 0.0, -0.2], 1.0, 5.0).unwrap();
    let out = extract_mesh(&sphere, 40, &|_, _| {}).unwrap();
    let mesh = out.mesh.clone().validated().unwrap();
    assert_watertight(&mesh);
    // Euler characteristic 2: a sphere.
    let edges = mesh.triangles.len() * 3 / 2;
    assert_eq!(mesh.positions.len() + mesh.triangles.len() - edges, 2);
    let cell = out.stats.cell_size;
    for (p, n) in mesh.positions.iter().zip(&out.normals) {
        let r = [p[0] - 0.1, p[1], p[2] + 0.2];
        let length = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        // Linear interpolation of the distance along an edge of length ≤ √3·h: off by at
        // most (√3·h)²/8 · max|f″| with |f″| ≤ 1/0.9 near the unit sphere.
        assert!(
            (length - 1.0).abs() < 3.0 * cell * cell / (8.0 * 0.9),
            "{p:?} {length}"
        );
        let dot: f64 = (0..3).map(|k| r[k] / length * n[k]).sum();
        assert!(dot > 0.9999, "{n:?}");
    }
    assert!(out.stats.blocks_searched <= out.stats.blocks);
}

#[test]
fn torus_mesh_is_watertight_and_reread_by_tobj_ply_and_stl_io() {
    let trained = torus();
    let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).unwrap();
    let regions = Region::of_network(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
    let field = CoreField::new(&blob, regions).unwrap();
    let out = extract_mesh(&field, 48, &|_, _| {}).unwrap();
    eprintln!("{:?}", out.stats);
    assert_watertight(&out.mesh);
    // A torus: Euler characteristic 0.
    let edges = out.mesh.triangles.len() * 3 / 2;
    assert_eq!(out.mesh.positions.len() + out.mesh.triangles.len(), edges);
    let dir = tempfile::tempdir().unwrap();
    for ext in ["obj", "ply"] {
        let path = dir.path().join(format!("torus.{ext}"));
        write_mesh(&path, &out.mesh, Some(&out.normals)).unwrap();
        let back = read_mesh(&path).unwrap();
        assert_eq!(back.triangles, out.mesh.triangles, "{ext}");
        assert_watertight(&back);
    }
    let path = dir.path().join("torus.stl");
    write_mesh(&path, &out.mesh, Some(&out.normals)).unwrap();
    let mut file = std::fs::File::open(&path).unwrap();
    let stl = stl_io::read_stl(&mut file).unwrap();
    assert_eq!(stl.faces.len(), out.mesh.triangles.len());
    // stl_io welds equal f32 positions: the vertex count survives the round trip.
    assert_eq!(stl.vertices.len(), out.mesh.positions.len());
    assert!(stl.validate().is_ok(), "{:?}", stl.validate());
    assert!(Path::new(&path).exists());
}

#[test]
fn bad_mesh_requests_are_named() {
    let sphere = SphereField::new([0.0; 3], 1.0, 5.0).unwrap();
    let e = extract_mesh(&sphere, 0, &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("resolution 0"), "{e}");
    let e = extract_mesh(&sphere, MAX_RESOLUTION + 1, &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("outside"), "{e}");
    let e = write_mesh(Path::new("x.stp"), &Mesh::default(), None).unwrap_err();
    assert!(e.to_string().contains(".stl"), "{e}");
}

/// A unit sphere (Φ > 0 inside) whose field turns positive again beyond r = 1.75, a phantom
/// shell like a network's extrapolation far from its points; its one region is a box turned
/// 45° about z, half-side 1.2, so the shell crosses the octree's voxels beside the box.
struct PhantomShell {
    regions: Vec<Region>,
}

impl PhantomShell {
    fn new() -> Self {
        let (c, s) = (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        );
        let k = 1.0 / 1.2;
        let normalization = crate::implicit::Normalization {
            center: [0.0; 3],
            matrix: [[c * k, s * k, 0.0], [-s * k, c * k, 0.0], [0.0, 0.0, k]],
        };
        PhantomShell {
            regions: vec![Region::new(normalization, 2.0, 1.0).unwrap()],
        }
    }
}

impl Field for PhantomShell {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.value_gradient(p).0
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        // (1 − r²)(1.75 − r): positive inside r = 1, negative up to r = 1.75, positive beyond.
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let (a, b) = (1.0 - r * r, 1.75 - r);
        let dr = -2.0 * r * b - a;
        let g = if r > 0.0 {
            p.map(|v| dr * v / r)
        } else {
            [0.0; 3]
        };
        (a * b, g)
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }
}

/// Nothing outside the regions is searched: a ray along the box's turned diagonal meets the
/// phantom shell at r = 1.75 in voxels beside the box (outside it: |x| + |y| > 1.2·√2), and
/// must go on to the sphere at r = 1, as `mesh` would.
#[test]
fn surface_beside_the_regions_is_not_rendered() {
    let field = PhantomShell::new();
    let tracer = Tracer::new(&field, Method::Punctual, &RenderOptions::default()).unwrap();
    let origin: [f64; 3] = [2.5, 2.5, 0.1];
    let length = (origin[0] * origin[0] + origin[1] * origin[1] + origin[2] * origin[2]).sqrt();
    let direction = origin.map(|v| -v / length);
    let t = tracer.hit(origin, direction).expect("the sphere is hit");
    assert!((length - t - 1.0).abs() < 1e-3, "hit at r = {}", length - t);
}
