use neurosurf_trainer::demo::*;
use neurosurf_trainer::implicit::ImplicitOptions;
use neurosurf_trainer::sample::Pose;

fn main() {
    let mut options = ImplicitOptions::default();
    if std::env::var("PERAXIS").is_ok() {
        options.box_scaling = neurosurf_trainer::implicit::BoxScaling::PerAxis;
    }
    let inflate: f64 = std::env::var("INFLATE")
        .map(|v| v.parse().unwrap())
        .unwrap_or(1.3);
    for seed in 1..=4u64 {
        let points = body_points(&Pose::REST, seed).expect("points");
        let body = train_body(&points, &options, None, &|_| {}).expect("train");
        println!(
            "seed {seed} body {:.3} s conv {}",
            body.summary.seconds,
            body.summary.converged()
        );
        let bounds = point_bounds(&points.positions);
        let cam = framing(&bounds, 20.0, 10.0, 128, 256).unwrap();
        let p = picture(
            &body.network,
            feature_regions(&points, inflate),
            &cam,
            1,
            std::path::Path::new("/tmp/bodyexp"),
            &format!("s{seed}.png"),
            "",
        )
        .unwrap();
        println!("{:?}", p.stats);
    }
}
