use super::*;

fn lle_quality(surface: SampleSurface, count: usize, noise: f64) -> (f64, f64, f64, Embedding) {
    let sample = sample_surface(surface, count, noise, 7).unwrap();
    let embedding = embed_points(&sample.points, &LleOptions::default()).unwrap();
    let (aligned, r2) = align_affine(&sample.parameters, &embedding.parameters).unwrap();
    let keep = neighborhood_preservation(&sample.parameters, &aligned, 10).unwrap();
    let corr = distance_correlation(&sample.parameters, &aligned).unwrap();
    (r2, keep, corr, embedding)
}

/// LLE's (u, v) must be an affine image of the true parameters up to this unexplained
/// variance, keep this share of 10-neighbourhoods and correlate distances this well.
const MIN_R2: f64 = 0.97;
const MIN_NEIGHBORHOODS: f64 = 0.85;
const MIN_DISTANCE_CORRELATION: f64 = 0.97;

#[test]
fn lle_recovers_an_open_cylinder() {
    // Fig. 5's 1400 and 700 points (measured: R² 0.992, 93 % neighbourhoods, r 0.989 at 1400).
    for count in [1400, 700] {
        let (r2, keep, corr, e) = lle_quality(SampleSurface::OpenCylinder, count, 0.0);
        eprintln!(
            "cylinder {count}: R² {r2:.4} keep {keep:.3} corr {corr:.4} {:?} it {}",
            e.folds, e.iterations
        );
        assert!(r2 > MIN_R2 && keep > MIN_NEIGHBORHOODS && corr > MIN_DISTANCE_CORRELATION);
        assert!(e.folds.is_flat());
    }
}

#[test]
fn lle_recovers_a_swiss_roll_patch() {
    // Measured: R² 0.982, 90 % neighbourhoods, r 0.981.
    let (r2, keep, corr, e) = lle_quality(SampleSurface::SwissRoll, 2000, 0.0);
    eprintln!(
        "swiss roll: R² {r2:.4} keep {keep:.3} corr {corr:.4} {:?} it {}",
        e.folds, e.iterations
    );
    assert!(r2 > MIN_R2 && keep > MIN_NEIGHBORHOODS && corr > MIN_DISTANCE_CORRELATION);
}

#[test]
fn lle_with_noise_still_recovers_the_cylinder() {
    let (r2, keep, _, _) = lle_quality(SampleSurface::OpenCylinder, 1400, 0.005);
    eprintln!("noisy cylinder: R² {r2:.4} keep {keep:.3}");
    assert!(r2 > 0.95 && keep > 0.6);
}

#[test]
fn a_closed_sphere_is_rejected_as_folded() {
    let sample = sample_surface(SampleSurface::Sphere, 1000, 0.0, 7).unwrap();
    let options = LleOptions {
        check_folds: false,
        ..LleOptions::default()
    };
    let e = embed_points(&sample.points, &options).unwrap();
    eprintln!("sphere {:?}", e.folds);
    assert!(!e.folds.is_flat());
    let err = embed_points(&sample.points, &LleOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("cannot flatten"), "{err}");
}

#[test]
fn bad_point_sets_are_named_errors() {
    let options = LleOptions::default();
    let few: Vec<[f64; 3]> = (0..8).map(|i| [i as f64, (i * i) as f64, 0.0]).collect();
    let e = embed_points(&few, &options).unwrap_err().to_string();
    assert!(e.contains("too few"), "{e}");
    let mut dup = sample_surface(SampleSurface::Plane, 100, 0.0, 1)
        .unwrap()
        .points;
    dup[50] = dup[7];
    let e = embed_points(&dup, &options).unwrap_err().to_string();
    assert!(
        e.contains("coincide") && e.contains("7") && e.contains("50"),
        "{e}"
    );
    let line: Vec<[f64; 3]> = (0..100)
        .map(|i| [i as f64, 2.0 * i as f64, -(i as f64)])
        .collect();
    let e = embed_points(&line, &options).unwrap_err().to_string();
    assert!(e.contains("line"), "{e}");
    let mut nan = sample_surface(SampleSurface::Plane, 100, 0.0, 1)
        .unwrap()
        .points;
    nan[3][1] = f64::NAN;
    assert!(
        embed_points(&nan, &options)
            .unwrap_err()
            .to_string()
            .contains("non-finite")
    );
    let e = embed_points(
        &nan[..2],
        &LleOptions {
            neighbors: 2,
            ..options
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("too few") || e.to_string().contains("k = 2"),
        "{e}"
    );
}

#[test]
fn network_partials_match_central_differences() {
    let mut net = SurfaceNetwork::zeros(
        &[4, 3],
        Activation::TanSig,
        [0.1, -0.2],
        [1.5, 0.7],
        [1.0, 2.0, 3.0],
        2.0,
    )
    .unwrap();
    for act in Activation::ALL {
        net.activation = act;
        randomize(&mut net, 5);
        let (u, v, h) = (0.3, -0.4, 1e-6);
        let e = net.evaluate(u, v);
        let fu = net.position(u + h, v);
        let bu = net.position(u - h, v);
        let fv = net.position(u, v + h);
        let bv = net.position(u, v - h);
        for a in 0..3 {
            assert!((e.position[a] - net.position(u, v)[a]).abs() < 1e-12);
            assert!(
                (e.du[a] - (fu[a] - bu[a]) / (2.0 * h)).abs() < 1e-6,
                "{act:?} du"
            );
            assert!(
                (e.dv[a] - (fv[a] - bv[a]) / (2.0 * h)).abs() < 1e-6,
                "{act:?} dv"
            );
        }
    }
}

fn topology_of(surface: SampleSurface) -> TopologySearch {
    let sample = sample_surface(surface, 400, 0.0, 11).unwrap();
    let fit = fit_network(
        &sample.points,
        &sample.parameters,
        &TopologyOptions::default(),
    )
    .unwrap();
    for c in &fit.search.candidates {
        eprintln!(
            "{surface:?} {}x{} p{} tr {:.2e} va {:.2e} te {:.2e} it {}",
            c.layers,
            c.neurons,
            c.parameters,
            c.training_mse,
            c.validation_mse,
            c.test_mse,
            c.iterations
        );
    }
    eprintln!(
        "{surface:?} chosen {:?} rel rms {}",
        fit.search.best(),
        fit.relative_rms_error
    );
    fit.search
}

#[test]
fn topology_search_sizes_the_network_to_the_surface() {
    // Measured: the plane gets 1 × 2 (15 weights), the wavy surface 2 × 7 (101).
    let plane = topology_of(SampleSurface::Plane);
    let wavy = topology_of(SampleSurface::Wavy);
    assert!(
        plane.best().layers == 1 && plane.best().neurons <= 3,
        "{:?}",
        plane.best()
    );
    assert!(
        wavy.best().parameters >= 2 * plane.best().parameters,
        "{:?}",
        wavy.best()
    );
    assert!(plane.best().test_mse < 1e-5 && wavy.best().test_mse < 1e-4);
}

#[test]
fn reconstructs_a_wavy_patch_with_both_tessellations() {
    let sample = sample_surface(SampleSurface::Wavy, 500, 0.0, 3).unwrap();
    let mut options = ReconstructOptions::default();
    let coons = reconstruct(&sample.points, &options).unwrap();
    options.tessellation = Tessellation::Delaunay { vertices: 600 };
    let tri = reconstruct(&sample.points, &options).unwrap();
    let (cm, tm) = (&coons.surface.mesh, &tri.surface.mesh);
    eprintln!(
        "coons {} v, rel rms {}, delaunay {} v {} t",
        cm.vertex_count(),
        coons.fit.relative_rms_error,
        tm.vertex_count(),
        tm.triangle_count()
    );
    assert_eq!((cm.vertex_count(), cm.triangle_count()), (900, 2 * 29 * 29));
    // Both meshes are one open disk: a single boundary loop, every inner edge used twice.
    for mesh in [cm, tm] {
        let report = edge_report(mesh);
        assert_eq!((report.non_manifold, report.misoriented), (0, 0));
        assert_eq!(boundary_loops(&mesh.triangles).unwrap().len(), 1);
        // Every vertex lies on the true surface within 2 % of the 2.06 diagonal.
        for p in &mesh.positions {
            let z = SampleSurface::Wavy.height(p[0], p[1]).unwrap();
            assert!((p[2] - z).abs() < 0.04, "{p:?} vs {z}");
        }
    }
    assert!(tm.vertex_count() > 450 && tm.vertex_count() < 800);
}
