//! Bad input, command by command, from one table: every command that reads a file is given a
//! missing file, an empty file, bytes that are not its format, and (where it reads numbers)
//! a NaN, a short line, and degenerate point sets (40 and 10⁶ copies of one point). Each must fail with exit code 1, an `error:` line that
//! names the file, no panic, and no output written (an existing output is kept).

mod common;

use std::fs;
use std::path::Path;

use common::neurosurf;

/// A command reading `{in}` and writing `{out}` (when it writes a file).
struct Command {
    args: &'static [&'static str],
    /// Whether it reads numbers as text (NaN and degenerate inputs apply).
    text_points: bool,
}

const COMMANDS: &[Command] = &[
    Command {
        args: &["sample", "{in}", "--points", "50", "--out", "{out}"],
        text_points: false,
    },
    Command {
        args: &["implicit", "fit", "--points", "{in}", "--out", "{out}"],
        text_points: false,
    },
    Command {
        args: &["implicit", "rbf", "--points", "{in}", "--out", "{out}"],
        text_points: false,
    },
    Command {
        args: &["caoen", "fit", "{in}", "--out", "{out}"],
        text_points: true,
    },
    Command {
        args: &[
            "caoen", "fit-mesh", "{in}", "--keys", "20", "--out", "{out}",
        ],
        text_points: false,
    },
    Command {
        args: &[
            "caoen", "image", "compress", "{in}", "--keys", "16", "--out", "{out}",
        ],
        text_points: false,
    },
    Command {
        args: &["curve", "fit", "{in}", "--out", "{out}"],
        text_points: true,
    },
    Command {
        args: &["curve", "surface", "{in}", "--out", "{out}"],
        text_points: true,
    },
    Command {
        args: &["parametric", "embed", "{in}", "--out", "{out}"],
        text_points: true,
    },
    Command {
        args: &["parametric", "fit", "{in}", "--out", "{out}"],
        text_points: true,
    },
    Command {
        args: &["info", "{in}"],
        text_points: false,
    },
    Command {
        args: &["mesh", "{in}", "--out", "{out}"],
        text_points: false,
    },
    Command {
        args: &["render", "{in}", "--out", "{out}"],
        text_points: false,
    },
    Command {
        args: &["compare", "{in}"],
        text_points: false,
    },
    Command {
        args: &["parametric", "tessellate", "{in}", "--out", "{out}"],
        text_points: false,
    },
];

/// Runs `command` with `{in}` and `{out}` replaced; returns the arguments and the output.
fn run_with(command: &Command, input: &Path, out: &Path) -> (Vec<String>, std::process::Output) {
    let args: Vec<String> = command
        .args
        .iter()
        .map(|a| {
            a.replace("{in}", input.to_str().unwrap())
                .replace("{out}", out.to_str().unwrap())
        })
        .collect();
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let output = neurosurf(&refs);
    (args, output)
}

/// Runs `command` on `input` and checks that it fails cleanly; `case` names the input.
fn refused(command: &Command, input: &Path, out: &Path, case: &str) {
    fs::write(out, b"precious").unwrap();
    let (args, output) = run_with(command, input, out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let what = format!("{case}: neurosurf {}", args.join(" "));
    assert_eq!(output.status.code(), Some(1), "{what} exit: {stderr}");
    assert!(stderr.starts_with("error: "), "{what}: {stderr}");
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    let name = input.file_name().unwrap().to_str().unwrap();
    assert!(
        stderr.contains(name),
        "{what} does not name {name}: {stderr}"
    );
    assert_eq!(
        fs::read(out).unwrap(),
        b"precious",
        "{what} touched its output"
    );
}

#[test]
fn every_command_refuses_bad_files_by_name_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.bin");
    for (index, command) in COMMANDS.iter().enumerate() {
        // The file extension some readers dispatch on.
        let ext = match command.args[0] {
            "sample" => "obj",
            "implicit" => "ply",
            "caoen" if command.args[1] == "fit-mesh" => "obj",
            "caoen" if command.args[1] == "image" => "png",
            "info" | "mesh" | "render" | "compare" => "nsb",
            "parametric" if command.args[1] == "tessellate" => "nsb",
            _ => "txt",
        };
        let missing = dir.path().join(format!("missing-{index}.{ext}"));
        refused(command, &missing, &out, "a missing file");
        let empty = dir.path().join(format!("empty-{index}.{ext}"));
        fs::write(&empty, b"").unwrap();
        refused(command, &empty, &out, "an empty file");
        let garbage = dir.path().join(format!("garbage-{index}.{ext}"));
        fs::write(&garbage, b"\x00\x01not this format\xff\xfe 1 2\n").unwrap();
        refused(command, &garbage, &out, "garbage");
        if command.text_points {
            let nan = dir.path().join(format!("nan-{index}.txt"));
            let mut text = String::new();
            for i in 0..40 {
                let t = f64::from(i) * 0.3;
                text.push_str(&format!("{} {} {}\n", t.cos(), t.sin(), 0.1 * t));
            }
            text.push_str("0.5 nan 0.1\n");
            fs::write(&nan, text).unwrap();
            refused(command, &nan, &out, "a NaN");
            let same = dir.path().join(format!("same-{index}.txt"));
            fs::write(&same, "0.5 0.5 0.5\n".repeat(40)).unwrap();
            refused(command, &same, &out, "forty copies of one point");
            let million = dir.path().join(format!("million-{index}.txt"));
            fs::write(&million, "0.5 0.5 0.5\n".repeat(1_000_000)).unwrap();
            refused(command, &million, &out, "a million copies of one point");
            let short = dir.path().join(format!("short-{index}.txt"));
            fs::write(&short, "1 2 3\n4 5\n6 7 8\n").unwrap();
            refused(command, &short, &out, "a short line");
            // Magnitudes of 1e30: a fit in f32 is what a user expects; anything else must
            // be a named error, never a panic.
            let huge = dir.path().join(format!("huge-{index}.txt"));
            let text: String = (0..60)
                .map(|i| {
                    let t = f64::from(i) * 0.1;
                    format!("{} {} {}\n", 1e30 * t.cos(), 1e30 * t.sin(), 1e29 * t)
                })
                .collect();
            fs::write(&huge, text).unwrap();
            let (args, output) = run_with(command, &huge, &out);
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert!(
                output.status.success() || stderr.starts_with("error: "),
                "1e30 coordinates: neurosurf {}: {stderr}",
                args.join(" ")
            );
            assert!(!stderr.contains("panicked"), "{stderr}");
        }
    }
}

/// Numeric options at 0, negative and 10⁹: each is refused by name (or by the argument parser
/// as not a number), without a panic and without writing.
#[test]
fn absurd_option_values_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let torus = dir.path().join("torus.ply");
    let ok = neurosurf(&[
        "sample",
        "torus",
        "--points",
        "96",
        "--out",
        torus.to_str().unwrap(),
    ]);
    assert!(ok.status.success());
    let model = dir.path().join("torus.nsb");
    let fitted = neurosurf(&[
        "implicit",
        "fit",
        "--points",
        torus.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(fitted.status.success());
    let ring = dir.path().join("ring.txt");
    let text: String = (0..200)
        .map(|i| {
            let t = f64::from(i) * 0.0314;
            format!("{} {}\n", t.cos(), t.sin())
        })
        .collect();
    fs::write(&ring, text).unwrap();
    let spot = format!("{}/../data/spot.obj", env!("CARGO_MANIFEST_DIR"));
    let out = dir.path().join("out.bin");
    let (torus, model, ring) = (
        torus.to_str().unwrap(),
        model.to_str().unwrap(),
        ring.to_str().unwrap(),
    );
    // (command with {v} for the value, the option named in the error)
    let table: &[(&[&str], &str)] = &[
        (
            &["sample", "torus", "--points", "{v}", "--out", "{out}"],
            "point",
        ),
        (
            &[
                "implicit",
                "fit",
                "--points",
                torus,
                "--features",
                "{v}",
                "--out",
                "{out}",
            ],
            "features",
        ),
        (
            &["mesh", model, "--resolution", "{v}", "--out", "{out}"],
            "resolution",
        ),
        (
            &["render", model, "--size", "{v},{v}", "--out", "{out}"],
            "size",
        ),
        (
            &[
                "caoen", "fit-mesh", &spot, "--keys", "{v}", "--out", "{out}",
            ],
            "key",
        ),
        (
            &["curve", "fit", ring, "--control", "{v}", "--out", "{out}"],
            "control",
        ),
        (
            &[
                "caoen", "image", "sample", "--size", "{v},{v}", "--out", "{out}",
            ],
            "size",
        ),
    ];
    for (args, named) in table {
        for value in ["0", "-1", "1000000000"] {
            fs::write(&out, b"precious").unwrap();
            let args: Vec<String> = args
                .iter()
                .map(|a| {
                    a.replace("{v}", value)
                        .replace("{out}", out.to_str().unwrap())
                })
                .collect();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let output = neurosurf(&args);
            let stderr = String::from_utf8_lossy(&output.stderr);
            let what = format!("neurosurf {}", args.join(" "));
            assert!(!output.status.success(), "{what} succeeded");
            assert!(!stderr.contains("panicked"), "{what}: {stderr}");
            assert!(stderr.starts_with("error"), "{what}: {stderr}");
            // A negative value is the parser's error (it names the argument); the others name
            // the option or the quantity it sets.
            if value != "-1" {
                assert!(
                    stderr.contains(named),
                    "{what} does not name {named}: {stderr}"
                );
            }
            assert_eq!(
                fs::read(&out).unwrap(),
                b"precious",
                "{what} touched its output"
            );
        }
    }
    // An output in a folder that does not exist.
    let nowhere = dir.path().join("missing folder").join("torus.obj");
    let output = neurosurf(&["mesh", model, "--out", nowhere.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success()
            && stderr.contains("missing folder")
            && stderr.contains("does not exist"),
        "{stderr}"
    );
    // Outputs that cannot be written: an existing folder, and a path under a file.
    let folder = dir.path().join("a folder");
    fs::create_dir(&folder).unwrap();
    for unwritable in [folder.clone(), out.join("torus.obj")] {
        let path = unwritable.to_str().unwrap();
        for command in [
            vec!["mesh", model, "--out", path],
            vec!["implicit", "fit", "--points", torus, "--out", path],
        ] {
            let output = neurosurf(&command);
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert!(
                !output.status.success()
                    && !stderr.contains("panicked")
                    && stderr.starts_with("error")
                    && stderr.contains(path),
                "{command:?}: {stderr}"
            );
        }
    }
    assert!(folder.is_dir());
    assert_eq!(fs::read(&out).unwrap(), b"precious");
}
