//! libFuzzer's entry for the trainer's file readers: the first byte picks the reader.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    neurosurf_fuzz::readers::read(data);
});
