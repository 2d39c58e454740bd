//! `naadf`: the command-line interface of the naadf voxel world service.
//!
//! This file declares the subcommands; each one lives in `commands/`.

mod commands;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Streaming voxel worlds built on nested axis-aligned distance fields.
#[derive(Parser)]
#[command(name = "naadf", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build a world file from a MagicaVoxel .vox scene.
    Import(commands::import::Args),
    /// Generate a procedural world.
    Generate(commands::generate::Args),
    /// Print a world's size, content and memory statistics.
    Info(commands::info::Args),
    /// Export a world as raw voxels.
    Export(commands::export::Args),
    /// Apply ops (JSON lines) to a world offline, through the server's code path.
    Apply(commands::apply::Args),
    /// Trace rays read as JSON lines from standard input.
    Raycast(commands::raycast::Args),
    /// Benchmarks.
    #[command(subcommand)]
    Bench(commands::bench::Bench),
}

fn main() -> ExitCode {
    commands::init_logging();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Import(a) => commands::import::run(a),
        Command::Generate(a) => commands::generate::run(a),
        Command::Info(a) => commands::info::run(a),
        Command::Export(a) => commands::export::run(a),
        Command::Raycast(a) => commands::raycast::run(a),
        Command::Apply(a) => commands::apply::run(a),
        Command::Bench(b) => commands::bench::run(b),
    };
    commands::finish(result)
}
