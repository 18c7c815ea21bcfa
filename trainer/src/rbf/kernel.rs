//! The kernels φ(r) = √(r² + c²) (the multiquadric; c = 0 gives the biharmonic φ(r) = r),
//! their gradients, and the packed sums Σ wᵢ φ(|x − cᵢ|) a model is evaluated with.

/// φ(|d|) = √(|d|² + c²) for a displacement `d` = x − centre.
///
/// Exact to a few ulps (one rounded sum of squares and a correctly rounded square root);
/// `c2 > 0` keeps it smooth and ≥ c everywhere, `c2 = 0` is the biharmonic |d|.
#[inline]
pub fn multiquadric(d: [f64; 3], c2: f64) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + c2).sqrt()
}

/// φ(|d|) and its gradient with respect to x, d/φ (each component bounded by 1 in
/// magnitude), to a few ulps. Where φ = 0 (the biharmonic's centre, where it has no
/// derivative) the gradient is taken as 0.
#[inline]
pub fn multiquadric_gradient(d: [f64; 3], c2: f64) -> (f64, [f64; 3]) {
    let phi = multiquadric(d, c2);
    if phi > 0.0 {
        let inv = 1.0 / phi;
        (phi, [d[0] * inv, d[1] * inv, d[2] * inv])
    } else {
        (phi, [0.0; 3])
    }
}

/// Centres per step of the packed sums: two AVX2 registers, or four SSE2 ones.
const LANES: usize = 8;

/// Centres and weights in structure-of-arrays form, padded to a multiple of [`LANES`] with
/// zero weights, for the vectorized sums of [`Packed::sum`].
#[derive(Clone, Debug)]
pub(super) struct Packed {
    x: Vec<[f64; LANES]>,
    y: Vec<[f64; LANES]>,
    z: Vec<[f64; LANES]>,
    w: Vec<[f64; LANES]>,
    /// Whether this CPU runs the AVX2 + FMA instantiation.
    fma: bool,
}

impl Packed {
    pub(super) fn new(centers: &[[f64; 3]], weights: &[f64]) -> Packed {
        let chunks = centers.len().div_ceil(LANES);
        let mut packed = Packed {
            x: vec![[0.0; LANES]; chunks],
            y: vec![[0.0; LANES]; chunks],
            z: vec![[0.0; LANES]; chunks],
            w: vec![[0.0; LANES]; chunks],
            fma: cpu_has_fma(),
        };
        for (i, (c, &w)) in centers.iter().zip(weights).enumerate() {
            let (chunk, lane) = (i / LANES, i % LANES);
            packed.x[chunk][lane] = c[0];
            packed.y[chunk][lane] = c[1];
            packed.z[chunk][lane] = c[2];
            packed.w[chunk][lane] = w;
        }
        packed
    }

    /// Σ wᵢ φ(|p − cᵢ|) and, when `GRADIENT`, Σ wᵢ (p − cᵢ)/φᵢ.
    ///
    /// The value is bit-identical with and without the gradient. Every term is exact to a few
    /// ulps; the sums run in [`LANES`] interleaved partial sums (added pairwise at the end),
    /// with fused multiply–adds on CPUs that have them, so the last bits depend on the CPU.
    #[inline]
    pub(super) fn sum<const GRADIENT: bool>(&self, p: [f64; 3], c2: f64) -> (f64, [f64; 3]) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
            return unsafe { sum_fma::<GRADIENT>(self, p, c2) };
        }
        sum_lanes::<GRADIENT, false>(self, p, c2)
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn sum_fma<const GRADIENT: bool>(packed: &Packed, p: [f64; 3], c2: f64) -> (f64, [f64; 3]) {
    sum_lanes::<GRADIENT, true>(packed, p, c2)
}

/// a·b + c, fused when compiled for FMA.
#[inline(always)]
fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

#[inline(always)]
fn sum_lanes<const GRADIENT: bool, const FMA: bool>(
    packed: &Packed,
    p: [f64; 3],
    c2: f64,
) -> (f64, [f64; 3]) {
    let mut value = [0.0; LANES];
    let mut gradient = [[0.0; LANES]; 3];
    for (((x, y), z), w) in packed.x.iter().zip(&packed.y).zip(&packed.z).zip(&packed.w) {
        for l in 0..LANES {
            let dx = p[0] - x[l];
            let dy = p[1] - y[l];
            let dz = p[2] - z[l];
            let r2 = madd::<FMA>(dz, dz, madd::<FMA>(dy, dy, madd::<FMA>(dx, dx, c2)));
            let phi = r2.sqrt();
            value[l] = madd::<FMA>(w[l], phi, value[l]);
            if GRADIENT {
                // w/φ, and 0 where φ = 0 (a biharmonic centre, or padding).
                let s = if phi > 0.0 { w[l] / phi } else { 0.0 };
                gradient[0][l] = madd::<FMA>(s, dx, gradient[0][l]);
                gradient[1][l] = madd::<FMA>(s, dy, gradient[1][l]);
                gradient[2][l] = madd::<FMA>(s, dz, gradient[2][l]);
            }
        }
    }
    (pairwise(value), gradient.map(pairwise))
}

/// The sum of the lanes, pairwise.
#[inline(always)]
fn pairwise(mut v: [f64; LANES]) -> f64 {
    let mut width = LANES;
    while width > 1 {
        width /= 2;
        for l in 0..width {
            v[l] += v[l + width];
        }
    }
    v[0]
}

/// Whether the CPU runs the AVX2 + FMA instantiation.
fn cpu_has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
