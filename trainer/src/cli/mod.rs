//! The command line: one module per command, each a thin layer over the library.

mod demo;
mod eval;
mod info;
mod output;
mod progress;
mod sample;
mod train;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Neural freeform surfaces: train on a desktop, evaluate on microcontrollers.
#[derive(Debug, Parser)]
#[command(name = "neurosurf", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Sample oriented control points from a built-in shape or a mesh file.
    Sample(sample::Args),
    /// Train a model from control points and write its blob.
    #[command(subcommand)]
    Train(train::Command),
    /// Evaluate a model at query points; CSV `x,y,z,phi,gx,gy,gz` on stdout.
    Eval(eval::Args),
    /// Describe a blob: kind, tree, parameters, size, training summary.
    Info(info::Args),
    /// The main job on built-in data: train a torus and a 3-feature head, write their blobs,
    /// and print their accuracy in f64, f32 and Q16.16.
    Demo(demo::Args),
}

/// Parses the arguments, runs the command, and turns an error into a message and exit code 1.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Sample(args) => sample::run(&args),
        Command::Train(command) => train::run(&command),
        Command::Eval(args) => eval::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Demo(args) => demo::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", describe(&error));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, each cause added only if the message so far does not already
/// say it (the library's errors often quote their source).
fn describe(error: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in error.chain() {
        let part = cause.to_string();
        if !text.contains(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
    }
    text
}
