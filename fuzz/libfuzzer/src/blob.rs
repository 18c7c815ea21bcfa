//! libFuzzer's entry: every input goes through the one harness of every model kind.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    neurosurf_fuzz::run(data);
});
