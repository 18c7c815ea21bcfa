//! The subjects `sim-bench` measures, as committed in `subjects.json`: each one's name, its
//! blob in each scalar and its evaluation points (or parameters), exactly as the firmware
//! receives them.
//!
//! Stored rather than trained at every run because training is not bit-for-bit the same on
//! every machine (see [`super::built_in`]); the firmware's instruction counts and cycle
//! estimates are, for given blobs and points, so `docs/performance/target.md` can be checked
//! against a fresh run anywhere. `neurosurf sim-bench --retrain cli/src/sim_bench/subjects.json`
//! trains them again and rewrites the file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use neurosurf_core::blob::ModelKind;
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::Op;
use neurosurf_trainer::evaluate::LoadedModel;
use neurosurf_trainer::io::write_atomic;
use serde::{Deserialize, Serialize};

use super::Subject;

/// The committed subjects.
const SUBJECTS: &str = include_str!("subjects.json");

/// What `subjects.json` holds.
#[derive(Serialize, Deserialize)]
struct File {
    /// What the file is and how it is made.
    about: String,
    subjects: Vec<StoredSubject>,
}

#[derive(Serialize, Deserialize)]
struct StoredSubject {
    name: String,
    /// One blob per scalar, in the order measured.
    blobs: Vec<StoredBlob>,
    /// The points (or parameters) one after the other, as many coordinates each as the model
    /// takes.
    points: Vec<f32>,
}

#[derive(Serialize, Deserialize)]
struct StoredBlob {
    /// [`ScalarKind::name`].
    scalar: String,
    /// The blob's bytes in hexadecimal.
    hex: String,
}

const ABOUT: &str = "The models and points `neurosurf sim-bench` measures (docs/performance/\
                     target.md). Written by `neurosurf sim-bench --retrain cli/src/sim_bench/\
                     subjects.json`, which trains them with fixed seeds.";

/// The committed subjects, ready to measure.
pub(super) fn load() -> Result<Vec<Subject>> {
    parse(SUBJECTS).context("the built-in subjects (cli/src/sim_bench/subjects.json) are unusable")
}

/// Subjects from the text of a `subjects.json`.
fn parse(text: &str) -> Result<Vec<Subject>> {
    let file: File = serde_json::from_str(text)?;
    file.subjects.into_iter().map(subject).collect()
}

fn subject(stored: StoredSubject) -> Result<Subject> {
    let path = PathBuf::from(format!("<built-in {}>", stored.name));
    let mut blobs = Vec::new();
    for blob in &stored.blobs {
        let scalar = [ScalarKind::F32, ScalarKind::Q16_16]
            .into_iter()
            .find(|k| k.name() == blob.scalar)
            .with_context(|| format!("{}: unknown scalar {:?}", stored.name, blob.scalar))?;
        let bytes = hex::decode(&blob.hex).with_context(|| {
            format!(
                "{}: the {} blob is not hexadecimal",
                stored.name,
                scalar.name()
            )
        })?;
        blobs.push((scalar, bytes));
    }
    // Every blob is read once: a subject the core refuses fails here, by name.
    let mut shape = None;
    for (_, bytes) in &blobs {
        let model = LoadedModel::from_bytes(bytes.clone(), &path)?;
        shape.get_or_insert((model.kind(), model.query_arity()));
    }
    let Some((kind, arity)) = shape else {
        bail!("{}: no blob", stored.name);
    };
    if stored.points.is_empty() || !stored.points.len().is_multiple_of(arity) {
        bail!(
            "{}: {} coordinates are not whole points of {arity}",
            stored.name,
            stored.points.len()
        );
    }
    let ops = match kind {
        ModelKind::Implicit => [Op::Field, Op::FieldGradient],
        _ => [Op::Position, Op::PositionDirection],
    };
    Ok(Subject {
        name: stored.name,
        path,
        blobs,
        points: stored.points,
        arity,
        ops,
    })
}

/// Writes `subjects` as a `subjects.json` to `path`.
pub(super) fn write(subjects: &[Subject], path: &Path) -> Result<()> {
    let file = File {
        about: ABOUT.into(),
        subjects: subjects
            .iter()
            .map(|s| StoredSubject {
                name: s.name.clone(),
                blobs: s
                    .blobs
                    .iter()
                    .map(|(scalar, bytes)| StoredBlob {
                        scalar: scalar.name().into(),
                        hex: hex::encode(bytes),
                    })
                    .collect(),
                points: s.points.clone(),
            })
            .collect(),
    };
    let mut text = serde_json::to_string_pretty(&file)?;
    text.push('\n');
    // What is written is what `load` will read.
    parse(&text).context("the trained subjects do not read back")?;
    Ok(write_atomic(path, text.as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_committed_subjects_load() {
        let subjects = load().unwrap();
        assert!(subjects.iter().any(|s| s.ops[0] == Op::Field));
        assert!(subjects.iter().any(|s| s.ops[0] == Op::Position));
        for s in &subjects {
            assert!(s.points.len().is_multiple_of(s.arity), "{}", s.name);
            assert_eq!(s.blobs.len(), 2, "{}", s.name);
        }
    }

    #[test]
    fn a_corrupt_subject_is_refused_by_name() {
        let text = r#"{"about": "", "subjects": [{"name": "broken", "blobs": [{"scalar": "f32", "hex": "00ff"}], "points": [0, 0, 0]}]}"#;
        let error = format!("{:#}", parse(text).unwrap_err());
        assert!(error.contains("broken"), "{error}");
        let text = r#"{"about": "", "subjects": [{"name": "odd", "blobs": [{"scalar": "f64", "hex": ""}], "points": []}]}"#;
        let error = format!("{:#}", parse(text).unwrap_err());
        assert!(error.contains("unknown scalar"), "{error}");
    }
}
