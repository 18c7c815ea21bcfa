//! Inputs the coverage-guided campaign once crashed on (`fuzz/regressions/`), each kept with
//! the fix that closed it: the harness must pass every one.

#[test]
fn every_found_crash_stays_fixed() {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    let mut count = 0;
    for entry in std::fs::read_dir(&folder).expect("fuzz/regressions") {
        let path = entry.expect("entry").path();
        let bytes = std::fs::read(&path).expect("read");
        // A panic fails the test and names nothing; the file name says which crash it was.
        eprintln!("{}", path.display());
        let _ = neurosurf_fuzz::run(&bytes);
        count += 1;
    }
    assert!(count > 0, "no regression inputs in {}", folder.display());
}
