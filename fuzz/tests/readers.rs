//! The readers harness over its committed corpus (`fuzz/corpus-readers/`: one valid file per
//! reader, its first byte picking the reader) and seeded mutations of it: every seed reads,
//! and every mutation reads or fails with an error that names the file.

use neurosurf_fuzz::readers::{READER_COUNT, read};

fn corpus() -> Vec<(String, Vec<u8>)> {
    neurosurf_fuzz::corpus("corpus-readers")
}

#[test]
fn every_seed_reads_and_every_reader_has_one() {
    let mut readers = vec![false; READER_COUNT];
    for (name, bytes) in corpus() {
        readers[usize::from(bytes[0]) % READER_COUNT] = true;
        assert_eq!(read(&bytes), None, "{name}");
    }
    assert!(readers.iter().all(|&r| r), "{readers:?}");
}

#[test]
fn seeded_mutations_read_or_name_the_file() {
    let corpus = corpus();
    let mut state: u64 = 0x7265_6164_6572_7321;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let tokens: [&[u8]; 8] = [
        b"nan",
        b"-inf",
        b"1e309",
        b"\n",
        b" ",
        b",",
        b"4294967295",
        b"-1",
    ];
    let mut failed = 0;
    let rounds = 4_000;
    for i in 0..rounds {
        let (_, original) = &corpus[i % corpus.len()];
        let mut bytes = original.clone();
        for _ in 0..1 + next() % 4 {
            let at = 1 + (next() as usize) % (bytes.len() - 1).max(1);
            let at = at.min(bytes.len());
            match next() % 4 {
                0 if at < bytes.len() => bytes[at] = next() as u8,
                1 => {
                    let token = tokens[(next() as usize) % tokens.len()];
                    bytes.splice(at..at, token.iter().copied());
                }
                2 => {
                    let end = (at + (next() as usize) % 16).min(bytes.len());
                    bytes.drain(at..end);
                }
                _ => bytes.truncate(at),
            }
        }
        failed += usize::from(read(&bytes).is_some());
    }
    println!("{rounds} mutations: {failed} refused with a named error");
    assert!(failed > rounds / 10, "{failed}");
}

/// Inputs a pinned campaign once hung on (`fuzz/regressions-readers/`, the first byte picking
/// the reader as in the campaign), each kept with its fix: every one reads or names the file.
#[test]
fn every_found_hang_stays_fixed() {
    let inputs = neurosurf_fuzz::corpus("regressions-readers");
    assert!(!inputs.is_empty());
    for (name, bytes) in inputs {
        // Reads, or fails with an error that names the file (`read` checks), promptly.
        eprintln!("{name}");
        let _ = read(&bytes);
    }
}
