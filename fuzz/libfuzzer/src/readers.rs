//! libFuzzer's entry for the trainer's file readers: the first byte picks the reader, or
//! `NEUROSURF_FUZZ_READER=k` pins reader k (0 … 8, in the order of `neurosurf_fuzz::readers`)
//! so one reader gets every execution. Every 2¹⁸ executions the process prints how many each
//! reader had (a line `executions per reader: [...]` in the log), so a campaign can say how
//! its executions split between the readers.
#![no_main]

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use neurosurf_fuzz::readers::{READER_COUNT, read_with, reader_of};

static PER_READER: [AtomicU64; READER_COUNT] = [const { AtomicU64::new(0) }; READER_COUNT];
static TOTAL: AtomicU64 = AtomicU64::new(0);
static PINNED: OnceLock<Option<usize>> = OnceLock::new();

fn pinned() -> Option<usize> {
    *PINNED.get_or_init(|| {
        let value = std::env::var("NEUROSURF_FUZZ_READER").ok()?;
        let index: usize = value
            .parse()
            .ok()
            .filter(|&k| k < READER_COUNT)
            .unwrap_or_else(|| {
                panic!(
                    "NEUROSURF_FUZZ_READER={value}: give 0 to {}",
                    READER_COUNT - 1
                )
            });
        Some(index)
    })
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Some(chosen) = reader_of(data) else {
        return;
    };
    let index = pinned().unwrap_or(chosen);
    PER_READER[index].fetch_add(1, Ordering::Relaxed);
    if TOTAL.fetch_add(1, Ordering::Relaxed) % (1 << 18) == (1 << 18) - 1 {
        let counts: Vec<u64> = PER_READER
            .iter()
            .map(|c| c.load(Ordering::Relaxed))
            .collect();
        eprintln!("executions per reader: {counts:?}");
    }
    read_with(index, &data[1..]);
});
