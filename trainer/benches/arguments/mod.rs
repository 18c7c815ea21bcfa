//! Command-line helpers the table-writing benches share.

/// The value after `name` in `args`, if given.
pub fn option<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

/// The arguments as given after `--`, to name the command that wrote a table.
pub fn given(args: &[String]) -> String {
    args.iter()
        .skip(1)
        .filter(|a| *a != "--bench")
        .cloned()
        .collect::<Vec<_>>()
        .join(" ")
}

/// `path` relative to the workspace root (cargo runs benches in the package's folder).
pub fn in_workspace(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}
