//! Bad input, command by command, from one table: every command that reads a file is given a
//! missing file, an empty file and bytes that are not its format; every command that reads
//! points (text, PLY or OBJ) is also given a NaN, an infinity, a short line, one point, and
//! degenerate point sets (40 and 10⁶ copies of one point), each written in its own format.
//! Each must fail with exit code 1, an `error:` line that names the file, no panic, and no
//! output written (an existing output is kept). Magnitudes of 10³⁰ and a one-pixel image
//! must either work or fail that way.

mod common;

use std::fs;
use std::path::Path;

use common::neurosurf;

/// What a command reads.
#[derive(Clone, Copy, PartialEq)]
enum Reads {
    /// Points as text: `x y z` (or `x y`) per line.
    Text,
    /// Oriented points in a PLY file.
    Ply,
    /// A mesh in an OBJ file.
    Obj,
    /// A PNG image.
    Png,
    /// A model blob.
    Blob,
}

impl Reads {
    fn extension(self) -> &'static str {
        match self {
            Reads::Text => "txt",
            Reads::Ply => "ply",
            Reads::Obj => "obj",
            Reads::Png => "png",
            Reads::Blob => "nsb",
        }
    }

    /// A file of this format holding `rows`, each the text of one point's coordinates (a row
    /// may be malformed on purpose). PLY rows get a normal; OBJ rows are vertices, joined three
    /// by three into faces.
    fn points_file(self, rows: &[String]) -> Vec<u8> {
        let mut text = String::new();
        match self {
            Reads::Text => {
                for row in rows {
                    text.push_str(row);
                    text.push('\n');
                }
            }
            Reads::Ply => {
                text.push_str("ply\nformat ascii 1.0\n");
                text.push_str(&format!("element vertex {}\n", rows.len()));
                for p in ["x", "y", "z", "nx", "ny", "nz"] {
                    text.push_str(&format!("property float {p}\n"));
                }
                text.push_str("end_header\n");
                for row in rows {
                    text.push_str(&format!("{row} 0 0 1\n"));
                }
            }
            Reads::Obj => {
                for row in rows {
                    text.push_str(&format!("v {row}\n"));
                }
                for f in 0..rows.len() / 3 {
                    text.push_str(&format!("f {} {} {}\n", 3 * f + 1, 3 * f + 2, 3 * f + 3));
                }
            }
            Reads::Png | Reads::Blob => unreachable!("not a point format"),
        }
        text.into_bytes()
    }
}

/// A command reading `{in}` and writing `{out}` (when it writes a file).
struct Command {
    args: &'static [&'static str],
    reads: Reads,
}

const COMMANDS: &[Command] = &[
    Command {
        args: &["sample", "{in}", "--points", "50", "--out", "{out}"],
        reads: Reads::Obj,
    },
    Command {
        args: &["implicit", "fit", "--points", "{in}", "--out", "{out}"],
        reads: Reads::Ply,
    },
    Command {
        args: &["implicit", "rbf", "--points", "{in}", "--out", "{out}"],
        reads: Reads::Ply,
    },
    Command {
        args: &["caoen", "fit", "{in}", "--out", "{out}"],
        reads: Reads::Text,
    },
    Command {
        args: &[
            "caoen", "fit-mesh", "{in}", "--keys", "20", "--out", "{out}",
        ],
        reads: Reads::Obj,
    },
    Command {
        args: &[
            "caoen", "image", "compress", "{in}", "--bytes", "400", "--out", "{out}",
        ],
        reads: Reads::Png,
    },
    Command {
        args: &["curve", "fit", "{in}", "--out", "{out}"],
        reads: Reads::Text,
    },
    Command {
        args: &["curve", "surface", "{in}", "--out", "{out}"],
        reads: Reads::Text,
    },
    Command {
        args: &["parametric", "embed", "{in}", "--out", "{out}"],
        reads: Reads::Text,
    },
    Command {
        args: &["parametric", "fit", "{in}", "--out", "{out}"],
        reads: Reads::Text,
    },
    Command {
        args: &["parametric", "compare", "{in}"],
        reads: Reads::Text,
    },
    Command {
        args: &["info", "{in}"],
        reads: Reads::Blob,
    },
    Command {
        args: &["mesh", "{in}", "--out", "{out}"],
        reads: Reads::Blob,
    },
    Command {
        args: &["render", "{in}", "--out", "{out}"],
        reads: Reads::Blob,
    },
    Command {
        args: &["compare", "{in}"],
        reads: Reads::Blob,
    },
    Command {
        args: &["parametric", "tessellate", "{in}", "--out", "{out}"],
        reads: Reads::Blob,
    },
    Command {
        args: &["caoen", "normals", "{in}", "--out", "{out}"],
        reads: Reads::Blob,
    },
    Command {
        args: &[
            "caoen",
            "perspective",
            "{in}",
            "--eye",
            "0,0,5",
            "--out",
            "{out}",
        ],
        reads: Reads::Blob,
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

/// Runs `command` on `input` and checks that it fails cleanly; `case` names the input. Returns
/// what is wrong, if anything.
fn refused(command: &Command, input: &Path, out: &Path, case: &str) -> Option<String> {
    fs::write(out, b"precious").unwrap();
    let (args, output) = run_with(command, input, out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let what = format!("{case}: neurosurf {}", args.join(" "));
    let name = input.file_name().unwrap().to_str().unwrap();
    if output.status.code() != Some(1) {
        Some(format!(
            "{what} exits with {:?}: {stderr}",
            output.status.code()
        ))
    } else if !stderr.starts_with("error: ") || stderr.contains("panicked") {
        Some(format!("{what}: {stderr}"))
    } else if !stderr.contains(name) {
        Some(format!("{what} does not name {name}: {stderr}"))
    } else if fs::read(out).unwrap() != b"precious" {
        Some(format!("{what} touched its output"))
    } else {
        None
    }
}

/// Runs `command` on `input`, which a user may expect to work: it either works or fails
/// cleanly with a named error, never a panic. Returns what is wrong, if anything.
fn works_or_refused(command: &Command, input: &Path, out: &Path, case: &str) -> Option<String> {
    let (args, output) = run_with(command, input, out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let what = format!("{case}: neurosurf {}", args.join(" "));
    let clean = output.status.success() || stderr.starts_with("error: ");
    (!clean || stderr.contains("panicked")).then(|| format!("{what}: {stderr}"))
}

/// Forty points on a helix, the well-formed part of the number cases.
fn helix() -> Vec<String> {
    (0..40)
        .map(|i| {
            let t = f64::from(i) * 0.3;
            format!("{} {} {}", t.cos(), t.sin(), 0.1 * t)
        })
        .collect()
}

#[test]
fn every_command_refuses_bad_files_by_name_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.bin");
    let mut wrong: Vec<String> = Vec::new();
    for (index, command) in COMMANDS.iter().enumerate() {
        let ext = command.reads.extension();
        let file = |case: &str, bytes: &[u8]| {
            let path = dir.path().join(format!("{case}-{index}.{ext}"));
            fs::write(&path, bytes).unwrap();
            path
        };
        let missing = dir.path().join(format!("missing-{index}.{ext}"));
        wrong.extend(refused(command, &missing, &out, "a missing file"));
        wrong.extend(refused(command, &file("empty", b""), &out, "an empty file"));
        let garbage = file("garbage", b"\x00\x01not this format\xff\xfe 1 2\n");
        wrong.extend(refused(command, &garbage, &out, "garbage"));
        match command.reads {
            Reads::Text | Reads::Ply | Reads::Obj => {}
            Reads::Png => {
                let pixel = image::RgbImage::from_pixel(1, 1, image::Rgb([200, 100, 50]));
                let path = dir.path().join(format!("pixel-{index}.png"));
                pixel.save(&path).unwrap();
                wrong.extend(works_or_refused(command, &path, &out, "a one-pixel image"));
                continue;
            }
            Reads::Blob => continue,
        }
        let points = |case: &str, rows: &[String]| file(case, &command.reads.points_file(rows));
        let one = "0.5 0.5 0.5".to_string();
        for (case, bad) in [
            ("a NaN", "0.5 nan 0.1"),
            ("an infinity", "0.5 0.2 inf"),
            ("a short line", "4 5"),
        ] {
            let mut rows = helix();
            rows.insert(20, bad.to_string());
            let name = case.replace(' ', "-");
            wrong.extend(refused(command, &points(&name, &rows), &out, case));
        }
        wrong.extend(refused(
            command,
            &points("one", std::slice::from_ref(&one)),
            &out,
            "one point",
        ));
        let same = points("same", &vec![one.clone(); 40]);
        wrong.extend(refused(command, &same, &out, "forty copies of one point"));
        let million = points("million", &vec![one; 1_000_000]);
        wrong.extend(refused(
            command,
            &million,
            &out,
            "a million copies of one point",
        ));
        // Magnitudes of 1e30: a fit in f32 is what a user expects; anything else must be a
        // named error, never a panic.
        let huge: Vec<String> = (0..60)
            .map(|i| {
                let t = f64::from(i) * 0.1;
                format!("{} {} {}", 1e30 * t.cos(), 1e30 * t.sin(), 1e29 * t)
            })
            .collect();
        wrong.extend(works_or_refused(
            command,
            &points("huge", &huge),
            &out,
            "1e30 coordinates",
        ));
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
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
            &["patch", "compare", &spot, "--held-out", "{v}"],
            "held-out",
        ),
        (
            &["patch", "compare", &spot, "--resolution", "{v}"],
            "resolution",
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
