//! `naadf`: the command-line interface of the naadf voxel world service.
//!
//! This file declares the subcommands; each one lives in `commands/`.

mod commands;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// Streaming voxel worlds built on nested axis-aligned distance fields.
#[derive(Parser)]
#[command(name = "naadf", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The subcommands, in the order `naadf --help` lists them: by use (see [`GROUPS`]).
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
    /// Serve a world: gRPC streaming and edits, durable in a data directory.
    Serve(commands::serve::Args),
    /// Mirror a server (or another relay) and serve its world to clients of your own,
    /// forwarding their edits upstream.
    Relay(commands::relay::Args),
    /// Join a server and mirror its world, checking every digest.
    Mirror(commands::mirror::Args),
    /// Send ops (JSON lines) to a server; prints the acknowledged versions.
    Edit(commands::edit::Args),
    /// Print a server's version, digest and clients.
    Status(commands::status::Args),
    /// Write the batches a server logged after its newest snapshot as an ops script.
    ExportLog(commands::export_log::Args),
    /// Check or repair a server's data directory (snapshots and write-ahead log).
    #[command(subcommand)]
    Data(commands::data::Data),
    /// Render a frame of a world file or a server's world on the GPU (or lavapipe).
    #[cfg(feature = "gpu")]
    Render(commands::render::Args),
    /// Serve frames for a server as a headless render node.
    #[cfg(feature = "gpu")]
    RenderNode(commands::render_node::Args),
    /// Ask a server for a frame from its render nodes.
    Frame(commands::frame::Args),
    /// Open a window on a server's world: fly through it and edit it live.
    #[cfg(feature = "gpu")]
    View(commands::view::Args),
    /// Run a replay script (or a HashDAG CSV) against a world file or a server.
    #[cfg(feature = "gpu")]
    Replay(commands::replay::Args),
    /// Record a live server's edit batches, with their users, as a replay script.
    Record(commands::record::Args),
    /// Benchmarks.
    #[cfg(feature = "gpu")]
    #[command(subcommand)]
    Bench(commands::bench::Bench),
}

/// How `naadf --help` groups the subcommands: a heading and the commands under it.
/// `every_command_is_in_one_group` keeps it complete.
const GROUPS: &[(&str, &[&str])] = &[
    (
        "World files",
        &["import", "generate", "info", "export", "apply", "raycast"],
    ),
    (
        "Service",
        &["serve", "relay", "mirror", "edit", "status", "export-log", "data"],
    ),
    ("Rendering", &["render", "render-node", "frame", "view"]),
    ("Replay", &["replay", "record"]),
    ("Benchmarks", &["bench"]),
];

#[cfg(feature = "gpu")]
impl Command {
    /// Whether the command may open a GPU device (headless or in a window).
    fn uses_gpu(&self) -> bool {
        use commands::bench::Bench;
        matches!(
            self,
            Command::Render(_)
                | Command::RenderNode(_)
                | Command::View(_)
                | Command::Replay(_)
                | Command::Bench(Bench::Gpu(_) | Bench::Frames(_))
        )
    }
}

/// The command line, with the subcommands listed under the headings of [`GROUPS`] instead of
/// clap's one flat list; each line's text is the subcommand's own `about`.
fn command_line() -> clap::Command {
    let cmd = Cli::command();
    let width = cmd.get_subcommands().map(|c| c.get_name().len()).max().unwrap_or(0);
    let mut listing = String::new();
    for (heading, names) in GROUPS {
        listing.push_str(&format!("{heading}:\n"));
        // A command built without the `gpu` feature is left out.
        for name in names.iter().filter(|n| cmd.find_subcommand(n).is_some()) {
            let about = cmd
                .find_subcommand(name)
                .and_then(|c| c.get_about())
                .map(ToString::to_string)
                .unwrap_or_default();
            listing.push_str(&format!("  {name:width$}  {about}\n"));
        }
        listing.push('\n');
    }
    cmd.help_template(format!(
        "{{about-with-newline}}\n{{usage-heading}} {{usage}}\n\n{listing}Options:\n{{options}}{{after-help}}"
    ))
    .after_help("`naadf help COMMAND` or `naadf COMMAND --help` shows a command's options.")
}

fn main() -> ExitCode {
    let cli = match Cli::from_arg_matches(&command_line().get_matches()) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    #[cfg(feature = "gpu")]
    let _runtime_dir = cli.command.uses_gpu().then(commands::quiet_headless_gpu).flatten();
    // Long-running network commands report what they do; one-shot tools stay quiet.
    commands::init_logging(match cli.command {
        Command::Serve(_) | Command::Relay(_) | Command::Mirror(_) => "info",
        _ => "warn",
    });
    let result = match cli.command {
        Command::Import(a) => commands::import::run(a),
        Command::Generate(a) => commands::generate::run(a),
        Command::Info(a) => commands::info::run(a),
        Command::Export(a) => commands::export::run(a),
        Command::Raycast(a) => commands::raycast::run(a),
        Command::Apply(a) => commands::apply::run(a),
        Command::Serve(a) => commands::serve::run(a),
        Command::Relay(a) => commands::relay::run(a),
        Command::Mirror(a) => commands::mirror::run(a),
        Command::Edit(a) => commands::edit::run(a),
        Command::Status(a) => commands::status::run(a),
        Command::ExportLog(a) => commands::export_log::run(a),
        Command::Data(d) => commands::data::run(d),
        #[cfg(feature = "gpu")]
        Command::Render(a) => commands::render::run(a),
        #[cfg(feature = "gpu")]
        Command::View(a) => commands::view::run(a),
        #[cfg(feature = "gpu")]
        Command::RenderNode(a) => commands::render_node::run(a),
        Command::Frame(a) => commands::frame::run(a),
        #[cfg(feature = "gpu")]
        Command::Replay(a) => commands::replay::run(a),
        Command::Record(a) => commands::record::run(a),
        #[cfg(feature = "gpu")]
        Command::Bench(b) => commands::bench::run(b),
    };
    commands::finish(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every subcommand appears under exactly one heading of `naadf --help`, and every name
    /// there is a subcommand.
    #[test]
    fn every_command_is_in_one_group() {
        let cmd = Cli::command();
        let mut listed: Vec<&str> = GROUPS.iter().flat_map(|(_, names)| names.iter().copied()).collect();
        listed.sort_unstable();
        let mut real: Vec<&str> = cmd.get_subcommands().map(|c| c.get_name()).collect();
        real.sort_unstable();
        assert_eq!(listed, real);
    }

    #[test]
    fn command_line_is_valid() {
        command_line().debug_assert();
    }
}
