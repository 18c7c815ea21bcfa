//! The Cortex-M example (`examples/cortex-m/`): it builds with the Debian toolchain, runs in
//! QEMU, exits successfully, and logs the Φ and the normal the host computes from the same
//! blob, in `f32` and in Q16.16.
//!
//! The toolchain comes from `firmware-sim/scripts/setup.sh` (the test command `scripts/test.sh`
//! runs it first); without it this test fails with a message naming that script.

use std::time::Duration;

use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::scalar::{Q16, Scalar};
use neurosurf_firmware_sim::{Toolchain, build_elf, repository_root, run_program};

/// The blob the example includes.
const BLOB: &str = "core/examples/torus.nsb";

/// The target computes the host's `f32` bits (the core's float math is one IEEE seam), and
/// defmt prints the shortest decimal that reads back as the same `f32`: any difference
/// beyond rounding noise is a wrong result.
const F32_TOLERANCE: f32 = 1e-6;
/// Q16.16 is bit-exact between host and target too; one unit in the last place.
const Q16_TOLERANCE: f32 = 1.0 / 65536.0;

#[test]
fn the_cortex_m_example_logs_the_normal_the_host_computes() {
    let root = repository_root();
    let toolchain = Toolchain::find(&root).unwrap_or_else(|e| panic!("{e}"));
    let elf = build_elf(
        &toolchain,
        &root,
        &root.join("examples/cortex-m"),
        &root.join("target/examples/cortex-m"),
        "neurosurf-example-cortex-m",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // An error here is a failed or hung run, with the example's log.
    let log = run_program(&toolchain, &elf, Duration::from_secs(60))
        .unwrap_or_else(|e| panic!("the example failed: {e}"));
    println!("{}", log.join("\n"));

    let blob = std::fs::read(root.join(BLOB)).unwrap();
    let float = ImplicitModel::<f32>::from_blob(&blob).unwrap();
    let fixed = ImplicitModel::<Q16>::from_blob(&blob).unwrap();

    let target = Logged::find(&log, "f32");
    let host = float.field_gradient(target.point);
    let normal = host.normal().expect("the host finds a normal");
    target.assert_close(host.value, normal, F32_TOLERANCE, &log);

    let target = Logged::find(&log, "Q16.16");
    let host = fixed.field_gradient(target.point.map(Q16::from_f32_saturating));
    let normal = host.normal().expect("the host finds a normal");
    target.assert_close(
        host.value.to_f32(),
        normal.map(Q16::to_f32),
        Q16_TOLERANCE,
        &log,
    );
}

/// One evaluation as the example logs it: `INFO  f32: Φ([x, y, z]) = φ, normal [a, b, c]`.
#[derive(Debug)]
struct Logged {
    point: [f32; 3],
    value: f32,
    normal: [f32; 3],
}

impl Logged {
    /// The evaluation logged for `scalar`; panics, showing the log, without one.
    fn find(log: &[String], scalar: &str) -> Self {
        let prefix = format!("INFO  {scalar}: Φ(");
        log.iter()
            .find_map(|line| Self::parse(line.strip_prefix(&prefix)?))
            .unwrap_or_else(|| {
                panic!(
                    "no {scalar} normal in the example's log:\n{}",
                    log.join("\n")
                )
            })
    }

    /// `[x, y, z]) = φ, normal [a, b, c]`.
    fn parse(text: &str) -> Option<Self> {
        let (point, rest) = text.split_once(") = ")?;
        let (value, normal) = rest.split_once(", normal ")?;
        Some(Logged {
            point: vector(point)?,
            value: value.parse().ok()?,
            normal: vector(normal)?,
        })
    }

    /// Panics, showing the log, unless Φ and every normal component are within `tolerance`
    /// of the host's.
    fn assert_close(&self, value: f32, normal: [f32; 3], tolerance: f32, log: &[String]) {
        let close = |a: f32, b: f32| (a - b).abs() <= tolerance;
        assert!(
            close(self.value, value) && self.normal.iter().zip(normal).all(|(&a, b)| close(a, b)),
            "the target logged Φ = {}, normal {:?}; the host computes Φ = {value}, normal \
             {normal:?} (tolerance {tolerance}); log:\n{}",
            self.value,
            self.normal,
            log.join("\n")
        );
    }
}

/// `[a, b, c]` as three `f32`.
fn vector(text: &str) -> Option<[f32; 3]> {
    let mut parts = text
        .trim()
        .strip_prefix('[')?
        .strip_suffix(']')?
        .split(", ");
    let mut next = || parts.next()?.parse().ok();
    let vector = [next()?, next()?, next()?];
    parts.next().is_none().then_some(vector)
}
