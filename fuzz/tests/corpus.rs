//! The fuzz harness over the committed corpus (`fuzz/corpus/`: blobs the trainer wrote, every
//! kind, f32 and Q16.16) and seeded mutations of it: every corpus blob loads as its kind, and
//! no mutation panics. The coverage-guided campaign runs the same harness (`fuzz/libfuzzer/`).

use neurosurf_core::blob::{self, ModelKind};
use std::collections::BTreeSet;

fn corpus() -> Vec<(String, Vec<u8>)> {
    neurosurf_fuzz::corpus("corpus")
}

#[test]
fn every_corpus_blob_loads_as_its_kind_in_both_scalars() {
    let mut kinds = BTreeSet::new();
    for (name, bytes) in corpus() {
        let (header, _) = blob::parse(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        kinds.insert(header.model.code());
        let verdict = neurosurf_fuzz::run(&bytes);
        assert!(verdict.framed, "{name}");
        // As it is and repaired (the same bytes), in f32 and Q16.16; the RBF baseline is
        // evaluated by the trainer only.
        let expected = if header.model == ModelKind::Rbf { 0 } else { 4 };
        assert_eq!(verdict.loaded, expected, "{name}");
    }
    let all: BTreeSet<u8> = (1..=6).collect();
    assert_eq!(kinds, all, "the corpus has a blob of every kind");
}

/// xorshift64*: seeded, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

#[test]
fn seeded_mutations_of_the_corpus_never_panic() {
    let corpus = corpus();
    let mut rng = Rng(0x6e65_7572_6f73_7572);
    let (mut framed, mut loaded) = (0, 0);
    let interesting: [u8; 8] = [0, 1, 0x7f, 0x80, 0xff, 0xfe, 9, 64];
    for i in 0..20_000 {
        let (_, original) = &corpus[i % corpus.len()];
        let mut bytes = original.clone();
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(bytes.len());
            match rng.below(6) {
                0 => bytes[at] ^= 1 << rng.below(8),
                1 => bytes[at] = interesting[rng.below(interesting.len())],
                2 => bytes[at] = rng.next() as u8,
                // Near the payload's start, where its shape is described.
                3 => {
                    let at = 12 + rng.below(24).min(bytes.len().saturating_sub(13));
                    bytes[at] = rng.next() as u8;
                }
                4 => {
                    let len = rng.below(bytes.len() - at);
                    bytes.drain(at..at + len.min(16));
                }
                _ => {
                    let (_, other) = &corpus[rng.below(corpus.len())];
                    let from = rng.below(other.len());
                    let len = rng.below(32).min(other.len() - from);
                    bytes.splice(at..at, other[from..from + len].iter().copied());
                }
            }
            if bytes.is_empty() {
                break;
            }
        }
        let verdict = neurosurf_fuzz::run(&bytes);
        framed += usize::from(verdict.framed);
        loaded += usize::from(verdict.loaded > 0);
    }
    println!("20 000 mutations: {framed} framed as they were, {loaded} loaded a model");
    // The repair lets mutations reach the model validation, and some pass it.
    assert!(loaded >= 1_000, "{loaded}");
}
