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

/// The value after `name` parsed, or `default` when not given; a value that does not parse
/// stops the bench naming `name` and what it should be.
#[allow(dead_code)] // Not every bench takes a value.
pub fn parsed<T: std::str::FromStr>(args: &[String], name: &str, default: &str, what: &str) -> T {
    option(args, name)
        .unwrap_or(default)
        .parse()
        .unwrap_or_else(|_| panic!("{name}: {what}"))
}
