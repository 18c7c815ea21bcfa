//! The core as a library on a desktop: load a blob once, then evaluate Φ, ∇Φ and the outward
//! normal in `f32` and in Q16.16, side by side. Run with
//! `cargo run -p neurosurf-core --example host [BLOB]` (default: `torus.nsb` beside this
//! file, a torus of radii 1 and 0.4 trained from 96 points by `neurosurf sample torus
//! --points 96 --seed 1` and `neurosurf implicit fit`).

use neurosurf_core::BlobError;
use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::scalar::{Q16, Scalar};

/// The torus, stored in f32 (the core converts it to Q16.16 on loading).
static TORUS: &[u8] = include_bytes!("torus.nsb");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let bytes = match std::env::args().nth(1) {
        Some(path) => std::fs::read(path)?,
        None => TORUS.to_vec(),
    };
    // Every check happens here; after it, evaluation cannot fail or panic.
    let float = ImplicitModel::<f32>::from_blob(&bytes).map_err(describe)?;
    let fixed = ImplicitModel::<Q16>::from_blob(&bytes).map_err(describe)?;
    println!(
        "{:<18} {:>10} {:>10}  normal (f32)",
        "point", "Φ f32", "Φ Q16.16"
    );
    // The centre (outside), inside the tube, and two points on the surface.
    for p in [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.4, 0.0, 0.0],
        [0.0, 1.0, 0.4],
    ] {
        let phi = float.field(p);
        let phi_fixed = fixed.field(p.map(Q16::from_f32_saturating)).to_f32();
        let normal = float
            .normal(p)
            .map_or("none (∇Φ = 0)".to_string(), |n| format!("{n:.4?}"));
        let point = format!("{p:?}");
        println!("{point:<18} {phi:>10.5} {phi_fixed:>10.5}  {normal}");
    }
    Ok(())
}

fn describe(e: BlobError) -> String {
    format!("the core refuses this blob: {e}")
}
