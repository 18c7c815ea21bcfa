//! The [`Model`] path gives exactly what each model's own API gives, and [`model::visit`]
//! picks the model type a blob names, for every kind, on blobs the trainer wrote
//! (`fuzz/corpus/`).

use std::path::Path;

use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::caoen::CaoEnModel;
use neurosurf_core::curve::{BSplineCurve, BSplineSurface};
use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::model::{self, MAX_INPUTS, MAX_OUTPUTS, Model, ModelVisitor};
use neurosurf_core::parametric::SurfaceNetworkModel;
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

/// The blobs in `fuzz/corpus/`, by file name.
fn corpus() -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|path| (path.display().to_string(), std::fs::read(&path).unwrap()))
        .collect()
}

/// Inputs in each model's domain and beyond it.
const INPUTS: [[f32; 4]; 5] = [
    [0.0, 0.0, 0.0, 0.0],
    [0.3, 0.7, 0.1, 0.0],
    [1.4, 0.0, 0.2, 0.5],
    [-0.9, 0.5, 1.0, 0.0],
    [2.0, -3.0, 0.5, 0.0],
];

/// What `Model::evaluate` writes, value and full, at every input.
fn through_trait<S: Scalar, M: Model<S>>(m: &M) -> Vec<Vec<S>> {
    let mut out = Vec::new();
    for input in INPUTS {
        let input = input.map(S::from_f32_saturating);
        for full in [false, true] {
            let mut words = [S::ZERO; MAX_OUTPUTS];
            m.evaluate(&input, full, &mut words);
            out.push(words[..m.output_len(full)].to_vec());
        }
    }
    out
}

/// The same through each model's own API.
fn direct<S: Scalar>(kind: ModelKind, bytes: &[u8]) -> Vec<Vec<S>> {
    let zero = [S::ZERO; 3];
    let mut out = Vec::new();
    for input in INPUTS {
        let x = input.map(S::from_f32_saturating);
        let (value, full): (Vec<S>, Vec<S>) = match kind {
            ModelKind::Implicit => {
                let m = ImplicitModel::<S>::from_blob(bytes).unwrap();
                let p = [x[0], x[1], x[2]];
                let fg = m.field_gradient(p);
                (
                    vec![m.field(p)],
                    [fg.value].into_iter().chain(fg.gradient).collect(),
                )
            }
            ModelKind::Curve => {
                let m = BSplineCurve::<S>::from_blob(bytes).unwrap();
                let p = m.eval(x[0]);
                (
                    m.position(x[0]).to_vec(),
                    p.position.into_iter().chain(p.tangent).collect(),
                )
            }
            ModelKind::SplineSurface => {
                let m = BSplineSurface::<S>::from_blob(bytes).unwrap();
                let uv = [x[0], x[1]];
                let n = m.normal(uv).unwrap_or(zero);
                (
                    m.position(uv).to_vec(),
                    m.position(uv).into_iter().chain(n).collect(),
                )
            }
            ModelKind::SurfaceNetwork => {
                let m = SurfaceNetworkModel::<S>::from_blob(bytes).unwrap();
                let uv = [x[0], x[1]];
                let p = m.eval(uv);
                let n = p.normal.unwrap_or(zero);
                (
                    m.position(uv).to_vec(),
                    p.position.into_iter().chain(n).collect(),
                )
            }
            ModelKind::CaoEn => {
                let m = CaoEnModel::<S>::from_blob(bytes).unwrap();
                let mut source = [S::ZERO; 8];
                source[..4].copy_from_slice(&x);
                let y: [S; 8] = m.eval(&source);
                let p = m.target_dimension();
                let value = y[..p].to_vec();
                let point = m.eval_normal(&source);
                let n = point.normal.unwrap_or(zero);
                let full = if p == 3 {
                    point.position.into_iter().chain(n).collect()
                } else {
                    value.iter().copied().chain(zero).collect()
                };
                (value, full)
            }
            ModelKind::Rbf => unreachable!(),
        };
        out.push(value);
        out.push(full);
    }
    out
}

/// Loads through the registry and returns what the trait path writes.
struct Evaluate<'a>(&'a [u8]);

impl ModelVisitor for Evaluate<'_> {
    type Output = (ModelKind, Vec<Vec<f32>>);
    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
        let mut m = Box::<M>::default();
        m.load_blob(self.0).unwrap();
        let words = through_trait(&*m);
        let as_f32 = words
            .into_iter()
            .map(|w| w.into_iter().map(S::to_f32).collect())
            .collect();
        (M::KIND, as_f32)
    }
}

#[test]
fn the_trait_path_gives_what_each_models_own_api_gives() {
    let mut kinds = 0;
    for (name, bytes) in corpus() {
        let (header, _) = blob::parse(&bytes).unwrap();
        if header.model == ModelKind::Rbf {
            assert!(model::visit(header.model, ScalarKind::F32, Evaluate(&bytes)).is_none());
            continue;
        }
        kinds += 1;
        let (kind, f32_words) = model::visit(header.model, ScalarKind::F32, Evaluate(&bytes))
            .unwrap_or_else(|| panic!("{name}: not registered"));
        assert_eq!(kind, header.model, "{name}");
        let expected: Vec<Vec<f32>> = direct::<f32>(kind, &bytes);
        assert_eq!(f32_words, expected, "{name} in f32");
        let (_, q16_words) =
            model::visit(header.model, ScalarKind::Q16_16, Evaluate(&bytes)).unwrap();
        let expected: Vec<Vec<f32>> = direct::<Q16>(kind, &bytes)
            .into_iter()
            .map(|w| w.into_iter().map(Q16::to_f32).collect())
            .collect();
        assert_eq!(q16_words, expected, "{name} in Q16.16");
    }
    assert!(kinds >= 10, "{kinds} blobs of the five evaluated kinds");
    assert!(model::visit(ModelKind::Implicit, ScalarKind::F64, Evaluate(b"")).is_none());
}

/// `evaluate_batch` at `count` seeded points in [−2, 2]ⁿ, against `evaluate` point by point:
/// the words of every point that differ, as (point, full).
struct BatchAgainstSingle<'a> {
    bytes: &'a [u8],
    count: usize,
}

impl ModelVisitor for BatchAgainstSingle<'_> {
    type Output = Vec<(usize, bool)>;
    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
        let mut m = Box::<M>::default();
        m.load_blob(self.bytes).unwrap();
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            ((state >> 40) as f32 / (1 << 24) as f32) * 4.0 - 2.0
        };
        let inputs: Vec<[S; MAX_INPUTS]> = (0..self.count)
            .map(|_| [(); MAX_INPUTS].map(|()| S::from_f32_saturating(next())))
            .collect();
        let mut differing = Vec::new();
        for full in [false, true] {
            let mut batch = vec![[S::ZERO; MAX_OUTPUTS]; self.count];
            m.evaluate_batch(&inputs, full, &mut batch);
            for (i, (input, got)) in inputs.iter().zip(&batch).enumerate() {
                let mut single = [S::ZERO; MAX_OUTPUTS];
                m.evaluate(input, full, &mut single);
                let n = m.output_len(full);
                if got[..n] != single[..n] {
                    differing.push((i, full));
                }
            }
        }
        differing
    }
}

/// The batch path gives the single path's bits, on counts that fill no chunk, one chunk and a
/// chunk and a bit (the core converts 16 points at a time and evaluates 8 lanes at a time).
#[test]
fn the_batch_path_gives_what_the_single_path_gives() {
    for (name, bytes) in corpus() {
        let (header, _) = blob::parse(&bytes).unwrap();
        for scalar in [ScalarKind::F32, ScalarKind::Q16_16] {
            for count in [1, 7, 16, 37] {
                let run = BatchAgainstSingle {
                    bytes: &bytes,
                    count,
                };
                if let Some(differing) = model::visit(header.model, scalar, run) {
                    assert!(
                        differing.is_empty(),
                        "{name} in {} at {count} points: {differing:?}",
                        scalar.name()
                    );
                }
            }
        }
    }
}
